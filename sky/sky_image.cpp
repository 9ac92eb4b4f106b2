#include "sky/sky_image.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <set>
#include <mutex>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "sky/fisheye.h"
#include "sky/sun_position.h"
#include "util/error.h"
#include "util/frame_names.h"
#include "util/parse.h"
#include "util/progress.h"

namespace dynsky {

bool SkyImage::in_disc(int i, int j) const {
    Vec2 uv = fisheye::pixel_center_uv(i, j, resolution);
    return uv.squaredNorm() <= 1.0f;
}

void check_sky_resolution(int n) {
    if (n < kMinSkyResolution || n > kMaxSkyResolution)
        throw Error("--sky-res " + std::to_string(n) + ": the fisheye must be " + std::to_string(kMinSkyResolution) +
                    ".." + std::to_string(kMaxSkyResolution) + " pixels wide");
}

void validate_sky(const SkyImage& sky, const std::string& name) {
    int n = sky.resolution;
    if (n <= 0 || sky.rgb.size() != size_t(n) * n * 3) throw_file_error(name, "sky image has no pixels");
    double total = 0, brightest = 0;
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            Color c = sky.pixel(i, j);
            for (int k = 0; k < 3; ++k) {
                if (!std::isfinite(c[k]))
                    throw_file_error(name, "sky pixel (" + std::to_string(i) + ", " + std::to_string(j) + ") is " +
                                               (std::isnan(c[k]) ? "NaN" : "infinite") +
                                               ": a sky must hold finite radiance");
                if (c[k] < 0)
                    throw_file_error(name, "sky pixel (" + std::to_string(i) + ", " + std::to_string(j) +
                                               ") is negative (" + std::to_string(c[k]) +
                                               "): radiance cannot be negative");
                if (c[k] > kMaxSkyRadiance)
                    throw_file_error(name, "sky pixel (" + std::to_string(i) + ", " + std::to_string(j) + ") is " +
                                               number_text(c[k], 3) +
                                               " W m^-2 sr^-1, above the limit of 1e9 (the sun is about 2e7): a "
                                               "corrupt or mis-scaled sky");
            }
            if (sky.in_disc(i, j)) total += c.sum(), brightest = std::max(brightest, double(c.maxCoeff()));
        }
    }
    if (!(total > 0))
        throw_file_error(
            name,
            "sky is black everywhere inside the fisheye disc: nothing to light with (a scene lit by its "
            "own lights at night: give a faint sky, e.g. a constant 5e-7 W m^-2 sr^-1, about 0.001 lx, the "
            "light of a moonless night; a full moon's 0.2 lx is about 1e-4)");
    // Light this faint underflows single precision on its way to a pixel: a black render.
    if (brightest < kMinSkyRadiance)
        throw_file_error(name, "sky's brightest pixel is " + number_text(brightest, 3) + ", below " +
                                   number_text(kMinSkyRadiance, 3) +
                                   ": too faint to light with in single precision (a mis-scaled sky?)");
}

void write_sky_metadata(const SkyImage& sky, ImageMetadata* m) {
    m->numbers["dynsky:time"] = sky.time_seconds;
    if (sky.sun_direction) {
        m->numbers["dynsky:sun_x"] = sky.sun_direction->x();
        m->numbers["dynsky:sun_y"] = sky.sun_direction->y();
        m->numbers["dynsky:sun_z"] = sky.sun_direction->z();
    }
    if (!sky.source.empty()) m->strings["dynsky:source"] = sky.source;
    if (!sky.units.empty()) m->strings["dynsky:units"] = sky.units;
}

Image sky_to_image(const SkyImage& sky) {
    Image image(sky.resolution, sky.resolution, 3);
    image.pixels = sky.rgb;
    write_sky_metadata(sky, &image.metadata);
    image.metadata.strings["dynsky:layout"] = "equidistant fisheye, upper hemisphere, north up, east left";
    return image;
}

void read_sky_metadata(const ImageMetadata& metadata, const std::string& name, SkyImage* out) {
    SkyImage& sky = *out;
    const auto& num = metadata.numbers;
    const auto& str = metadata.strings;
    for (const char* key : {"dynsky:time", "dynsky:sun_x", "dynsky:sun_y", "dynsky:sun_z"}) {
        if (str.count(key)) throw_file_error(name, std::string(key) + " is text ('" + str.at(key) + "'), not a number");
        if (num.count(key) && !std::isfinite(num.at(key)))
            throw_file_error(name, std::string(key) + " is " + number_text(num.at(key)) + ", not a finite number");
    }
    if (auto it = num.find("dynsky:time"); it != num.end()) sky.time_seconds = it->second, sky.has_clock = true;
    const int sun_parts = int(num.count("dynsky:sun_x") + num.count("dynsky:sun_y") + num.count("dynsky:sun_z"));
    if (sun_parts != 0 && sun_parts != 3)
        throw_file_error(name, "has only part of the sun's direction (dynsky:sun_x, _y, _z: all three or none)");
    if (sun_parts == 3) {
        const Vec3d d(num.at("dynsky:sun_x"), num.at("dynsky:sun_y"), num.at("dynsky:sun_z"));
        if (!(d.norm() > 1e-6) || !std::isfinite(d.norm()))
            throw_file_error(name, "its sun direction (dynsky:sun_x, _y, _z) is (" + number_text(d.x()) + ", " +
                                       number_text(d.y()) + ", " + number_text(d.z()) +
                                       "), not a direction: fix or remove those attributes");
        sky.sun_direction = d.normalized().cast<float>();
    }
    if (auto it = metadata.strings.find("dynsky:source"); it != metadata.strings.end()) sky.source = it->second;
    if (auto it = metadata.strings.find("dynsky:units"); it != metadata.strings.end()) sky.units = it->second;
}

std::array<int, 3> rgb_channel_indices(const Image& image, const std::string& name) {
    // The colour channels by name, any case: R, G, B; else one layer's LAYER.R, .G, .B (a render's
    // AOV layers beside its RGB are ignored); a file without names gives its first three.
    std::array<int, 3> rgb = {0, 1, 2};
    if (!image.channel_names.empty()) {
        std::vector<std::string> upper = image.channel_names;
        for (std::string& n : upper)
            for (char& ch : n) ch = char(std::toupper(static_cast<unsigned char>(ch)));
        auto index = [&](const std::string& wanted) {
            const auto it = std::find(upper.begin(), upper.end(), wanted);
            return it == upper.end() ? -1 : int(it - upper.begin());
        };
        std::string layer;  // "" or "LAYER."
        if (index("R") < 0 || index("G") < 0 || index("B") < 0) {
            std::vector<size_t> layered_r;  // the channels named LAYER.R
            for (size_t k = 0; k < upper.size(); ++k)
                if (upper[k].size() > 2 && upper[k].compare(upper[k].size() - 2, 2, ".R") == 0) layered_r.push_back(k);
            if (layered_r.size() > 1)
                throw_file_error(name, "has colour channels in more than one layer (" +
                                           image.channel_names[layered_r[0]] + ", " +
                                           image.channel_names[layered_r[1]] +
                                           ") and none without one: write the one that is the sky to its own file");
            if (!layered_r.empty()) layer = upper[layered_r[0]].substr(0, upper[layered_r[0]].size() - 1);
        }
        for (int c = 0; c < 3; ++c) {
            const std::string want(1, "RGB"[c]);
            rgb[c] = index(layer + want);
            if (rgb[c] < 0) {
                std::string listed;
                for (const std::string& n : image.channel_names) listed += (listed.empty() ? "" : ", ") + n;
                throw_file_error(name, "has no " + want + " channel (its channels: " + listed +
                                           "): radiance needs R, G and B channels");
            }
        }
    }
    return rgb;
}

namespace {
// ": NAME, NAME" of an image's channels, "" when it names none.
std::string channel_list(const Image& image) {
    std::string s;
    for (const std::string& c : image.channel_names) s += (s.empty() ? " (its channels: " : ", ") + c;
    return s.empty() ? s : s + "; a luminance-only Y sky has no colour to light with)";
}
}  // namespace

SkyImage sky_from_image(const Image& image, const std::string& name) {
    if (image.width != image.height)
        throw_file_error(name, "sky image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                                   ", but a canonical fisheye sky must be square (render, animate, compare and sky "
                                   "predict also take a 2:1 lat-long)");
    if (image.width < 4)
        throw_file_error(name, "sky image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                                   " pixels: too small to hold a sky (at least 4 x 4)");
    if (image.channels < 3)
        throw_file_error(name, "sky image needs 3 colour channels (R, G, B), has " + std::to_string(image.channels) +
                                   channel_list(image));
    const std::array<int, 3> rgb = rgb_channel_indices(image, name);
    SkyImage sky(image.width);
    for (size_t p = 0; p < size_t(image.width) * image.height; ++p)
        for (int c = 0; c < 3; ++c) sky.rgb[p * 3 + c] = image.pixels[p * image.channels + size_t(rgb[c])];
    read_sky_metadata(image.metadata, name, &sky);
    return sky;
}

void refuse_jpeg_as_radiance(const std::string& path) {
    // A JPEG is 8-bit display values whatever its name: refused by its first bytes, before it is
    // decoded only to be refused by its pixel type.
    if (has_jpeg_signature(path))
        throw_file_error(path,
                         "is a JPEG file of 8-bit pixels: integer pixels are display-encoded values, not linear "
                         "radiance. A sky is a float EXR (or .hdr): an all-sky (fisheye) photograph becomes one "
                         "with 'dynsky sky import'; a tone-mapped panorama cannot be made radiance again, use "
                         "the HDR (.exr, .hdr) it was made from");
}

void convert_to_rec709(Image* image, const std::string& path) {
    const auto flag = image->metadata.numbers.find("acesImageContainerFlag");
    const auto space = image->metadata.strings.find("oiio:ColorSpace");
    const std::optional<Chromaticities> primaries =
        file_primaries(image->chromaticities, flag != image->metadata.numbers.end() && flag->second == 1,
                       space == image->metadata.strings.end() ? "" : space->second);
    // What the file said is not said of what it becomes (a sky written from it is Rec.709).
    if (flag != image->metadata.numbers.end()) image->metadata.numbers.erase(flag);
    image->chromaticities.reset();
    if (!primaries) return;
    // Integer pixels are display-encoded (photographs): a matrix on encoded values would be wrong,
    // and photographs' primaries are the camera's anyway (sky-import calibrates colour).
    if (!image->has_float_file_pixels()) {
        std::fprintf(stderr, "dynsky: warning: %s: says its pixels are in %s primaries: taken as sRGB's\n",
                     path.c_str(), describe_chromaticities(*primaries).c_str());
        return;
    }
    // A grey image is the same grey in any primaries of this white (the adapted white stays white).
    if (image->channels < 3) return;
    Eigen::Matrix3d m;
    try {
        m = rec709_from(*primaries);
    } catch (const Error& e) {
        throw_file_error(path, e.what());
    }
    const Eigen::Matrix3f mf = m.cast<float>();
    const size_t count = size_t(image->width) * image->height;
    size_t negative = 0;
    for (size_t q = 0; q < count; ++q) {
        float* p = &image->pixels[q * image->channels];
        const Eigen::Vector3f v = mf * Eigen::Vector3f(p[0], p[1], p[2]);
        bool clipped = false;
        for (int c = 0; c < 3; ++c) {
            // Beyond Rec.709's gamut a colour has a negative part, which no light can be.
            clipped = clipped || v[c] < 0;
            p[c] = std::isfinite(v[c]) ? std::max(v[c], 0.0f) : v[c];
        }
        negative += clipped;
    }
    if (space != image->metadata.strings.end()) space->second = "Linear";
    std::fprintf(stderr, "dynsky: note: %s: pixels converted from %s primaries to linear Rec.709 (dynsky's space)%s\n",
                 path.c_str(), describe_chromaticities(*primaries).c_str(),
                 negative
                     ? (", " + std::to_string(negative) + " pixel(s) outside Rec.709's gamut clipped to it").c_str()
                     : "");
}

void warn_of_unapplied_profile(const Image& image, const std::string& path) {
    const auto& strings = image.metadata.strings;
    // An ICC profile other than sRGB's (a camera's Adobe RGB, Display P3) is not applied.
    const auto icc = strings.find("ICCProfile:profile_description");
    if (icc != strings.end()) {
        std::string name = icc->second;
        std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return std::tolower(c); });
        // Once per profile: a sequence's photographs share theirs.
        static std::mutex mutex;
        static std::set<std::string> warned;
        const std::lock_guard<std::mutex> lock(mutex);
        if (name.find("srgb") == std::string::npos && name.find("61966") == std::string::npos &&
            warned.insert(icc->second).second)
            std::fprintf(stderr,
                         "dynsky: warning: %s: its ICC profile '%s' is not applied: its values are taken as sRGB's "
                         "(colours off by up to 15 %% for Adobe RGB); convert it to sRGB first (e.g. jpgicc or tificc "
                         "of liblcms2-utils, or a photo editor); said once for every file with it\n",
                         path.c_str(), icc->second.c_str());
    }
}

Image read_radiance_image(const std::string& path) {
    Image image = read_image(path);
    if (image.channels > 3 || (image.channels == 3 && !image.channel_names.empty())) {
        // R, G and B by name (a lat-long or a photograph with AOV layers, X Y Z or Y BY RY: its
        // first three channels read as colour without a word).
        const std::array<int, 3> rgb = rgb_channel_indices(image, path);
        if (image.channels != 3 || rgb != std::array<int, 3>{0, 1, 2}) {
            Image picked(image.width, image.height, 3);
            for (size_t q = 0; q < size_t(image.width) * image.height; ++q)
                for (int c = 0; c < 3; ++c)
                    picked.pixels[q * 3 + c] = image.pixels[q * image.channels + size_t(rgb[c])];
            picked.metadata = std::move(image.metadata);
            picked.file_format = image.file_format, picked.file_pixel_type = image.file_pixel_type;
            picked.chromaticities = image.chromaticities;
            image = std::move(picked);
        }
        image.channel_names = {"R", "G", "B"};
    }
    convert_to_rec709(&image, path);
    warn_of_unapplied_profile(image, path);
    // Lossy compression's ringing beside a bright pixel reads as 0: a negative within 1e-3 of the
    // brightest value in its 33 x 33 neighbourhood (DWA's blocks are 8 x 8 / 32 lines). Measured
    // against the whole image's brightest, a -500 pixel 70 degrees from a 2e6 sun read as 0 silently.
    // Most files have no negative at all: only then is the neighbourhood's brightest found.
    if (std::none_of(image.pixels.begin(), image.pixels.end(), [](float v) { return v < 0; })) return image;
    cv::Mat top(image.height, image.width, CV_32FC1, cv::Scalar(0));
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x)
            for (int c = 0; c < image.channels; ++c)
                if (const float v = image.at(x, y, c); std::isfinite(v))
                    top.at<float>(y, x) = std::max(top.at<float>(y, x), v);
    cv::dilate(top, top, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(33, 33)));
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x)
            for (int c = 0; c < image.channels; ++c) {
                float& v = image.pixels[(size_t(y) * image.width + x) * image.channels + c];
                if (v < 0 && v >= -1e-3f * top.at<float>(y, x)) v = 0;
            }
    return image;
}

Image read_sky_file(const std::string& path) {
    refuse_jpeg_as_radiance(path);
    Image image = read_radiance_image(path);
    apply_orientation(image);
    return image;
}

std::string filled_mask_path(const std::string& sky_path) {
    return std::filesystem::path(sky_path).replace_extension(".filled.png").string();
}

std::vector<unsigned char> filled_mask_beside(const std::string& sky_path, int n) {
    const std::filesystem::path filled = filled_mask_path(sky_path);
    if (!std::filesystem::exists(filled)) return {};
    const Image m = read_image(filled.string());
    if (m.width != n || m.height != n) {
        // Not this sky's (left beside a sky of another size): ignored, said; only the moving sky
        // and evaluations use a mask, and a render must not fail on one.
        if (!reports_silenced())
            std::fprintf(stderr,
                         "dynsky: warning: %s: a filled-pixel mask of %dx%d beside a %d px sky: not its mask, "
                         "ignored (every pixel counts as seen)\n",
                         filled.c_str(), m.width, m.height, n);
        return {};
    }
    std::vector<unsigned char> mask(size_t(n) * n);
    for (size_t p = 0; p < mask.size(); ++p) mask[p] = m.pixels[p * size_t(m.channels)] > 0.5f;
    return mask;
}

SkyImage load_sky(const std::string& path) { return sky_from_radiance_file(read_sky_file(path), path); }

void require_radiance_pixels(const Image& image, const std::string& path) {
    const std::string& type = image.file_pixel_type;
    if (type != "half" && type != "float" && type != "double")
        throw_file_error(path, "is a " + (image.file_format.empty() ? std::string("non-EXR") : image.file_format) +
                                   " file of " + type +
                                   " pixels: integer pixels are display-encoded values, not linear radiance. A sky "
                                   "is a float EXR (or .hdr): an all-sky (fisheye) photograph becomes one with 'dynsky "
                                   "sky import'; a tone-mapped panorama cannot be made radiance again, use the HDR "
                                   "(.exr, .hdr) it was made from");
}

namespace {

// A square image whose brightest light lies outside the sky disc is not an upper-hemisphere fisheye
// (a canonical sky has nothing there): a lat-long's top half stored square, a cropped panorama.
// Taken as one, its corners were dropped and its sun put at the horizon (2.4 x too dark a render,
// without a word; an audit of files from other tools): refused. Corners that hold light without
// it are said to be dropped. Skies this program wrote say their layout.
void check_light_outside_the_disc(const SkyImage& sky, const Image& image, const std::string& path) {
    if (image.metadata.strings.count("dynsky:layout")) return;
    double inside = 0, outside = 0, top_in = 0, top_out = 0, low_in = std::numeric_limits<double>::infinity();
    long n_inside = 0, n_outside = 0;
    for (int j = 0; j < sky.resolution; ++j)
        for (int i = 0; i < sky.resolution; ++i) {
            const double l = luminance(sky.pixel(i, j));
            if (!std::isfinite(l)) continue;  // validate_sky names it
            if (sky.in_disc(i, j)) inside += l, ++n_inside, top_in = std::max(top_in, l), low_in = std::min(low_in, l);
            else outside += l, ++n_outside, top_out = std::max(top_out, l);
        }
    if (n_inside == 0 || n_outside == 0 || !(inside > 0) || !(outside > 0)) return;
    const double ratio = (outside / n_outside) / (inside / n_inside);
    const std::string share = number_text(100 * ratio, 3) + " % of the disc's mean radiance";
    // Its brightest light (a sun) outside the disc: dropping it is surely wrong.
    if (top_out > top_in)
        throw_file_error(path,
                         "is not an upper-hemisphere fisheye: its brightest pixel lies in a corner, outside "
                         "the sky disc (the corners hold " +
                             share +
                             "; a canonical sky has nothing there). A 2:1 lat-long (whole sphere) is taken as "
                             "it is; a photograph's fisheye with 'dynsky sky import'; a panorama's top half or "
                             "a cropped image must be made a lat-long or a fisheye first");
    // A uniform sky (a furnace test's) is the same in any layout: nothing to say.
    if (ratio > kMaxLightOutsideDisc && top_in > 1.01 * low_in)
        std::fprintf(stderr,
                     "dynsky: warning: %s: its corners, outside the sky disc, hold light (%s) that is dropped: is "
                     "it an upper-hemisphere fisheye (north up, east left)? A 2:1 lat-long is taken as it is\n",
                     path.c_str(), share.c_str());
}

}  // namespace

SkyImage sky_from_radiance_file(const Image& image, const std::string& path) {
    require_radiance_pixels(image, path);
    SkyImage sky = sky_from_image(image, path);
    validate_sky(sky, path);  // a NaN or huge pixel named as such first, wherever it lies
    check_light_outside_the_disc(sky, image, path);
    if (sky.source.empty()) sky.source = path;
    sky.filled = filled_mask_beside(path, sky.resolution);
    return sky;
}

void save_sky(const std::string& path, const SkyImage& sky, const std::string& preview_png,
              const ImageMetadata& extra) {
    if (file_extension(path) != ".exr") throw_file_error(path, "sky images are written as OpenEXR: use a .exr name");
    Image image = sky_to_image(sky);
    for (const auto& [name, value] : extra.numbers) image.metadata.numbers[name] = value;
    for (const auto& [name, value] : extra.strings) image.metadata.strings[name] = value;
    write_image(path, image);
    // A filled mask beside the sky replaced belonged to that one (an import's), not to this.
    std::error_code ec;
    std::filesystem::remove(filled_mask_path(path), ec);
    if (!preview_png.empty()) write_image(preview_png, tonemap_to_display(image));
}

SkyImage resampled_sky(const SkyImage& sky, int n) {
    if (n < 1) throw Error("resampled_sky: the resolution must be positive");
    if (n == sky.resolution) return sky;
    const int m = sky.resolution;
    cv::Mat image(m, m, CV_32FC3), out;
    const double c = (m - 1) / 2.0, rim = m / 2.0 - 0.5;  // the last ring of pixel centres inside
    for (int j = 0; j < m; ++j)
        for (int i = 0; i < m; ++i) {
            int si = i, sj = j;
            if (!sky.in_disc(i, j)) {  // the nearest pixel inside along the radius
                const double x = i - c, y = j - c, r = std::hypot(x, y), f = r > 0 ? rim / r : 0.0;
                si = std::clamp(int(std::lround(c + x * f)), 0, m - 1);
                sj = std::clamp(int(std::lround(c + y * f)), 0, m - 1);
                for (int step = 0; step < m && !sky.in_disc(si, sj); ++step) {  // rounding left it outside
                    si += si < c ? 1 : si > c ? -1 : 0;
                    sj += sj < c ? 1 : sj > c ? -1 : 0;
                }
            }
            const Color v = sky.pixel(si, sj);
            image.at<cv::Vec3f>(j, i) = cv::Vec3f(v[0], v[1], v[2]);
        }
    cv::resize(image, out, cv::Size(n, n), 0, 0, n > m ? cv::INTER_LINEAR : cv::INTER_AREA);
    SkyImage r = sky;
    r.resolution = n;
    r.rgb.assign(size_t(n) * n * 3, 0.0f);
    if (!sky.filled.empty()) {  // a pixel is filled where any pixel under it was
        cv::Mat mask(m, m, CV_8UC1, const_cast<unsigned char*>(sky.filled.data())), small;
        cv::resize(mask * 255, small, cv::Size(n, n), 0, 0, n > m ? cv::INTER_NEAREST : cv::INTER_AREA);
        r.filled.assign(size_t(n) * n, 0);
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) r.filled[size_t(j) * n + i] = small.at<unsigned char>(j, i) > 0;
    }
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            if (r.in_disc(i, j)) {
                const cv::Vec3f v = out.at<cv::Vec3f>(j, i);
                r.set_pixel(i, j, Color(std::max(v[0], 0.0f), std::max(v[1], 0.0f), std::max(v[2], 0.0f)));
            }
    return r;
}

void clear_outside_disc(SkyImage* sky) {
    for (int j = 0; j < sky->resolution; ++j)
        for (int i = 0; i < sky->resolution; ++i)
            if (!sky->in_disc(i, j)) sky->set_pixel(i, j, Color::Zero());
}

double horizontal_illuminance(const SkyImage& sky) {
    double e = 0;
    for (int j = 0; j < sky.resolution; ++j)
        for (int i = 0; i < sky.resolution; ++i)
            if (sky.in_disc(i, j))
                e += luminance(sky.pixel(i, j)) * fisheye::direction_from_pixel(i, j, sky.resolution).y() *
                     fisheye::pixel_solid_angle(i, j, sky.resolution);
    return kLumensPerWatt * e;
}

std::optional<double> sky_recorded_utc_seconds(const SkyImage& sky) {
    const size_t at = sky.source.rfind("time=");
    if (at == std::string::npos || (at > 0 && sky.source[at - 1] != ' ' && sky.source[at - 1] != '('))
        return std::nullopt;
    const size_t end = sky.source.find_first_of(" )", at);
    const std::string text = sky.source.substr(at + 5, end == std::string::npos ? std::string::npos : end - at - 5);
    try {
        return utc_seconds(text);
    } catch (const Error&) {
        return std::nullopt;
    }
}

std::vector<std::string> sky_sequence_files(const std::string& folder) {
    std::vector<std::string> skies, others;
    for (const auto& e : std::filesystem::directory_iterator(folder)) {
        if (!e.is_regular_file() || is_hidden_file(e.path().string())) continue;
        const std::string ext = file_extension(e.path().string());
        // `sky procedural`'s flow_NNNN.exr beside its frames hold motion, not skies (at the
        // frames' times: ordered by time, one was taken for the previous frame).
        // Radiance .hdr and .pfm files are float skies too (a capture tool's HDR sequence).
        if ((ext == ".exr" && !image_header_number(e.path().string(), "dynsky:flow_dt")) || ext == ".hdr" ||
            ext == ".pfm") {
            skies.push_back(e.path().string());
        } else if (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".tif" || ext == ".tiff") {
            if (written_beside_a_sky(e.path().string())) continue;
            others.push_back(e.path().filename().string());
        }
    }
    skies = skies_in_time_order(skies);
    if (!others.empty()) {  // a photograph among the skies, not imported: said, not silently skipped
        std::sort(others.begin(), others.end());
        std::fprintf(stderr,
                     "dynsky: warning: %s: %zu image(s) that are not float skies ignored (%s%s); the sequence is its "
                     ".exr, .hdr and .pfm files (import photographs with 'dynsky sky import')\n",
                     folder.c_str(), others.size(), others[0].c_str(), others.size() > 1 ? ", ..." : "");
    }
    if (skies.empty())
        throw_file_error(
            folder, "a folder without sky files (.exr, .hdr, .pfm: give a captured sequence of canonical fisheyes)");
    return skies;
}

std::string sequence_start(const std::string& folder, bool previous_wanted, std::string* previous, bool quiet) {
    const std::vector<std::string> skies = sky_sequence_files(folder);
    const bool chosen = previous_wanted && skies.size() >= 2;
    if (chosen) *previous = skies[skies.size() - 2];
    if (!quiet)
        std::fprintf(stderr, "dynsky: note: %s: moving on from its last sky, %s%s%s\n", folder.c_str(),
                     std::filesystem::path(skies.back()).filename().c_str(),
                     chosen ? ", with the one before it as the previous frame: " : "",
                     chosen ? std::filesystem::path(*previous).filename().c_str() : "");
    return skies.back();
}

bool written_beside_a_sky(const std::string& path) {
    const std::filesystem::path p(path);
    if (file_extension(path) != ".png") return false;
    if (p.filename() == kSequenceObstructionsName) return true;
    std::filesystem::path stem = p.stem();
    if (stem.extension() == ".filled") stem = stem.stem();
    std::error_code ec;
    return std::filesystem::exists(p.parent_path() / (stem.string() + ".exr"), ec);
}

std::vector<std::string> skies_in_time_order(std::vector<std::string> files) {
    std::sort(files.begin(), files.end(), natural_less);  // "sky 9" before "sky 10" when no time says
    std::vector<double> clocks, utc;
    bool all_clocks = true, all_utc = true, any_clock_set = false;
    for (const std::string& f : files) {
        const std::optional<double> t = image_header_number(f, "dynsky:time");
        all_clocks = all_clocks && t.has_value();
        any_clock_set = any_clock_set || (t && *t != 0);
        clocks.push_back(t.value_or(0));
        SkyImage recorded;
        recorded.source = image_header_strings(f, {"dynsky:source"}).front();
        const std::optional<double> u = sky_recorded_utc_seconds(recorded);
        all_utc = all_utc && u.has_value();
        utc.push_back(u.value_or(0));
    }
    const std::vector<double>* key = all_clocks && any_clock_set ? &clocks : all_utc ? &utc : nullptr;
    if (!key) return files;
    std::vector<size_t> order(files.size());
    for (size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return (*key)[a] < (*key)[b]; });
    std::vector<std::string> sorted;
    for (size_t k : order) sorted.push_back(files[k]);
    return sorted;
}

}  // namespace dynsky
