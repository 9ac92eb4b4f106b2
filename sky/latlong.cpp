#include "sky/latlong.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <utility>

#include <opencv2/imgproc.hpp>

#include "sky/fisheye.h"
#include "sky/sky_image.h"
#include "util/error.h"
#include "util/parse.h"
#include "util/progress.h"

namespace dynsky {

Vec3d latlong_direction(double u, double v) {
    return fisheye::direction_from_angles(kPiD * v, 2 * kPiD * u - kPiD / 2);
}

void latlong_uv(const Vec3d& w, double* u, double* v) {
    double theta = fisheye::zenith_angle(w);
    double phi = fisheye::azimuth(w);  // [0, 2 pi)
    double uu = (phi + kPiD / 2) / (2 * kPiD);
    *u = uu >= 1.0 ? uu - 1.0 : uu;
    *v = theta / kPiD;
}

double latlong_pixel_solid_angle(int row, int width, int height) {
    return (2 * kPiD / width) * (std::cos(kPiD * row / height) - std::cos(kPiD * (row + 1) / height));
}

Color sample_sky(const SkyImage& sky, const Vec3d& w) {
    double u, v;
    if (!fisheye::uv_from_direction(w, &u, &v)) return Color::Zero();
    const int n = sky.resolution;
    double x = (u + 1) / 2 * n - 0.5, y = (v + 1) / 2 * n - 0.5;
    Color c;
    if (fisheye::bilinear_in_disc(sky.rgb.data(), n, x, y, &c)) return c;
    // At the very rim no neighbour's centre is inside the disc: take the nearest pixel inside.
    double r = std::sqrt(u * u + v * v), k = r > 0 ? std::min(1.0, (1.0 - 1.0 / n) / r) : 1.0;
    int i = std::clamp(int(std::floor((u * k + 1) / 2 * n)), 0, n - 1);
    int j = std::clamp(int(std::floor((v * k + 1) / 2 * n)), 0, n - 1);
    return sky.pixel(i, j);
}

Color sample_latlong(const Image& latlong, const Vec3d& w) {
    double u, v;
    latlong_uv(w, &u, &v);
    const int W = latlong.width, H = latlong.height;
    double x = u * W - 0.5, y = v * H - 0.5;
    int i0 = int(std::floor(x)), j0 = int(std::floor(y));
    double fx = x - i0, fy = y - j0;
    // Rows from the direction's own half (of an even height): next to the horizon the filter read
    // the other half's row, and a snow ground 20 x the sky lit an upward plane 1.7 % too much.
    int lo = 0, hi = H - 1;
    if (H % 2 == 0) (w.y() >= 0 ? hi : lo) = w.y() >= 0 ? H / 2 - 1 : H / 2;
    Color out = Color::Zero();
    for (int dj = 0; dj < 2; ++dj) {
        int j = std::clamp(j0 + dj, lo, hi);
        for (int di = 0; di < 2; ++di) {
            int i = ((i0 + di) % W + W) % W;
            double wgt = (di ? fx : 1 - fx) * (dj ? fy : 1 - fy);
            for (int c = 0; c < 3; ++c) out[c] += float(wgt) * latlong.at(i, j, std::min(c, latlong.channels - 1));
        }
    }
    return out;
}

Image sky_to_latlong(const SkyImage& sky, int width, const Color& ground) {
    if (width < 4 || width % 2 != 0)
        throw Error("lat-long width " + std::to_string(width) + " must be even and at least 4 (the image is W x W/2)");
    if (width > 65536) throw Error("lat-long width " + std::to_string(width) + " is over 65536 pixels");
    const int W = width, H = width / 2;
    Image out(W, H, 3);
    // The finest fisheye pixel spacing on the sphere: pi/N radially, (pi/N) sin(theta)/theta >= 2/N
    // around. Sub-samples no more than half of that apart see every fisheye pixel a lat-long pixel covers.
    const double texel = 2.0 / sky.resolution;
    tbb::parallel_for(tbb::blocked_range<int>(0, H), [&](const tbb::blocked_range<int>& rows) {
        for (int r = rows.begin(); r != rows.end(); ++r) {
            const double theta0 = kPiD * r / H, theta1 = kPiD * (r + 1) / H;
            const double max_sin = (theta0 <= kPiD / 2 && theta1 >= kPiD / 2)
                                       ? 1.0
                                       : std::max(std::sin(theta0), std::sin(theta1));
            const int n_theta = std::clamp(int(std::ceil(2 * (theta1 - theta0) / texel)), 1, 32);
            const int n_phi = std::clamp(int(std::ceil(2 * (2 * kPiD / W) * max_sin / texel)), 1, 32);
            for (int c = 0; c < W; ++c) {
                Eigen::Array3d sum = Eigen::Array3d::Zero();
                double weight = 0;
                for (int a = 0; a < n_theta; ++a) {
                    double v = (r + (a + 0.5) / n_theta) / H;
                    double wgt = std::sin(kPiD * v);
                    for (int b = 0; b < n_phi; ++b) {
                        double u = (c + (b + 0.5) / n_phi) / W;
                        Vec3d w = latlong_direction(u, v);
                        Color L = w.y() >= 0 ? sample_sky(sky, w) : ground;
                        sum += wgt * L.cast<double>();
                        weight += wgt;
                    }
                }
                Eigen::Array3d mean = weight > 0 ? Eigen::Array3d(sum / weight) : Eigen::Array3d::Zero();
                for (int k = 0; k < 3; ++k) out.at(c, r, k) = float(mean[k]);
            }
        }
    });
    write_sky_metadata(sky, &out.metadata);
    out.metadata.strings["dynsky:layout"] =
        "equirectangular W x W/2, top row zenith, centre column azimuth 90 deg (east), azimuth increasing to the right "
        "(Blender environment mapping with north = +Y)";
    return out;
}

SkyImage latlong_to_fisheye(const Image& latlong, int resolution, bool lower, ProgressBar* progress) {
    if (!is_latlong_shape(latlong.width, latlong.height) || latlong.channels < 3)
        throw Error("lat-long image is " + std::to_string(latlong.width) + "x" + std::to_string(latlong.height) + "x" +
                    std::to_string(latlong.channels) + ": want W x W/2 with 3 or more channels");
    if (resolution < 2 || resolution > 16384)
        throw Error("fisheye resolution " + std::to_string(resolution) + " must be in 2..16384");
    const int n = resolution, H = latlong.height;
    SkyImage sky(n);
    // A fisheye pixel spans pi/n radially; lat-long pixels pi/H: enough sub-samples a side to land
    // at least twice in every lat-long pixel the fisheye pixel covers. Where those disagree by more
    // than a factor 1.5 (a sun of a few pixels, a sharp edge) the pixel is sampled 4 x as finely a
    // side: point samples of a few-pixel sun missed or doubled up to 1 % of a sunny sky's energy.
    const int ss = std::clamp(int(std::ceil(2.0 * H / n)), 2, 16), fine = 4 * ss;
    auto average = [&](int i, int j, int k, double* spread) {
        Eigen::Array3d sum = Eigen::Array3d::Zero();
        double weight = 0, lo = 1e300, hi = 0;
        for (int b = 0; b < k; ++b)
            for (int a = 0; a < k; ++a) {
                double u = (i + (a + 0.5) / k) / n * 2 - 1, v = (j + (b + 0.5) / k) / n * 2 - 1;
                double r = std::sqrt(u * u + v * v);
                if (r > 1) continue;
                Vec3d w = fisheye::direction_from_uv(u, v);
                if (lower) w.y() = -w.y();
                double wgt = fisheye::sinc(r * kPiD / 2);  // solid angle per uv area (up to a constant)
                const Eigen::Array3d value = sample_latlong(latlong, w).cast<double>();
                sum += wgt * value;
                weight += wgt;
                const double l = value.sum();
                lo = std::min(lo, l), hi = std::max(hi, l);
            }
        if (spread) *spread = weight > 0 ? hi / std::max(lo, 1e-30) : 1.0;
        return std::make_pair(sum, weight);
    };
    // Refined: the pixels whose samples disagree and those within 2 pixels of them (a pixel whose
    // few samples all missed a sun it holds part of agrees with itself; refining only the others
    // added 0.5-0.9 % of the sky's energy).
    cv::Mat refine(n, n, CV_8UC1, cv::Scalar(0));
    tbb::parallel_for(0, n, [&](int j) {
        for (int i = 0; i < n; ++i) {
            if (fisheye::pixel_center_uv(i, j, n).squaredNorm() > 1.0f)
                continue;  // centre below the horizon: no sky (lookups step inward)
            double spread = 1;
            auto [sum, weight] = average(i, j, ss, &spread);
            if (spread > 1.5) refine.at<uint8_t>(j, i) = 255;
            if (weight > 0) sky.set_pixel(i, j, Eigen::Array3d(sum / weight).cast<float>());
        }
        if (progress) progress->advance();
    });
    cv::dilate(refine, refine, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(5, 5)));
    tbb::parallel_for(0, n, [&](int j) {
        for (int i = 0; i < n; ++i) {
            if (!refine.at<uint8_t>(j, i) || fisheye::pixel_center_uv(i, j, n).squaredNorm() > 1.0f) continue;
            const auto [sum, weight] = average(i, j, fine, nullptr);
            if (weight > 0) sky.set_pixel(i, j, Eigen::Array3d(sum / weight).cast<float>());
        }
        if (progress) progress->advance();
    });
    return sky;
}

LatlongEnvironment load_latlong_environment(const std::string& path, int resolution) {
    Image image = read_sky_file(path);
    require_radiance_pixels(image, path);
    return latlong_environment(image, path, resolution);
}

double turn_latlong(Image* latlong, double degrees) {
    if (!std::isfinite(degrees)) throw Error("the sky's turn must be a finite number of degrees");
    const int W = latlong->width;
    // Azimuth grows to the right: the pixel at column c goes to c + shift.
    const long columns = std::lround(degrees / 360.0 * W), shift = ((columns % W) + W) % W;
    if (shift == 0) return 0;
    const size_t row = size_t(W) * latlong->channels;
    for (int y = 0; y < latlong->height; ++y) {
        float* r = latlong->pixels.data() + size_t(y) * row;
        std::rotate(r, r + row - size_t(shift) * latlong->channels, r + row);
    }
    return 360.0 * double(columns) / W;
}

namespace {

Vec3d turned_direction(const Vec3d& w, double degrees) {
    return fisheye::direction_from_angles(fisheye::zenith_angle(w.normalized()),
                                          fisheye::azimuth(w.normalized()) + degrees * kPiD / 180);
}

// A fisheye turned by `turns` quarter turns (1..3): its pixels permuted, exactly. Azimuth grows from
// north (top) towards east (left): counter-clockwise in the image.
SkyImage quarter_turned(const SkyImage& sky, int turns) {
    const int code = turns == 1   ? cv::ROTATE_90_COUNTERCLOCKWISE
                     : turns == 2 ? cv::ROTATE_180
                                  : cv::ROTATE_90_CLOCKWISE;
    const int n = sky.resolution;
    SkyImage out = sky;
    cv::Mat in(n, n, CV_32FC3, const_cast<float*>(sky.rgb.data())), turned;
    cv::rotate(in, turned, code);
    out.rgb.assign(turned.ptr<float>(), turned.ptr<float>() + size_t(n) * n * 3);
    if (!sky.filled.empty()) {
        cv::Mat mask(n, n, CV_8UC1, const_cast<unsigned char*>(sky.filled.data())), turned_mask;
        cv::rotate(mask, turned_mask, code);
        out.filled.assign(turned_mask.ptr<unsigned char>(), turned_mask.ptr<unsigned char>() + size_t(n) * n);
    }
    if (sky.sun_direction)
        out.sun_direction = turned_direction(sky.sun_direction->cast<double>(), 90.0 * turns).cast<float>();
    return out;
}

}  // namespace

SkyImage turned_about_zenith(const SkyImage& sky, double degrees) {
    // A quarter turn (90, 180, 270) is exact; the round trip below blurs (a cloudy sky lost about
    // half its pixel-scale detail turned by 90, its sun's peak halved).
    if (std::isfinite(degrees)) {
        const double quarter = std::remainder(degrees, 360.0) / 90.0;
        const long quarters = std::lround(quarter);
        if (std::abs(quarter - double(quarters)) < 1e-9) {
            const int turns = int(((quarters % 4) + 4) % 4);
            return turns == 0 ? sky : quarter_turned(sky, turns);
        }
    }
    Image ll = sky_to_latlong(sky, 4 * sky.resolution);
    degrees = turn_latlong(&ll, degrees);  // what the pixels turn by: the sun and mask the same
    if (degrees == 0) return sky;          // a whole turn, or less than a column: no round trip's blur
    SkyImage out = sky;                    // its time, units, source and the rest as they were
    out.rgb = latlong_to_fisheye(ll, sky.resolution).rgb;
    if (sky.sun_direction)
        out.sun_direction = turned_direction(sky.sun_direction->cast<double>(), degrees).cast<float>();
    if (!sky.filled.empty()) {  // nearest: a pixel is filled where the pixel it came from was
        const int n = sky.resolution;
        out.filled.assign(size_t(n) * n, 0);
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const Vec2 uv = fisheye::pixel_center_uv(i, j, n);
                if (uv.squaredNorm() > 1) continue;
                const Vec3d from = turned_direction(fisheye::direction_from_uv(double(uv.x()), double(uv.y())),
                                                    -degrees);
                double x, y;
                fisheye::pixel_from_direction(from, n, &x, &y);
                out.filled[size_t(j) * n + i] = sky.is_filled(std::clamp(int(std::lround(x)), 0, n - 1),
                                                              std::clamp(int(std::lround(y)), 0, n - 1));
            }
    }
    return out;
}

SkyImage load_sky_or_latlong(const std::string& path, std::shared_ptr<SkyImage>* ground,
                             const SkyFileOptions& options) {
    *ground = nullptr;
    int resolution = options.resolution;
    if (resolution != 0) check_sky_resolution(resolution);
    Image image = read_sky_file(path);
    if (!is_latlong_shape(image.width, image.height)) {
        SkyImage sky = sky_from_radiance_file(image, path);  // read once
        if (resolution > 0) sky = resampled_sky(sky, resolution);
        return options.turn_deg != 0 ? turned_about_zenith(sky, options.turn_deg) : sky;
    }
    require_radiance_pixels(image, path);
    if (image.height < 4)
        throw_file_error(path, "lat-long sky is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                                   " pixels: too small to hold a sky (at least 8 x 4)");
    if (resolution == 0 && options.latlong_limit > 0 && image.height > options.latlong_limit)
        resolution = options.latlong_limit;
    // Checked before the turn, so that an error names the file's own pixel.
    if (options.turn_deg != 0) check_latlong_pixels(image, path);
    const double turned = turn_latlong(&image, options.turn_deg);
    LatlongEnvironment env = latlong_environment(image, path, resolution);
    read_sky_metadata(image.metadata, path, &env.sky);  // `sky latlong` keeps the sky's time and sun
    if (env.sky.sun_direction && turned != 0)
        env.sky.sun_direction = turned_direction(env.sky.sun_direction->cast<double>(), turned).cast<float>();
    *ground = std::make_shared<SkyImage>(std::move(env.ground));
    return std::move(env.sky);
}

void check_latlong_pixels(const Image& image, const std::string& path) {
    if (image.channels < 3)
        throw Error(path + ": lat-long environment has " + std::to_string(image.channels) +
                    " channel(s), want R, G and B (a luminance-only Y file has no colour to light with)");
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x)
            for (int c = 0; c < 3; ++c) {
                float v = image.at(x, y, c);
                if (!(v >= 0 && std::isfinite(v)))
                    throw Error(path + ": pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") of the " +
                                (2 * y < image.height ? "sky (upper half)" : "ground (lower half)") + " is " +
                                (std::isnan(v) ? std::string("NaN") : number_text(v, 3)) +
                                ": not a radiance image (radiance is finite and at least 0)");
                // The ground half too: it lights the scene from below (1e30 there rendered as 1e30).
                if (v > kMaxSkyRadiance)
                    throw_file_error(path, "pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") of the " +
                                               (2 * y < image.height ? "sky (upper half)" : "ground (lower half)") +
                                               " is " + number_text(v, 3) +
                                               " W m^-2 sr^-1, above the limit of 1e9 (the sun is about 2e7): a "
                                               "corrupt or mis-scaled environment");
            }
}

LatlongEnvironment latlong_environment(const Image& image, const std::string& path, int resolution) {
    if (!is_latlong_shape(image.width, image.height))
        throw Error(path + ": a lat-long (equirect) environment must be twice as wide as it is high, not " +
                    std::to_string(image.width) + "x" + std::to_string(image.height));
    check_latlong_pixels(image, path);
    const int n = resolution > 0 ? resolution : std::max(16, image.height + (image.height & 1));
    LatlongEnvironment env;
    // A large file takes a while (an 8192 x 4096 HDRI 15 s, 16384 x 8192 90 s on 2 cores): shown.
    std::optional<ProgressBar> progress;
    if (double(image.width) * image.height >= 16e6)
        progress.emplace(4LL * n,
                         "convert " + std::filesystem::path(path).filename().string() + " (lat-long, sky and ground)");
    env.sky = latlong_to_fisheye(image, n, false, progress ? &*progress : nullptr);
    env.ground = latlong_to_fisheye(image, n, true, progress ? &*progress : nullptr);
    if (progress) progress->finish();
    env.sky.source = env.ground.source = "latlong:" + path;
    auto it = image.metadata.numbers.find("dynsky:time");
    if (it != image.metadata.numbers.end()) env.sky.time_seconds = env.ground.time_seconds = it->second;
    validate_sky(env.sky, path + " (its upper half)");
    return env;
}

std::string moving_latlong_note(const std::string& path, int n, bool size_given) {
    return "dynsky: note: " + path + " is a lat-long sky: its upper half moves, as a " + std::to_string(n) + " x " +
           std::to_string(n) + " fisheye" + (size_given ? "" : " (--sky-res: another size)");
}

}  // namespace dynsky
