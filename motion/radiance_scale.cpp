#include "motion/radiance_scale.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <vector>

#include "motion/sun_patch.h"
#include "sky/clear_sky.h"
#include "sky/cloud_mask.h"
#include "sky/fisheye.h"
#include "util/error.h"

namespace dynsky {

std::string RadianceScale::describe() const {
    if (!measured) return "not measured (no sun above the horizon to compare with)";
    char text[160];
    std::snprintf(text, sizeof text, "%.3g x the clear-sky model's radiance (%s)", factor,
                  clear_weight >= 1   ? "its clear pixels"
                  : clear_weight <= 0 ? "its mean: too few clear pixels"
                                      : "its clear pixels and its mean");
    return text;
}

RadianceScale measure_radiance_scale(const SkyImage& sky, const RadianceScaleParams& params) {
    RadianceScale out;
    const HdrCalibrationParams& cal = params.calibration;
    std::optional<Vec3d> sun;
    if (sky.sun_direction) sun = sky.sun_direction->cast<double>();
    else sun = sun_from_brightest_pixels(sky);
    if (!sun || !(sun->y() > 0.02)) return out;

    ClearSkyParams p;
    p.sun_direction = sun->normalized();
    p.turbidity = cal.turbidity;
    p.ground_albedo = cal.ground_albedo;
    p.sun_disc = false;
    const ClearSkyModel model(p, false);
    const Image encoded = encode_sky_for_mask(sky);  // exposure-free: the rule sees colour, not scale
    const double deg = kPiD / 180;
    const double cos_sun = std::cos(cal.exclude_sun_deg * deg), cos_zenith = std::cos(cal.max_zenith_deg * deg);
    const int n = sky.resolution, stride = std::max(1, n / 128);  // about 13,000 pixels at any size
    std::vector<double> clear_ratios;
    double sum_sky = 0, sum_model = 0;
    long compared = 0;
    for (int j = stride / 2; j < n; j += stride)
        for (int i = stride / 2; i < n; i += stride) {
            if (!sky.in_disc(i, j)) continue;
            const Vec2 uv = fisheye::pixel_center_uv(i, j, n);
            const Vec3d w = fisheye::direction_from_uv(double(uv.x()), double(uv.y()));
            if (w.y() < cos_zenith || w.dot(p.sun_direction) > cos_sun) continue;
            const double y_sky = luminance(sky.pixel(i, j)), y_model = luminance(model.sky_radiance(w));
            if (!(y_model > 0) || !std::isfinite(y_sky)) continue;
            ++compared;
            sum_sky += y_sky, sum_model += y_model;
            const float r = encoded.at(i, j, 0), g = encoded.at(i, j, 1), b = encoded.at(i, j, 2);
            const bool clipped = std::min({r, g, b}) >= 0.98f;
            if (!clipped && y_sky > 0 && !is_cloud(r, g, b, cal.clear_rule)) clear_ratios.push_back(y_sky / y_model);
        }
    if (compared == 0 || !(sum_sky > 0) || !(sum_model > 0)) return out;
    out.measured = true;
    out.clear_fraction = double(clear_ratios.size()) / double(compared);
    out.clear_weight = clear_ratios.size() >= 20
                           ? trust_ramp(out.clear_fraction, cal.min_clear_fraction, cal.full_clear_fraction)
                           : 0.0;
    double log_factor = (1 - out.clear_weight) * std::log(sum_sky / sum_model);
    if (out.clear_weight > 0) {
        auto mid = clear_ratios.begin() + std::ptrdiff_t(clear_ratios.size() / 2);
        std::nth_element(clear_ratios.begin(), mid, clear_ratios.end());
        log_factor += out.clear_weight * std::log(*mid);
    }
    out.factor = std::exp(log_factor);
    if (!(out.factor > 0 && std::isfinite(out.factor))) return RadianceScale{};
    out.apply = out.factor > params.band || out.factor < 1 / params.band;
    return out;
}

void scale_radiance(SkyImage* sky, double factor) {
    const float f = float(factor);
    for (float& v : sky->rgb) v *= f;
}

RadianceScale bring_to_model_scale(SkyImage* sky, std::shared_ptr<const SkyImage>* previous,
                                   const std::optional<Vec3d>& sun_if_unrecorded) {
    RadianceScale scale;
    if (!sky->sun_direction && sun_if_unrecorded) {
        SkyImage with_sun = *sky;
        with_sun.sun_direction = sun_if_unrecorded->cast<float>();
        scale = measure_radiance_scale(with_sun);
    } else {
        scale = measure_radiance_scale(*sky);
    }
    // Measured on its clear pixels the scale holds whatever the file says (a sky scaled by hand keeps
    // its attributes); on an overcast's mean it does not: a dark overcast is 0.3 x the clear-sky
    // model's radiance because it is dark, and moved at the model's scale it read as a thinner cloud
    // (`compare` darkened its clear sky to match). A sky that says it is W m^-2 sr^-1 and shows
    // little clear sky is taken at its word.
    // Brighter than any sky can be (30 x the clear-sky model's on its mean: a sunlit cumulus field
    // is 2-3 x) it is not in those units whatever it says: an overcast x 1e4 clipped at the log
    // map's 300 and came out a flat 0.2 % of itself after one step.
    constexpr double kBrighterThanAnySky = 30;
    if (sky->units == kAbsoluteRadiance && scale.clear_weight < 0.5 && scale.factor <= kBrighterThanAnySky)
        scale.apply = false;
    if (!scale.apply) return scale;
    scale_radiance(sky, 1 / scale.factor);
    if (*previous) {  // the same units as the sky: one factor for both
        SkyImage p = **previous;
        scale_radiance(&p, 1 / scale.factor);
        *previous = std::make_shared<const SkyImage>(std::move(p));
    }
    return scale;
}

}  // namespace dynsky
