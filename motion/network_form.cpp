#include "motion/network_form.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "sky/clear_sky.h"
#include "sky/fisheye.h"
#include "sky/preset_import.h"
#include "util/error.h"
#include "util/image.h"

namespace dynsky {

namespace fs = std::filesystem;

cv::Mat to_network_form(const SkyImage& sky, const NetworkFormParams& form, int resolution) {
    const int n = sky.resolution;
    Image unit = hdr_to_unit(sky, form.unit_map);
    cv::Mat image(n, n, CV_32FC3);
    std::copy(unit.pixels.begin(), unit.pixels.end(), image.ptr<float>());
    if (resolution > 0 && resolution != n) {
        cv::resize(image, image, cv::Size(resolution, resolution), 0, 0, cv::INTER_AREA);
        image.setTo(cv::Scalar::all(0), ~sky_disc_mask(resolution));
    }
    return image;
}

SkyImage from_network_form(const cv::Mat& image, const SkyImage& like, const NetworkFormParams& form) {
    if (image.rows != like.resolution || image.cols != like.resolution || image.type() != CV_32FC3)
        throw Error("from_network_form: the image must be CV_32FC3 at the sky's resolution");
    Image unit(image.cols, image.rows, 3);
    cv::Mat c = image.isContinuous() ? image : image.clone();
    std::copy(c.ptr<float>(), c.ptr<float>() + unit.pixels.size(), unit.pixels.begin());
    SkyImage out = unit_to_hdr(unit, form.unit_map);
    out.time_seconds = like.time_seconds;
    out.sun_direction = like.sun_direction;
    out.source = like.source;
    out.units = like.units;
    return out;
}

namespace {
// I_cm of an HDR sky at its own resolution, CV_8UC1 255 = cloud.
cv::Mat cloud_mask_of_sky(const SkyImage& sky, const NetworkFormParams& form) {
    const int n = sky.resolution;
    std::vector<unsigned char> in_disc(size_t(n) * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) in_disc[size_t(j) * n + i] = sky.in_disc(i, j);
    Image mask = cloud_mask(encode_sky_for_mask(sky), form.cloud_rule, &in_disc);
    cv::Mat m(n, n, CV_8UC1);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) m.at<uint8_t>(j, i) = mask.at(i, j, 0) > 0.7f ? 255 : 0;
    return m;
}
}  // namespace

cv::Mat network_cloud_mask(const cv::Mat& image, const NetworkFormParams& form) {
    SkyImage like(image.rows);
    cv::Mat clean;
    cv::min(cv::max(image, 0.0), 1.0, clean);
    cv::patchNaNs(clean, 0.0);
    return cloud_mask_of_sky(from_network_form(clean, like, form), form);
}

NetworkFrame resample_frame(const NetworkFrame& frame, int resolution) {
    const int n = resolution;
    if (frame.image.rows == n) return frame;
    NetworkFrame f;
    f.time_seconds = frame.time_seconds;
    f.sun_direction = frame.sun_direction;
    const cv::Mat disc = sky_disc_mask(n);
    cv::resize(frame.image, f.image, cv::Size(n, n), 0, 0, cv::INTER_AREA);
    f.image.setTo(cv::Scalar::all(0), ~disc);
    cv::Mat seen, cloud;
    frame.valid.convertTo(seen, CV_32F, 1.0 / 255.0);
    cv::resize(seen, seen, cv::Size(n, n), 0, 0, cv::INTER_AREA);
    f.valid = (seen > 0.999f) & disc;
    frame.cloud.convertTo(cloud, CV_32F, 1.0 / 255.0);
    cv::resize(cloud, cloud, cv::Size(n, n), 0, 0, cv::INTER_AREA);
    f.cloud = (cloud > 0.5f) & disc;
    return f;
}

NetworkFrame network_frame(const SkyImage& sky, const std::vector<unsigned char>& not_sky, int resolution,
                           const NetworkFormParams& form) {
    const int big = sky.resolution;
    if (!not_sky.empty() && not_sky.size() != size_t(big) * big)
        throw Error("network_frame: the not-sky mask does not match the sky's resolution");
    NetworkFrame f;
    f.time_seconds = sky.time_seconds;
    f.sun_direction = sky.sun_direction;
    f.image = to_network_form(sky, form);
    f.valid = sky_disc_mask(big);
    if (!not_sky.empty())
        for (int j = 0; j < big; ++j)
            for (int i = 0; i < big; ++i)
                if (not_sky[size_t(j) * big + i]) f.valid.at<uint8_t>(j, i) = 0;
    f.cloud = cloud_mask_of_sky(sky, form);
    return resample_frame(f, resolution > 0 ? resolution : big);
}

NetworkFrame network_frame_from_photo(const std::string& path, const std::string& preset, int import_resolution,
                                      int resolution, const NetworkFormParams& form) {
    std::vector<unsigned char> not_sky;
    if (!preset.empty()) {
        SkyImage sky = import_preset_photo(path, preset, import_resolution, &not_sky);
        return network_frame(sky, not_sky, resolution, form);
    }
    const SkyImage sky = load_sky(path);
    if (sky.resolution < import_resolution)
        throw_file_error(path, "is a " + std::to_string(sky.resolution) + " px sky, smaller than --import-res " +
                                   std::to_string(import_resolution) +
                                   " (import it larger or give a smaller --import-res)");
    not_sky = sky.filled;  // load_sky read the mask its import wrote beside it
    // At the import resolution first (area-averaged), then as above: as a photograph imported there.
    NetworkFrame at_import = network_frame(sky, not_sky, import_resolution, form);
    return resolution == import_resolution ? at_import : resample_frame(at_import, resolution);
}

double clear_sky_turbidity(const SkyImage& sky, const Vec3d& sun_direction) {
    if (!(sun_direction.y() > 0.01) || sky.resolution < 16) return 3.0;
    const int n = 64;
    const SkyImage small = sky.resolution == n ? sky : resampled_sky(sky, n);
    const Vec3d sun = sun_direction.normalized();
    const double cos_sun = std::cos(5.0 * kPiD / 180);  // the sun and its disc's spread left out
    auto departure = [&](double turbidity) {
        ClearSkyParams p;
        p.sun_direction = sun;
        p.turbidity = turbidity;
        p.sun_disc = false;
        const SkyImage model = make_clear_sky(p, n);
        std::vector<double> d;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                if (!small.in_disc(i, j) || fisheye::direction_from_pixel(i, j, n).dot(sun) > cos_sun) continue;
                const Color v = small.pixel(i, j), m = model.pixel(i, j);
                if (!(luminance(v) > 0) || !(luminance(m) > 0) || !(v[2] > 0) || !(m[2] > 0) || !(v[0] > 0)) continue;
                d.push_back(std::abs(std::log(luminance(v) / luminance(m))) +
                            std::abs(std::log((v[0] / v[2]) / (m[0] / m[2]))));
            }
        if (d.size() < 100) return 1e9;
        std::nth_element(d.begin(), d.begin() + long(d.size() / 2), d.end());
        return d[d.size() / 2];
    };
    const double at_three = departure(3.0);
    double best = 3.0, best_departure = at_three;
    // Every half step of the model's range, then the best one's neighbourhood by tenths: a sky of
    // turbidity 7 or 9 (`sky clear --turbidity 7`) lay between the candidates, fell back to 3, and
    // its aureole read as cloud and was torn off the sun by the wind.
    for (double t = 1.5; t <= 10.0; t += 0.5)
        if (const double d = departure(t); d < best_departure) best = t, best_departure = d;
    const double coarse = best;
    for (double t = coarse - 0.4; t <= coarse + 0.4 + 1e-9; t += 0.1)
        if (t >= 1.5 && t <= 10.0)
            if (const double d = departure(t); d < best_departure) best = t, best_departure = d;
    return best_departure < 0.02 && best_departure < 0.5 * at_three ? best : 3.0;
}

cv::Mat clear_background(const Vec3d& sun_direction, int n, const NetworkFormParams& form, double turbidity) {
    ClearSkyParams p;
    p.sun_direction = sun_direction.y() > 0.01 ? sun_direction : Vec3d(sun_direction.x(), 0.01, sun_direction.z());
    p.turbidity = turbidity;
    p.sun_disc = false;
    return to_network_form(make_clear_sky(p, n), form, n);
}

}  // namespace dynsky
