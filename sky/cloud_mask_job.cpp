#include "sky/cloud_mask_job.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "sky/photo_import.h"
#include "sky/preset_import.h"
#include "sky/sky_image.h"
#include "util/atomic_file.h"
#include "util/error.h"
#include "util/image.h"

namespace dynsky {

namespace {

// Without its mask file, a preset's own obstruction geometry in the photo's grid (as import uses it):
// fixed rectangles, the shadow band at the sun's azimuth for the file name's time, the horizon profile.
std::vector<unsigned char> preset_geometry_not_sky(const std::string& preset, const std::string& photo,
                                                   const SkyCircle& circle, int width, int height) {
    const PresetImportPlan plan = plan_preset_import(preset, photo, 64);
    const PhotoImportParams& p = plan.params;
    PhotoGeometry g;
    g.circle = circle;
    g.lens = p.lens, g.north_deg = p.north_deg, g.mirrored = p.mirrored;
    g.tilt_deg = p.tilt_deg, g.tilt_azimuth_deg = p.tilt_azimuth_deg;
    std::vector<unsigned char> out = horizon_obstruction_mask(p.horizon_obstructions, circle, width, height);
    if (p.shadow_band) {
        const auto band = shadow_band_mask(*p.shadow_band, g, width, height);
        for (size_t k = 0; k < out.size(); ++k) out[k] |= band[k];
    }
    for (const auto& r : p.not_sky_rects)
        for (int y = std::max(0, r[1]); y < std::min(height, r[1] + r[3]); ++y)
            for (int x = std::max(0, r[0]); x < std::min(width, r[0] + r[2]); ++x) out[size_t(y) * width + x] = 1;
    return out;
}

}  // namespace

void run_cloud_mask(const CloudMaskJob& o) {
    check_extension("--out", o.out, ".png");
    check_outputs_are_not_inputs({o.out}, {o.input, o.mask});
    const CloudMaskParams& mp = o.params;
    if (!std::isfinite(mp.threshold)) throw Error("--cloud-threshold must be a finite number");
    Image encoded, mask;
    std::vector<unsigned char> sky;
    if (file_extension(o.input) == ".exr") {
        // A canonical sky (linear radiance): encoded as a camera would, inside the disc.
        SkyImage s = load_sky(o.input);
        encoded = encode_sky_for_mask(s);
        sky.assign(size_t(s.resolution) * s.resolution, 0);
        for (int j = 0; j < s.resolution; ++j)
            for (int i = 0; i < s.resolution; ++i) sky[size_t(j) * s.resolution + i] = s.in_disc(i, j);
    } else {
        Image photo = read_image(o.input);
        apply_orientation(photo);  // as `sky import` turns it
        if (photo.channels < 3) throw_file_error(o.input, "the cloud rule needs an RGB photograph");
        for (float v : photo.pixels)
            if (!std::isfinite(v)) throw_file_error(o.input, "has NaN or infinite pixels");
        encoded = photo;
        sky.assign(size_t(photo.width) * photo.height, 1);
        if (!o.whole_image) {
            SkyCircle c;
            PhotoImportParams pp;
            if (!o.preset.empty()) pp = camera_preset(o.preset).params;
            if (!o.circle) check_photo_fits(photo, o.input, pp);  // as `sky import` refuses it
            if (o.circle) c = *o.circle;
            else if (pp.circle) c = *pp.circle;
            else c = find_sky_circle(photo, o.input, pp.min_radius_fraction, pp.max_radius_fraction);
            std::string mask_path = o.mask.empty() && !o.preset.empty() ? find_preset_mask(o.preset, o.input) : o.mask;
            std::vector<unsigned char> not_sky;
            if (!mask_path.empty())
                not_sky = load_not_sky_mask(mask_path, o.mask.empty() ? pp.mask_layout : MaskLayout::PhotoBlackIsNotSky,
                                            photo.width, photo.height);
            else if (!o.preset.empty())
                not_sky = preset_geometry_not_sky(o.preset, o.input, c, photo.width, photo.height);
            for (int y = 0; y < photo.height; ++y)
                for (int x = 0; x < photo.width; ++x) {
                    double dx = x - c.center_x, dy = y - c.center_y;
                    size_t p = size_t(y) * photo.width + x;
                    sky[p] = dx * dx + dy * dy <= c.radius * c.radius && (not_sky.empty() || !not_sky[p]);
                }
        }
    }
    // A circle given off the photograph holds none of it: said so (it read as a black photograph).
    if (std::find(sky.begin(), sky.end(), 1) == sky.end())
        throw_file_error(o.input, "the sky circle holds none of the photograph's " + std::to_string(encoded.width) +
                                      " x " + std::to_string(encoded.height) + " pixels: check --center and --radius");
    // A black photograph has no colour to judge (0 / 0 in the rule called half of it cloud).
    bool lit = false;
    for (size_t p = 0; p < sky.size() && !lit; ++p)
        if (sky[p])
            for (int c = 0; c < 3 && !lit; ++c) lit = encoded.pixels[p * size_t(encoded.channels) + size_t(c)] > 0;
    if (!lit) throw_file_error(o.input, "the sky it shows is black everywhere: no cloud to find");
    mask = cloud_mask(encoded, mp, &sky);
    long long cloud = 0, total = 0;
    for (size_t p = 0; p < sky.size(); ++p)
        if (sky[p]) {
            ++total;
            cloud += mask.pixels[p] > 0.5f;
        }
    write_image(o.out, mask);
    std::printf(
        "wrote %s (255 cloud, 100 clear, 0 not sky); rule %s %s %.3f; cloud fraction %.1f%% of %lld sky pixels\n",
        o.out.c_str(), cloud_rule_name(mp.rule), mp.rule == CloudRule::RedBlueRatio ? "r/b >" : "(b-r)/(b+r) <",
        mp.threshold, total ? 100.0 * cloud / total : 0.0, total);
}

}  // namespace dynsky
