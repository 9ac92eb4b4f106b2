#include "sky/photo_import.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <new>
#include <optional>
#include <opencv2/imgproc.hpp>
#include <opencv2/xphoto.hpp>
#include <opencv2/photo.hpp>
#include <regex>
#include <sstream>

#include "sky/cloud_mask.h"
#include "sky/fill_seams.h"
#include "sky/fisheye.h"
#include "util/color.h"
#include "util/error.h"
#include "util/parse.h"
#include "util/image.h"

namespace dynsky {

namespace fs = std::filesystem;

namespace {

constexpr double kDeg = kPiD / 180.0;

std::string fmt(double v, int digits = 1) {
    std::ostringstream s;
    s.precision(digits);
    s << std::fixed << v;
    return s.str();
}

// The rotation taking the camera's optical axis to the zenith (the smallest one), as a matrix.
Eigen::Matrix3d world_to_camera(double tilt_deg, double tilt_azimuth_deg) {
    if (tilt_deg == 0) return Eigen::Matrix3d::Identity();
    Vec3d axis = fisheye::direction_from_angles(tilt_deg * kDeg, tilt_azimuth_deg * kDeg);
    return Eigen::Quaterniond::FromTwoVectors(axis, Vec3d::UnitY()).toRotationMatrix();
}

constexpr float kMaxPhotoValue = 1e15f;

// RGB float image (3 channels, RGB order) from any channel count.
cv::Mat to_rgb_mat(const Image& image, const std::string& name) {
    if (image.channels != 1 && image.channels < 3)
        throw_file_error(name, "has " + std::to_string(image.channels) +
                                   " channels; a sky photograph needs 1 (grey) or 3+ (RGB)");
    cv::Mat out(image.height, image.width, CV_32FC3);
    for (int y = 0; y < image.height; ++y) {
        cv::Vec3f* row = out.ptr<cv::Vec3f>(y);
        for (int x = 0; x < image.width; ++x) {
            for (int c = 0; c < 3; ++c) {
                float v = image.at(x, y, image.channels == 1 ? 0 : c);
                if (!std::isfinite(v))
                    throw_file_error(name, "pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") is " +
                                               (std::isnan(v) ? "NaN" : "infinite") +
                                               ": a photograph must hold finite values");
                if (v < 0)
                    throw_file_error(name, "pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                                               ") is negative (" + std::to_string(v) +
                                               "): a photograph cannot hold negative light");
                // Named here, by the photo's own pixel: the sky made from it named a resampled one.
                // (Not 1e9, the sky's limit: a photo in cd/m^2 holds the sun at about 1.6e9.)
                if (v > kMaxPhotoValue)
                    throw_file_error(name, "pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") is " +
                                               number_text(v, 3) +
                                               ", far beyond any light a camera records (above 1e15): a corrupt "
                                               "or mis-scaled photograph");
                row[x][c] = v;
            }
        }
    }
    return out;
}

// 8-bit grey for geometry work: display-encoded values as they are; linear ones normalised by
// their 99th percentile and sRGB-encoded (a crude tone map, enough to see the circle's edge).
cv::Mat display_grey(const cv::Mat& rgb, bool display_referred) {
    cv::Mat grey(rgb.rows, rgb.cols, CV_32F);
    for (int y = 0; y < rgb.rows; ++y)
        for (int x = 0; x < rgb.cols; ++x) {
            const cv::Vec3f& p = rgb.at<cv::Vec3f>(y, x);
            grey.at<float>(y, x) = (p[0] + p[1] + p[2]) / 3.0f;
        }
    if (!display_referred) {
        const float p99 = quantile(std::vector<float>(grey.begin<float>(), grey.end<float>()), 0.99);
        float scale = p99 > 0 ? 1.0f / p99 : 1.0f;
        for (auto it = grey.begin<float>(); it != grey.end<float>(); ++it) *it = linear_to_srgb(*it * scale);
    }
    cv::Mat out;
    grey.convertTo(out, CV_8U, 255.0);
    return out;
}

// An HDR photo as a display-encoded grey Image, for the geometry helpers.
Image tone_mapped_grey(const cv::Mat& rgb_linear) {
    cv::Mat g = display_grey(rgb_linear, false);
    Image enc(g.cols, g.rows, 1);
    for (int y = 0; y < g.rows; ++y)
        for (int x = 0; x < g.cols; ++x) enc.at(x, y, 0) = g.at<unsigned char>(y, x) / 255.0f;
    return enc;
}

cv::Mat image_to_grey8(const Image& image, bool display_referred) {
    return display_grey(to_rgb_mat(image, "image"), display_referred);
}

// The encoded level at which the photo saturates: the highest "plateau" of its per-pixel channel
// maximum (a spike in the histogram, as sensor clipping makes), or 1 if there is none.
// Judged on sky pixels within 0.9 of the radius: burnt-in captions and lamps at the rim are not sky.
double find_clip_level(const cv::Mat& rgb_encoded, const SkyCircle& circle, const cv::Mat& not_sky) {
    std::vector<double> hist(256, 0.0);
    double r2 = 0.81 * circle.radius * circle.radius;
    double total = 0;
    for (int y = 0; y < rgb_encoded.rows; ++y)
        for (int x = 0; x < rgb_encoded.cols; ++x) {
            double dx = x - circle.center_x, dy = y - circle.center_y;
            if (dx * dx + dy * dy > r2 || not_sky.at<unsigned char>(y, x)) continue;
            const cv::Vec3f& p = rgb_encoded.at<cv::Vec3f>(y, x);
            int b = std::clamp(int(std::lround(std::max({p[0], p[1], p[2]}) * 255.0f)), 0, 255);
            hist[b] += 1;
            total += 1;
        }
    // The plateau: the highest bin standing at least 3x above the bins just below it, and not
    // outnumbered by the counts above it (JPEG noise spreads a few values past the clip level).
    double min_count = std::max(20.0, 2e-4 * total);
    double above = 0;
    for (int b = 255; b >= 64; above += hist[b], --b) {
        if (hist[b] < min_count || above > hist[b]) continue;
        double below = 0;
        for (int k = b - 8; k <= b - 3; ++k) below += hist[k];
        if (hist[b] >= 3 * (below / 6 + 1)) return (b - 2) / 255.0;
    }
    return 1.0;
}

void inpaint_texture(cv::Mat& rgb, const cv::Mat& fill);  // below

// The image and its fill mask at `work` px when they are larger (area-averaged: a pixel any of
// whose area is filled counts as filled); false, and the two as they are, otherwise.
bool reduce_for_fill(const cv::Mat& rgb, const cv::Mat& fill, int work, cv::Mat* src, cv::Mat* mask) {
    *src = rgb, *mask = fill;
    if (rgb.cols <= work) return false;
    cv::resize(rgb, *src, cv::Size(work, work), 0, 0, cv::INTER_AREA);
    cv::Mat m;
    fill.convertTo(m, CV_32F);
    cv::resize(m, m, cv::Size(work, work), 0, 0, cv::INTER_AREA);
    *mask = m > 0.01f;
    return true;
}

// The 99th percentile of a one-channel float image over its known pixels (mask 0); 0 when none.
float known_percentile99(const cv::Mat& channel, const cv::Mat& mask) {
    std::vector<float> known;
    for (int y = 0; y < channel.rows; ++y)
        for (int x = 0; x < channel.cols; ++x)
            if (!mask.at<unsigned char>(y, x)) known.push_back(channel.at<float>(y, x));
    if (known.empty()) return 0.0f;
    const size_t q = size_t(0.99 * (known.size() - 1));
    std::nth_element(known.begin(), known.begin() + q, known.end());
    return known[q];
}

// Obstructions along the horizon (rooftops, railings, trees: a fifth of a Mobotix disc) filled by
// inpainting came out as radial streaks of whatever lay at their inner edge, green-grey spokes
// around every imported sky (looked at). Beyond the outermost seen sky of each azimuth, and beyond
// kBandMinRadius, the fill is instead the mean colour of the seen sky just inside that
// edge, smoothed over azimuth (sigma kBandSmoothingDeg; azimuths with no seen sky near the horizon
// take their neighbours'): a haze band, no streaks. Holes inside the seen sky (masts, an arm, a
// shadow band's inner part) are inpainted as before, these pixels now known around them. Returns
// the mask of what is left to inpaint.
constexpr double kBandMinRadius = 0.75;  // zenith 67.5 degrees: the band fill stays near the horizon
constexpr double kBandEdgeWidth = 0.06;  // x the radius: the seen ring whose mean colour fills
constexpr double kBandSmoothingDeg = 6.0;
constexpr double kBandSeamWidth = 0.015;  // x the radius: inpainted between the seen sky and the band
constexpr int kBandBins = 360;
constexpr double kRingMaxSeenRadius = 0.97;  // the median azimuth's seen sky ends below this: a ring

cv::Mat fill_horizon_band(cv::Mat& rgb, const cv::Mat& fill) {
    const int n = rgb.cols;
    const double c = (n - 1) / 2.0, half = n / 2.0;
    auto radius = [&](int x, int y) { return std::hypot(x - c, y - c) / half; };
    // Each pixel's azimuth bin, once (the atan2 is most of the passes' cost); -1 nearer the zenith
    // than any pass below looks (a bin's outermost seen sky only matters beyond kInner).
    const double kInner = kBandMinRadius - 2 * kBandEdgeWidth;
    cv::Mat bins(n, n, CV_16S);
    tbb::parallel_for(0, n, [&](int y) {
        for (int x = 0; x < n; ++x) {
            const double a = std::atan2(double(y) - c, double(x) - c);  // any fixed origin: bins only
            bins.at<short>(y, x) = radius(x, y) < kInner
                                       ? short(-1)
                                       : short(std::min(kBandBins - 1, int((a + kPiD) / (2 * kPiD) * kBandBins)));
        }
    });
    // The outermost seen sky of each azimuth (beyond kInner; 0 where none).
    std::vector<double> r_seen(kBandBins, 0.0);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const int b = bins.at<short>(y, x);
            const double r = radius(x, y);
            if (b >= 0 && r <= 1 && !fill.at<unsigned char>(y, x)) r_seen[size_t(b)] = std::max(r_seen[size_t(b)], r);
        }
    // Only a ring (the seen sky stops short of the horizon at most azimuths, as behind a rooftop
    // railing): an obstruction at a few azimuths (a TSI's arm and band) is inpainted as before.
    {
        std::vector<double> sorted = r_seen;
        std::nth_element(sorted.begin(), sorted.begin() + kBandBins / 2, sorted.end());
        if (sorted[kBandBins / 2] > kRingMaxSeenRadius) return fill.clone();
    }
    // The mean colour of the seen ring just inside it (near the horizon only).
    std::vector<cv::Vec3d> sum(kBandBins, cv::Vec3d(0, 0, 0));
    std::vector<double> count(kBandBins, 0.0);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const int b = bins.at<short>(y, x);
            if (b < 0 || fill.at<unsigned char>(y, x)) continue;
            const double r = radius(x, y);
            if (r > 1 || r < r_seen[size_t(b)] - kBandEdgeWidth) continue;
            const cv::Vec3f& v = rgb.at<cv::Vec3f>(y, x);
            sum[size_t(b)] += cv::Vec3d(v[0], v[1], v[2]), count[size_t(b)] += 1;
        }
    // Smoothed over azimuth by normalised convolution: empty bins take their neighbours'; wider
    // until every bin has some (a hidden half horizon), else nothing is band-filled.
    std::vector<cv::Vec3f> edge(kBandBins);
    for (double sigma_deg = kBandSmoothingDeg;; sigma_deg *= 3) {
        const double sigma = sigma_deg / 360.0 * kBandBins;
        const int reach = std::min(kBandBins / 2, int(std::ceil(3 * sigma)));
        bool all = true;
        for (int b = 0; b < kBandBins; ++b) {
            cv::Vec3d s(0, 0, 0);
            double w_sum = 0;
            for (int k = -reach; k <= reach; ++k) {
                const size_t i = size_t(((b + k) % kBandBins + kBandBins) % kBandBins);
                const double w = std::exp(-0.5 * k * k / (sigma * sigma));
                s += w * sum[i], w_sum += w * count[i];
            }
            if (!(w_sum > 0)) {
                all = false;
                break;
            }
            edge[size_t(b)] = cv::Vec3f(float(s[0] / w_sum), float(s[1] / w_sum), float(s[2] / w_sum));
        }
        if (all) break;
        if (reach >= kBandBins / 2) return fill.clone();  // no seen sky near the horizon at all
    }
    cv::Mat rest = fill.clone();
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const int b = bins.at<short>(y, x);
            if (b < 0 || !fill.at<unsigned char>(y, x)) continue;
            const double r = radius(x, y);
            if (r < kBandMinRadius || r < r_seen[size_t(b)]) continue;
            rgb.at<cv::Vec3f>(y, x) = edge[size_t(b)];
            rest.at<unsigned char>(y, x) = 0;
        }
    // A seam of a few pixels along the seen sky is left to the inpainting, which blends the two.
    const int seam = std::max(1, int(std::lround(kBandSeamWidth * half)));
    cv::Mat seen_near;
    cv::dilate(~fill, seen_near, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * seam + 1, 2 * seam + 1)));
    rest |= fill & seen_near;
    return rest;
}

// Telea's fast-marching inpainting of a 3-channel float image where fill != 0, in place
// (FillMethod::Texture: inpaint_texture instead).
// cv::inpaint takes float only one channel at a time, and its Telea path misbehaves on small
// values (OpenCV 4.6 fills a 0.2-0.4 ramp with 1.0 and -0.3): each channel is scaled so its 99th
// percentile is 255 first. Above 512 px the fill is computed at 512 and upsampled: inpainting is
// smooth anyway, and its cost grows with the filled area (seconds at 2048^2).
void inpaint_float(cv::Mat& rgb, const cv::Mat& fill_in, PhotoImportParams::FillMethod method) {
    if (method == PhotoImportParams::FillMethod::Texture) return inpaint_texture(rgb, fill_in);
    const cv::Mat fill = fill_horizon_band(rgb, fill_in);
    if (cv::countNonZero(fill) == 0) return;
    cv::Mat src, mask;
    const bool reduced = reduce_for_fill(rgb, fill, 512, &src, &mask);
    std::vector<cv::Mat> ch(3);
    cv::split(src, ch);
    tbb::parallel_for(0, 3, [&](int k) {
        const float top = known_percentile99(ch[k], mask), scale = top > 0 ? 255.0f / top : 1.0f;
        cv::Mat filled;
        cv::inpaint(ch[k] * scale, mask, filled, 3.0, cv::INPAINT_TELEA);
        ch[k] = cv::max(filled / scale, 0.0f);
    });
    cv::Mat result;
    cv::merge(ch, result);
    if (reduced) cv::resize(result, result, rgb.size(), 0, 0, cv::INTER_LINEAR);
    result.copyTo(rgb, fill);
}

// The shift-map fill (cv::xphoto::inpaint, INPAINT_SHIFTMAP) of the filled pixels inside
// kTextureFillRadius of the horizon: each copies a known pixel at an offset chosen by a graph cut, so
// a band across the sky gets the sky's own clouds and blue and its edges are seams of real texture.
// Only regions at least 4 % of the radius wide; thin ones and those near the horizon keep the
// smooth fill. Near the horizon: there the known pixels are few and dark (housings, roofs,
// the rim), and copied they made jagged dark arcs on two cameras (looked at). Judged and copied in
// CIELAB of the linear values over the seen pixels' 99th percentile, clipped at 4 (a sun copied into
// the band would come back no brighter than that), at most kTextureFillWork px (upsampled beyond:
// the cost grows with the image and the filled area).
constexpr double kTextureFillRadius = 0.92;
constexpr int kTextureFillWork = 384;
constexpr double kTextureFillMinWidth = 0.02;  // x the radius, half the width of the narrowest region

void inpaint_texture(cv::Mat& rgb, const cv::Mat& fill) {
    inpaint_float(rgb, fill, PhotoImportParams::FillMethod::Smooth);  // the horizon's, and the sources' start
    cv::Mat src, f;
    const bool reduced = reduce_for_fill(rgb, fill, kTextureFillWork, &src, &f);
    const int work = src.cols;
    cv::Mat interior = cv::Mat::zeros(work, work, CV_8U);
    const double c = (work - 1) / 2.0, r_max = kTextureFillRadius * work / 2.0;
    for (int y = 0; y < work; ++y)
        for (int x = 0; x < work; ++x)
            if (f.at<unsigned char>(y, x) && std::hypot(x - c, y - c) < r_max) interior.at<unsigned char>(y, x) = 255;
    // Only wide regions (the band, an arm): a thin object's gap (a mast, a wire) is filled well
    // smoothly, and the same from frame to frame, so that sequences imported one by one measure no
    // motion there.
    const int half = std::max(2, int(std::lround(kTextureFillMinWidth * work / 2.0)));
    const cv::Mat round = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * half + 1, 2 * half + 1));
    cv::Mat wide;
    cv::morphologyEx(interior, wide, cv::MORPH_OPEN, round);
    cv::dilate(wide, wide, round);
    interior &= wide;
    if (cv::countNonZero(interior) == 0) return;
    std::vector<cv::Mat> ch;
    cv::split(src, ch);
    const float top = known_percentile99(cv::max(cv::max(ch[0], ch[1]), ch[2]), f), scale = top > 0 ? 1.0f / top : 1.0f;
    cv::Mat lab, filled;
    cv::min(src * scale, 4.0f, lab);
    cv::cvtColor(lab, lab, cv::COLOR_LRGB2Lab);
    cv::xphoto::inpaint(lab, ~interior, filled, cv::xphoto::INPAINT_SHIFTMAP);
    // Copied from elsewhere, the texture keeps its source's level: re-levelled to meet the sky
    // around the region with no step (sky/fill_seams.h). The shift map also changes known pixels
    // next to the region (OpenCV 4.6: by up to a tenth of L), which are not copied back: the level
    // to meet is theirs as they were.
    lab.copyTo(filled, ~interior);
    remove_fill_seams(&filled, interior);
    cv::cvtColor(filled, filled, cv::COLOR_Lab2LRGB);
    filled = cv::max(filled / scale, 0.0f);
    cv::Mat where = interior;
    if (reduced) {
        cv::resize(filled, filled, rgb.size(), 0, 0, cv::INTER_LINEAR);
        cv::resize(interior, where, rgb.size(), 0, 0, cv::INTER_NEAREST);
        where &= fill;
    }
    filled.copyTo(rgb, where);
}

}  // namespace

float ImportedPhoto::encoded(float linear) const {
    return encoding_gamma > 0 ? std::pow(std::clamp(linear, 0.0f, 1.0f), 1.0f / encoding_gamma)
                              : linear_to_srgb(linear);
}

std::optional<float> header_gamma(const Image& photo) {
    const auto space = photo.metadata.strings.find("oiio:ColorSpace");
    if (space == photo.metadata.strings.end() || space->second.rfind("Gamma", 0) != 0) return std::nullopt;
    const std::string digits = space->second.substr(5);
    char* end = nullptr;
    const double gamma = std::strtod(digits.c_str(), &end);
    if (end == digits.c_str() || *end != '\0' || !(gamma > 0.05 && gamma < 20)) return std::nullopt;
    return float(gamma);
}

bool is_display_encoded(const Image& photo, const std::string& path, const std::string& encoding) {
    if (encoding == "srgb") return true;
    if (encoding == "linear") return false;
    if (encoding != "auto") throw Error("unknown input encoding '" + encoding + "' (use auto, srgb or linear)");
    if (photo.has_float_file_pixels()) return false;
    if (!photo.file_pixel_type.empty()) {
        auto it = photo.metadata.strings.find("oiio:ColorSpace");
        std::string space = it == photo.metadata.strings.end() ? "" : it->second;
        std::transform(space.begin(), space.end(), space.begin(), [](unsigned char c) { return std::tolower(c); });
        return space.find("linear") == std::string::npos && space.rfind("lin_", 0) != 0;
    }
    std::string ext = file_extension(path);
    return !(ext == ".exr" || ext == ".hdr" || ext == ".pfm" || ext == ".tif" || ext == ".tiff");
}

LensLaw parse_lens_law(const std::string& name) {
    if (name == "equidistant") return LensLaw::Equidistant;
    if (name == "equisolid") return LensLaw::Equisolid;
    if (name == "orthographic") return LensLaw::Orthographic;
    if (name == "stereographic") return LensLaw::Stereographic;
    throw Error("unknown lens law '" + name + "' (use equidistant, equisolid, orthographic or stereographic)");
}

const char* lens_law_name(LensLaw law) {
    switch (law) {
        case LensLaw::Equidistant: return "equidistant";
        case LensLaw::Equisolid: return "equisolid";
        case LensLaw::Orthographic: return "orthographic";
        case LensLaw::Stereographic: return "stereographic";
    }
    return "?";
}

double lens_radius(LensLaw law, double theta) {
    switch (law) {
        case LensLaw::Equidistant: return theta / (kPiD / 2);
        case LensLaw::Equisolid: return std::sqrt(2.0) * std::sin(theta / 2);
        case LensLaw::Orthographic: return std::sin(std::min(theta, kPiD / 2));
        case LensLaw::Stereographic: return std::tan(theta / 2);
    }
    return 0;
}

double lens_angle(LensLaw law, double r) {
    switch (law) {
        case LensLaw::Equidistant: return r * (kPiD / 2);
        case LensLaw::Equisolid: return 2 * std::asin(std::min(1.0, r / std::sqrt(2.0)));
        case LensLaw::Orthographic: return std::asin(std::min(1.0, r));
        case LensLaw::Stereographic: return 2 * std::atan(r);
    }
    return 0;
}

bool PhotoGeometry::project(const Vec3d& direction, double* x, double* y) const {
    Vec3d v = world_to_camera(tilt_deg, tilt_azimuth_deg) * direction.normalized();
    double theta = std::acos(std::clamp(v.y(), -1.0, 1.0));
    if (theta > kPiD / 2 + 1e-9) return false;
    double phi = std::atan2(v.x(), -v.z());
    double r = circle.radius * lens_radius(lens, theta);
    double psi = north_deg * kDeg + (mirrored ? phi : -phi);
    *x = circle.center_x + r * std::sin(psi);
    *y = circle.center_y - r * std::cos(psi);
    return true;
}

bool PhotoGeometry::unproject(double x, double y, Vec3d* direction) const {
    double dx = x - circle.center_x, dy = y - circle.center_y;
    double r = std::sqrt(dx * dx + dy * dy) / circle.radius;
    if (r > 1.0) return false;
    double theta = lens_angle(lens, r);
    double psi = std::atan2(dx, -dy);
    double phi = mirrored ? psi - north_deg * kDeg : north_deg * kDeg - psi;
    Vec3d v = fisheye::direction_from_angles(theta, phi);
    *direction = world_to_camera(tilt_deg, tilt_azimuth_deg).transpose() * v;
    return true;
}

namespace {

// The ellipse of an outline's rim points, when they lie on one closely (median distance under
// 0.5 % of its size + 0.5 px), it is no circle (axes over 1 % apart), and it has the lens's size
// (half-axes in [r_min, r_max]) and centre (inside the cols x rows photograph: a small lit blob is
// not one). An uneven resize stretches along the image's axes: the ellipse with its axes there
// (least squares on x^2 + B y^2 + D x + E y + F = 0) is taken if it fits nearly as well (a 3 %
// ellipse's own angle is poorly determined: 12 degrees for one), angle 0.
std::optional<cv::RotatedRect> lens_ellipse(const std::vector<cv::Point2f>& points, double r_min, double r_max,
                                            int cols, int rows) {
    if (points.size() < 20) return std::nullopt;
    // The median distance of the points from an ellipse (centre, half-axes, angle).
    auto median_off = [&](cv::Point2d c, double a, double b, double t) {
        std::vector<double> off;
        for (const cv::Point2f& p : points) {
            const double dx = p.x - c.x, dy = p.y - c.y;
            const double u = dx * std::cos(t) + dy * std::sin(t), v = -dx * std::sin(t) + dy * std::cos(t);
            off.push_back(std::abs(std::hypot(u / a, v / b) - 1) * (a + b) / 2);
        }
        return quantile(off, 0.5);
    };
    const cv::RotatedRect e = cv::fitEllipse(points);
    double a = e.size.width / 2.0, b = e.size.height / 2.0;
    const double off = median_off(e.center, a, b, e.angle * kPiD / 180);
    Eigen::MatrixXd m(points.size(), 4);
    Eigen::VectorXd rhs(points.size());
    for (size_t i = 0; i < points.size(); ++i) {
        const double x = points[i].x, y = points[i].y;
        m(Eigen::Index(i), 0) = y * y, m(Eigen::Index(i), 1) = x, m(Eigen::Index(i), 2) = y;
        m(Eigen::Index(i), 3) = 1, rhs(Eigen::Index(i)) = -x * x;
    }
    const Eigen::Vector4d q = m.colPivHouseholderQr().solve(rhs);
    cv::RotatedRect fitted = e;
    if (q(0) > 0) {
        const cv::Point2d c(-q(1) / 2, -q(2) / (2 * q(0)));
        const double a2 = c.x * c.x + q(0) * c.y * c.y - q(3);
        if (a2 > 0) {
            const double aa = std::sqrt(a2), bb = std::sqrt(a2 / q(0));
            if (median_off(c, aa, bb, 0) <= std::max(1.25 * off, off + 0.5)) {
                fitted = cv::RotatedRect(cv::Point2f(float(c.x), float(c.y)), cv::Size2f(float(2 * aa), float(2 * bb)),
                                         0.0f);
                a = aa, b = bb;
            }
        }
    }
    const double ratio = std::max(a, b) / std::max(1e-9, std::min(a, b));
    const bool lens_sized = std::min(a, b) >= r_min && std::max(a, b) <= r_max && fitted.center.x >= 0 &&
                            fitted.center.y >= 0 && fitted.center.x <= cols - 1 && fitted.center.y <= rows - 1;
    if (ratio > 1.01 && lens_sized && off < 0.005 * (a + b) / 2 + 0.5) return fitted;
    return std::nullopt;
}

// A fisheye's lens circle on a black surround (the Mobotix, most all-sky cameras): the outline of
// everything lit, fitted with a circle that ignores what is not the rim. None when the corners are
// not black or no circle fits well; an outline that is an ellipse instead (a photograph scaled
// unevenly) is given in *ellipse.
// p99: the level's 99th percentile.
std::optional<SkyCircle> find_lens_circle_on_black(const cv::Mat& level, double p99, double r_min, double r_max,
                                                   std::optional<cv::RotatedRect>* ellipse) {
    int cw = std::max(1, level.cols / 12), ch = std::max(1, level.rows / 12);
    // The surround's level: that of the three darkest corners (a lens circle cut by the frame on
    // two sides lights the fourth; it went to the Hough search, which found it 15 % too small).
    std::vector<double> corners;
    for (cv::Rect r : {cv::Rect(0, 0, cw, ch), cv::Rect(level.cols - cw, 0, cw, ch),
                       cv::Rect(0, level.rows - ch, cw, ch), cv::Rect(level.cols - cw, level.rows - ch, cw, ch)}) {
        cv::Mat patch = level(r).clone();
        corners.push_back(double(quantile(std::vector<float>(patch.begin<float>(), patch.end<float>()), 0.75)));
    }
    std::sort(corners.begin(), corners.end());
    const double corner = corners[2];
    if (!(p99 >= 8 && corner <= std::max(2.0, 0.03 * p99))) return std::nullopt;

    // Any light at all is inside the lens first; failing that (a JPEG's ringing beyond a bright rim
    // lit the surround up to 16 levels, 8 px out, and the outline fitted no circle), light above a
    // tenth of the photo's bright level.
    auto fit = [&](double threshold) -> std::optional<SkyCircle> {
        // Any light at all is inside the lens: the dark ground and rooftops at its rim (green at 1 of
        // 255, red and blue 0, on a morning photograph) count, or the outline shrinks to the sky's and
        // moves from frame to frame with the light (the Mobotix morning: radius 428-449 px against 486
        // at noon). `level` is each pixel's brightest channel; an opening drops JPEG's stray single
        // levels in the surround, and pieces under 16 pixels are noise.
        cv::Mat lit = level > threshold, labels, stats, centroids;
        cv::morphologyEx(lit, lit, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_CROSS, cv::Size(3, 3)));
        int n = cv::connectedComponentsWithStats(lit, labels, stats, centroids, 8, CV_32S);
        int largest = 0;
        for (int i = 1; i < n; ++i)
            if (largest == 0 || stats.at<int>(i, cv::CC_STAT_AREA) > stats.at<int>(largest, cv::CC_STAT_AREA))
                largest = i;
        if (largest == 0 || stats.at<int>(largest, cv::CC_STAT_AREA) < 64) return std::optional<SkyCircle>();
        std::vector<char> kept(n, 0);
        for (int i = 1; i < n; ++i) kept[i] = stats.at<int>(i, cv::CC_STAT_AREA) >= 16;

        // The rim: per direction from the centre, the farthest lit pixel. Burnt-in captions beyond the
        // circle, dark objects denting it and the frame cutting it (a lens circle taller than the
        // sensor) give directions that are not the rim: the fit leaves them out (below).
        double cx = centroids.at<double>(largest, 0), cy = centroids.at<double>(largest, 1);
        double r = std::sqrt(stats.at<int>(largest, cv::CC_STAT_AREA) / kPiD);
        constexpr int kDirections = 720;
        for (int pass = 0; pass < 2; ++pass) {
            std::vector<double> far(kDirections, -1.0);
            std::vector<cv::Point2d> far_px(kDirections);
            for (int y = 0; y < lit.rows; ++y)
                for (int x = 0; x < lit.cols; ++x) {
                    if (!kept[labels.at<int>(y, x)]) continue;
                    // Only the outline can be farthest in its direction.
                    if (x > 0 && y > 0 && x + 1 < lit.cols && y + 1 < lit.rows && lit.at<unsigned char>(y, x - 1) &&
                        lit.at<unsigned char>(y, x + 1) && lit.at<unsigned char>(y - 1, x) &&
                        lit.at<unsigned char>(y + 1, x))
                        continue;
                    double dx = x - cx, dy = y - cy, d = std::hypot(dx, dy);
                    int k = std::clamp(int((std::atan2(dy, dx) + kPiD) / (2 * kPiD) * kDirections), 0, kDirections - 1);
                    if (d > far[k]) far[k] = d, far_px[k] = cv::Point2d(x, y);
                }
            std::vector<cv::Point2d> rim;
            for (int k = 0; k < kDirections; ++k) {
                const cv::Point2d& p = far_px[k];
                if (far[k] < 0 || p.x < 1 || p.y < 1 || p.x > lit.cols - 2 || p.y > lit.rows - 2) continue;
                rim.push_back(p);
            }
            if (rim.size() < kDirections / 4) return std::optional<SkyCircle>();
            // Least squares on x^2 + y^2 + D x + E y + F = 0, refitted on the points within a robust
            // band of the last fit (median residual +- 3 MAD, at least 1.5 px): outliers go both ways.
            std::vector<char> in(rim.size(), 1);
            double rms = 0;
            size_t inliers = rim.size();
            for (int iter = 0; iter < 6; ++iter) {
                Eigen::MatrixXd a(inliers, 3);
                Eigen::VectorXd b(inliers);
                for (size_t i = 0, row = 0; i < rim.size(); ++i)
                    if (in[i]) {
                        a(row, 0) = rim[i].x, a(row, 1) = rim[i].y, a(row, 2) = 1;
                        b(row++) = -(rim[i].x * rim[i].x + rim[i].y * rim[i].y);
                    }
                Eigen::Vector3d d = a.colPivHouseholderQr().solve(b);
                cx = -d(0) / 2, cy = -d(1) / 2;
                double r2 = cx * cx + cy * cy - d(2);
                if (!(r2 > 0)) return std::optional<SkyCircle>();
                r = std::sqrt(r2);
                std::vector<double> res(rim.size());
                for (size_t i = 0; i < rim.size(); ++i) res[i] = std::hypot(rim[i].x - cx, rim[i].y - cy) - r;
                std::vector<double> sorted = res;
                double med = quantile(sorted, 0.5);
                for (double& v : sorted) v = std::abs(v - med);
                double band = std::max(1.5, 3 * 1.4826 * quantile(sorted, 0.5));
                inliers = 0, rms = 0;
                for (size_t i = 0; i < rim.size(); ++i) {
                    in[i] = std::abs(res[i] - med) <= band;
                    if (in[i]) ++inliers, rms += res[i] * res[i];
                }
                if (inliers < 5) return std::optional<SkyCircle>();
                rms = std::sqrt(rms / inliers);
            }
            // A lens circle: most directions on one circle, closely. A lit shape that is not one
            // (a letterboxed picture, a lamp) fails here and goes to the Hough search.
            if (inliers * 2 < rim.size() || rms > 0.01 * r + 0.5) {
                // Unless the outline is an ellipse, closely: the photograph was scaled unevenly (a
                // 1280 x 960 frame resized to 1001 x 777: the Hough search then found a circle 10 %
                // inside the lens). (The outline of any light, the first fit's, is the lens's: kept
                // over the second's.)
                if (inliers * 2 >= rim.size() && !*ellipse) {
                    std::vector<cv::Point2f> points;
                    for (size_t i = 0; i < rim.size(); ++i)
                        if (in[i]) points.emplace_back(float(rim[i].x), float(rim[i].y));
                    *ellipse = lens_ellipse(points, r_min, r_max, level.cols, level.rows);
                }
                return std::optional<SkyCircle>();
            }
        }
        if (r < r_min || r > r_max) return std::optional<SkyCircle>();
        return SkyCircle{cx, cy, r};
    };
    if (std::optional<SkyCircle> c = fit(corner + 0.5)) return c;
    return fit(corner + std::max(2.0, 0.1 * p99));
}

}  // namespace

SkyCircle find_sky_circle(const Image& photo, const std::string& name, double min_fraction, double max_fraction,
                          std::string* caution) {
    if (caution) caution->clear();
    if (!(min_fraction > 0 && max_fraction > min_fraction))
        throw Error("sky circle search: the radius range must satisfy 0 < min < max (got " + fmt(min_fraction, 3) +
                    ", " + fmt(max_fraction, 3) + ")");
    // The search scales the photo to 400 pixels: a sliver (a side under 16 pixels, or one 8 times
    // the other) would become an empty image, on which OpenCV asserts.
    if (photo.width < kMinPhotoSide || photo.height < kMinPhotoSide ||
        std::max(photo.width, photo.height) > 8 * std::min(photo.width, photo.height))
        throw_file_error(name, "the photograph is " + std::to_string(photo.width) + " x " +
                                   std::to_string(photo.height) +
                                   " pixels: no sky circle can be searched for in it (each side at least 16, "
                                   "at most 8 times the other); give --center and --radius");
    cv::Mat grey = image_to_grey8(photo, true);
    int shorter_side = std::min(photo.width, photo.height);
    // The lit region's outline is the lens circle itself, so its radius may lie further out of the
    // Hough search's range (which guards against edges inside the sky): half its smallest to 1.4
    // times its largest radius.
    cv::Mat level(photo.height, photo.width, CV_32F);
    for (int y = 0; y < photo.height; ++y)
        for (int x = 0; x < photo.width; ++x) {
            float brightest = 0;
            for (int c = 0; c < std::min(photo.channels, 3); ++c) brightest = std::max(brightest, photo.at(x, y, c));
            level.at<float>(y, x) = 255.0f * brightest;
        }
    // (A frame darker than 8 of 255 here shows no lens outline: the Hough search below then finds
    // the sky's edges, inside it.)
    const double level_p99 = quantile(std::vector<float>(level.begin<float>(), level.end<float>()), 0.99);
    std::optional<cv::RotatedRect> ellipse;
    if (std::optional<SkyCircle> lens = find_lens_circle_on_black(level, level_p99, 0.5 * min_fraction * shorter_side,
                                                                  1.4 * max_fraction * shorter_side, &ellipse))
        return *lens;
    if (ellipse) {
        // The largest circle inside it (the sky beyond along its long axis left out), and the
        // height that would make it round. The Hough search below found one 10 % inside the lens.
        const double a = ellipse->size.width / 2.0, b = ellipse->size.height / 2.0, t = ellipse->angle * kPiD / 180;
        const double half_w = std::hypot(a * std::cos(t), b * std::sin(t));
        const double half_h = std::hypot(a * std::sin(t), b * std::cos(t));
        const int square_h = int(std::lround(photo.height * half_w / half_h));
        const SkyCircle c{ellipse->center.x, ellipse->center.y, std::min(a, b)};
        // An uneven resize stretches along the image's axes (the fit above), a tilted ellipse is the lens's own.
        const bool along_axes = ellipse->angle == 0.0f;
        if (caution)
            *caution = "the lens's outline is an ellipse, not a circle (" + fmt(2 * half_w, 0) + " x " +
                       fmt(2 * half_h, 0) + " px about (" + fmt(ellipse->center.x, 0) + ", " +
                       fmt(ellipse->center.y, 0) + (along_axes ? "" : ", tilted " + fmt(ellipse->angle, 0) + " deg") +
                       "); the largest circle inside it is used, so the sky is " +
                       fmt(100 * (std::max(a, b) / std::min(a, b) - 1), 0) + " % stretched along one axis. " +
                       (along_axes ? "The photograph's pixels are not square (scaled unevenly?): for an exact import "
                                     "scale it to square pixels first (" +
                                         std::to_string(photo.width) + " x " + std::to_string(square_h) +
                                         ", e.g. oiiotool IN --resize " + std::to_string(photo.width) + "x" +
                                         std::to_string(square_h) + " -o OUT)"
                                   : std::string("Tilted, it is not a resize: the lens or sensor itself"));
        return c;
    }
    double scale = std::min(1.0, 400.0 / std::max(grey.cols, grey.rows));
    cv::Mat small;
    cv::resize(grey, small, cv::Size(), scale, scale, cv::INTER_AREA);
    // Stretch so the 99th percentile is white: dark exposures (the Mobotix) get the same edge
    // contrast as bright ones.
    {
        const unsigned char p99 = quantile(std::vector<unsigned char>(small.begin<unsigned char>(),
                                                                      small.end<unsigned char>()),
                                           0.99);
        if (p99 > 0) small.convertTo(small, CV_8U, 255.0 / p99);
    }
    cv::GaussianBlur(small, small, cv::Size(0, 0), 2.0);
    int shorter = std::min(photo.width, photo.height);
    int min_r = int(std::floor(min_fraction * shorter * scale)), max_r = int(std::ceil(max_fraction * shorter * scale));
    std::vector<cv::Vec3f> circles;
    // Canny high threshold 60 and 20 votes at this scale: the sky's rim is the image's strongest
    // circular edge for every camera we have; a smooth or uniform picture gives no candidate.
    cv::HoughCircles(small, circles, cv::HOUGH_GRADIENT, 1, std::min(small.cols, small.rows), 60, 20,
                     std::max(1, min_r), std::max(2, max_r));
    if (circles.empty())
        throw_file_error(name, "no sky circle found (looked for a circle of radius " + fmt(min_fraction * shorter, 0) +
                                   "-" + fmt(max_fraction * shorter, 0) +
                                   " px); give its centre and radius (--center X,Y --radius R)");
    SkyCircle c;
    c.center_x = (circles[0][0] + 0.5) / scale - 0.5;
    c.center_y = (circles[0][1] + 0.5) / scale - 0.5;
    c.radius = circles[0][2] / scale;
    if (level_p99 < 8 && caution)
        *caution = "the photograph is dark (99 % of it at most " + fmt(level_p99, 0) +
                   " of 255): its sky circle was found from the sky's edges, which on a dark frame lie inside "
                   "the lens, and may be too small; check it (--preview), give --center X,Y --radius R, or "
                   "import the frame with its sequence (one circle for all)";
    if (c.center_x < 0 || c.center_y < 0 || c.center_x > photo.width - 1 || c.center_y > photo.height - 1)
        throw_file_error(name, "the circle found lies outside the photograph: give --center and --radius");
    return c;
}

std::vector<unsigned char> load_not_sky_mask(const std::string& path, MaskLayout layout, int photo_width,
                                             int photo_height) {
    Image mask = read_image(path);
    apply_orientation(mask);  // as the photograph is turned: a mask is seen as the viewer shows it
    std::vector<unsigned char> out(size_t(photo_width) * photo_height, 0);
    auto value = [&](int x, int y, int c) { return mask.at(x, y, std::min(c, mask.channels - 1)); };
    if (layout == MaskLayout::PhotoBlackIsNotSky || layout == MaskLayout::TsiCloudMask) {
        if (mask.width != photo_width || mask.height != photo_height)
            throw_file_error(path, "mask is " + std::to_string(mask.width) + "x" + std::to_string(mask.height) +
                                       " but the photograph is " + std::to_string(photo_width) + "x" +
                                       std::to_string(photo_height) + ": a mask must have the photo's size");
        int nc = std::min(mask.channels, 3);
        for (int y = 0; y < photo_height; ++y)
            for (int x = 0; x < photo_width; ++x) {
                bool black = true;
                for (int c = 0; c < nc; ++c) black = black && value(x, y, c) <= 0.5f / 255.0f;
                out[size_t(y) * photo_width + x] = black ? 1 : 0;
            }
        if (layout == MaskLayout::TsiCloudMask) {
            // The TSI draws its sun marker (a yellow, sometimes white, disc) on the band: small
            // islands of "sky" inside the obstructions are such markers, not sky; yellow never is.
            cv::Mat open_sky(photo_height, photo_width, CV_8U);
            for (int y = 0; y < photo_height; ++y)
                for (int x = 0; x < photo_width; ++x) {
                    bool yellow = value(x, y, 0) > 0.9f && value(x, y, 1) > 0.9f && value(x, y, 2) < 0.1f;
                    if (yellow) out[size_t(y) * photo_width + x] = 1;
                    open_sky.at<unsigned char>(y, x) = out[size_t(y) * photo_width + x] ? 0 : 255;
                }
            cv::Mat labels, stats, centroids;
            cv::connectedComponentsWithStats(open_sky, labels, stats, centroids, 4);
            double island = 0.01 * cv::countNonZero(open_sky);
            for (int y = 0; y < photo_height; ++y)
                for (int x = 0; x < photo_width; ++x) {
                    int l = labels.at<int>(y, x);
                    if (l > 0 && stats.at<int>(l, cv::CC_STAT_AREA) < island) out[size_t(y) * photo_width + x] = 1;
                }
            cv::Mat sky(photo_height, photo_width, CV_8U);
            for (int y = 0; y < photo_height; ++y)
                for (int x = 0; x < photo_width; ++x)
                    sky.at<unsigned char>(y, x) = out[size_t(y) * photo_width + x] ? 0 : 255;
            std::vector<cv::Point> points;
            cv::findNonZero(sky, points);
            if (points.empty()) throw_file_error(path, "the TSI mask marks no pixel as sky");
            // The hull first: minEnclosingCircle on ~10^5 raw points takes seconds in OpenCV 4.6.
            std::vector<cv::Point> hull;
            cv::convexHull(points, hull);
            cv::Point2f c;
            float r;
            cv::minEnclosingCircle(hull, c, r);
            std::vector<unsigned char> inside = out;
            double reach = r - 2.0;
            for (int y = 0; y < photo_height; ++y)
                for (int x = 0; x < photo_width; ++x) {
                    double dx = x - c.x, dy = y - c.y, d = std::sqrt(dx * dx + dy * dy);
                    if (d <= reach) continue;
                    int sx = std::clamp(int(std::lround(c.x + dx / d * reach)), 0, photo_width - 1);
                    int sy = std::clamp(int(std::lround(c.y + dy / d * reach)), 0, photo_height - 1);
                    out[size_t(y) * photo_width + x] = inside[size_t(sy) * photo_width + sx];
                }
        }
        return out;
    }
    // Alonso's planar layout: photo pixel -> equidistant angle about (640, 480), radius 480 ->
    // point on the plane at height h = 0.1 of the plane's width -> mask pixel.
    if (mask.channels < 3) throw_file_error(path, "the Mobotix background mask must be an RGB image (green = not sky)");
    const double cx = 640, cy = 480, r0 = 480, h = 0.1;
    const int d = mask.width;
    if (mask.height != d)
        throw_file_error(path, "the Mobotix background mask must be square (it is 512 x 512 as shipped)");
    auto green = [&](int i, int j) { return value(j, i, 1) > 0.9f && value(j, i, 0) < 0.1f && value(j, i, 2) < 0.1f; };
    for (int y = 0; y < photo_height; ++y)
        for (int x = 0; x < photo_width; ++x) {
            double dx = x - cx, dy = y - cy, rho = std::sqrt(dx * dx + dy * dy) / r0;
            if (rho >= 1.0 || rho == 0) continue;
            double alpha = rho * kPiD / 2;
            double plane = h * std::tan(alpha) * d;  // distance from the plane's centre, mask pixels
            double di = dy / (rho * r0) * plane, dj = dx / (rho * r0) * plane;
            double m = std::max(std::abs(di), std::abs(dj));
            // Off the square: take the object at its edge along the same ray (masts reach the horizon).
            if (m > d / 2.0 - 1) {
                di *= (d / 2.0 - 1) / m;
                dj *= (d / 2.0 - 1) / m;
            }
            int i = std::clamp(int(d / 2.0 + di), 0, d - 1), j = std::clamp(int(d / 2.0 + dj), 0, d - 1);
            out[size_t(y) * photo_width + x] = green(i, j) ? 1 : 0;
        }
    return out;
}

namespace {

// A shadow band's direction in the photo (unit, from the circle's centre): where a direction at the
// sun's azimuth lands (this follows the preset's north, mirroring and tilt without restating them);
// none when it lands outside the lens's field.
std::optional<cv::Point2d> band_direction(const PhotoGeometry& geometry, double azimuth_deg) {
    double x = 0, y = 0;
    if (!geometry.project(fisheye::direction_from_angles(45 * kDeg, azimuth_deg * kDeg), &x, &y)) return std::nullopt;
    const cv::Point2d along(x - geometry.circle.center_x, y - geometry.circle.center_y);
    return along / std::max(cv::norm(along), 1e-9);
}

}  // namespace

std::vector<unsigned char> shadow_band_mask(const ShadowBand& band, const PhotoGeometry& geometry, int photo_width,
                                            int photo_height) {
    const SkyCircle& c = geometry.circle;
    const std::optional<cv::Point2d> direction = band_direction(geometry, band.azimuth_deg);
    if (!direction)
        throw Error("shadow band: azimuth " + fmt(band.azimuth_deg) + " deg does not project into the photo");
    const cv::Point2d centre(c.center_x, c.center_y), along = *direction;
    const cv::Point2d across(-along.y, along.x);
    const double reach = 2 * c.radius + photo_width + photo_height;  // beyond the rim
    const cv::Point2d corners[4] = {centre + band.start_px * along - band.half_width_px * across,
                                    centre + band.start_px * along + band.half_width_px * across,
                                    centre + reach * along + band.half_width_px * across,
                                    centre + reach * along - band.half_width_px * across};
    // Sub-pixel corners (4 fractional bits): the strip's edges land where measured.
    constexpr int kShift = 4;
    std::vector<cv::Point> poly;
    for (const auto& p : corners)
        poly.emplace_back(int(std::lround((p.x) * (1 << kShift))), int(std::lround((p.y) * (1 << kShift))));
    cv::Mat mask = cv::Mat::zeros(photo_height, photo_width, CV_8U);
    cv::fillConvexPoly(mask, poly, cv::Scalar(1), cv::LINE_8, kShift);
    return std::vector<unsigned char>(mask.datastart, mask.dataend);
}

std::optional<ShadowBandFound> find_shadow_band(const Image& encoded_photo, const PhotoGeometry& geometry,
                                                const ShadowBand& band, const std::vector<unsigned char>& hidden) {
    // The pixels judged: seen, between a sixth of the radius (the housing) and the rim's glare;
    // every pixel but on large photos (about 300 across the circle). Each by its brightest channel
    // plus its chroma (brightest - faintest): the TSI's band is grey, about as bright as a deep blue
    // sky in its blue channel but far less coloured, and darker than an overcast.
    const SkyCircle& c = geometry.circle;
    const int w = encoded_photo.width, h = encoded_photo.height;
    const int stride = std::max(1, int(c.radius / 150));
    struct Sample {
        float x, y, v;
    };
    std::vector<Sample> samples;
    for (int y = 0; y < h; y += stride)
        for (int x = 0; x < w; x += stride) {
            const double dx = x + 0.5 - c.center_x, dy = y + 0.5 - c.center_y, r = std::hypot(dx, dy);
            if (r < c.radius / 6 || r > 0.92 * c.radius || (!hidden.empty() && hidden[size_t(y) * w + x])) continue;
            float hi = 0, lo = 1e30f;
            for (int ch = 0; ch < std::min(3, encoded_photo.channels); ++ch)
                hi = std::max(hi, encoded_photo.at(x, y, ch)), lo = std::min(lo, encoded_photo.at(x, y, ch));
            samples.push_back({float(dx), float(dy), 2 * hi - lo});
        }
    const double hw = band.half_width_px;
    // The strip's median over its neighbours' for a world azimuth (the band's direction in the
    // photo as shadow_band_mask finds it); medians, so the sun's glare on the band does not count.
    std::vector<float> in, beside;
    auto contrast = [&](double azimuth_deg, int step) {
        const std::optional<cv::Point2d> direction = band_direction(geometry, azimuth_deg);
        if (!direction) return 1.0;
        const double ux = direction->x, uy = direction->y;
        in.clear(), beside.clear();
        for (size_t k = 0; k < samples.size(); k += size_t(step)) {
            const Sample& s = samples[k];
            const double along = s.x * ux + s.y * uy, across = std::abs(s.x * uy - s.y * ux);
            if (along < band.start_px) continue;
            if (across <= hw) in.push_back(s.v);
            else if (across >= 2 * hw && across <= 4 * hw) beside.push_back(s.v);
        }
        if (in.size() < 20 || beside.size() < 20) return 1.0;
        const double b = median(std::vector<float>(beside));
        return b > 0 ? median(std::vector<float>(in)) / b : 1.0;
    };
    ShadowBandFound best;
    for (double a = 0; a < 360; a += 1) {
        const double q = contrast(a, 3);
        if (q < best.contrast) best = {a, q};
    }
    const double coarse = best.azimuth_deg;
    best.contrast = 1;
    for (double a = coarse - 1.5; a <= coarse + 1.5 + 1e-9; a += 0.1) {
        const double q = contrast(a, 1);
        if (q < best.contrast) best = {std::fmod(a + 360, 360), q};
    }
    if (!(best.contrast < kShadowBandContrast)) return std::nullopt;
    return best;
}

std::vector<unsigned char> horizon_obstruction_mask(const std::vector<HorizonObstruction>& profile,
                                                    const SkyCircle& circle, int photo_width, int photo_height) {
    std::vector<unsigned char> out(size_t(photo_width) * photo_height, 0);
    if (profile.empty()) return out;
    for (int y = 0; y < photo_height; ++y)
        for (int x = 0; x < photo_width; ++x) {
            const double dx = x - circle.center_x, dy = y - circle.center_y;
            const double r = std::sqrt(dx * dx + dy * dy) / circle.radius;
            double psi = std::atan2(dx, -dy) / kDeg;  // clockwise from the photo's top
            if (psi < 0) psi += 360;
            for (const HorizonObstruction& h : profile)
                if (psi >= h.from_deg && psi < h.to_deg && r >= h.radius_fraction) {
                    out[size_t(y) * photo_width + x] = 1;
                    break;
                }
        }
    return out;
}

std::vector<unsigned char> detect_dark_obstructions(const Image& encoded_photo, const SkyCircle& circle,
                                                    double darkness) {
    cv::Mat grey = image_to_grey8(encoded_photo, true);
    cv::Mat disc = cv::Mat::zeros(grey.size(), CV_8U);
    cv::circle(disc, cv::Point2d(circle.center_x, circle.center_y), int(circle.radius * 1.02), 255, cv::FILLED);
    std::vector<unsigned char> values;
    for (int y = 0; y < grey.rows; ++y)
        for (int x = 0; x < grey.cols; ++x)
            if (disc.at<unsigned char>(y, x)) values.push_back(grey.at<unsigned char>(y, x));
    std::vector<unsigned char> out(size_t(grey.cols) * grey.rows, 0);
    if (values.empty()) return out;
    const double median_grey = median(std::move(values));
    cv::Mat dark = (grey < darkness * median_grey) & disc;
    // Opening drops speckle; only pieces that are a sizeable part of the disc count as objects.
    cv::morphologyEx(dark, dark, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(5, 5)));
    cv::Mat labels, stats, centroids;
    cv::connectedComponentsWithStats(dark, labels, stats, centroids, 8);
    double min_area = 0.002 * kPiD * circle.radius * circle.radius;
    cv::Mat keep = cv::Mat::zeros(grey.size(), CV_8U);
    for (int y = 0; y < grey.rows; ++y)
        for (int x = 0; x < grey.cols; ++x) {
            int l = labels.at<int>(y, x);
            if (l > 0 && stats.at<int>(l, cv::CC_STAT_AREA) >= min_area) keep.at<unsigned char>(y, x) = 255;
        }
    cv::dilate(keep, keep, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(5, 5)));
    for (int y = 0; y < grey.rows; ++y)
        for (int x = 0; x < grey.cols; ++x) out[size_t(y) * grey.cols + x] = keep.at<unsigned char>(y, x) ? 1 : 0;
    return out;
}

// The least share of the sky disc an import must see (the rest filled in): a TSI's arm, housing
// and band hide 13-15 %, a Mobotix horizon ring about 20 %.
constexpr double kMinSeenSkyShare = 0.25;

std::vector<unsigned char> detect_thin_dark_structures(const Image& encoded_photo, const SkyCircle& circle,
                                                       double darkness) {
    // The brightest channel: blue sky and white cloud are both bright in it, a mast or wire is
    // dark in every channel.
    cv::Mat rgb = to_rgb_mat(encoded_photo, "photo"), v;
    if (rgb.channels() == 3) {
        std::vector<cv::Mat> ch;
        cv::split(rgb, ch);
        v = cv::max(cv::max(ch[0], ch[1]), ch[2]);
    } else {
        v = rgb;
    }
    v.convertTo(v, CV_32F);
    const cv::Point2d centre(circle.center_x, circle.center_y);
    cv::Mat disc = cv::Mat::zeros(v.size(), CV_8U);
    cv::circle(disc, centre, int(std::ceil(circle.radius)), 255, cv::FILLED);
    // Beyond the circle counts as bright, so the housing's dark edge inside it is a thin
    // structure too.
    double top = 0;
    cv::minMaxLoc(v, nullptr, &top, nullptr, nullptr, disc);
    cv::Mat around = v.clone();
    around.setTo(cv::Scalar(top), ~disc);
    const int k = std::max(5, 2 * int(std::lround(0.015 * circle.radius)) + 1);
    cv::Mat closed;
    cv::morphologyEx(around, closed, cv::MORPH_CLOSE, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)));
    // Darker than `darkness` x the sky around it, and by a visible step (dim, quantised dawn
    // frames are full of small dark specks that are only a few code values deep).
    cv::Mat thin = (v < darkness * closed) & (closed - v > 0.04f * float(top)) & disc;
    cv::Mat labels, stats, centroids;
    const int count = cv::connectedComponentsWithStats(thin, labels, stats, centroids, 8);
    std::vector<unsigned char> keep_label(size_t(count), 0);
    for (int l = 1; l < count; ++l) {
        // The closing only finds what is narrower than k; of that, only long pieces (several
        // times k) are objects: a short dark fleck may be sky (a bird, a cloud's dark speck). And
        // only thin ones: on average at most 2 k wide over their extent (a curved rim crescent is
        // longer than its box's diagonal), not a mesh of dark texture joined at its corners.
        const double w = stats.at<int>(l, cv::CC_STAT_WIDTH), h = stats.at<int>(l, cv::CC_STAT_HEIGHT);
        const double length = std::hypot(w, h), area = stats.at<int>(l, cv::CC_STAT_AREA);
        keep_label[size_t(l)] = length >= 0.08 * circle.radius && area <= 2.0 * k * length;
    }
    std::vector<unsigned char> out(size_t(v.cols) * v.rows, 0);
    for (int y = 0; y < v.rows; ++y)
        for (int x = 0; x < v.cols; ++x) out[size_t(y) * v.cols + x] = keep_label[size_t(labels.at<int>(y, x))];
    return out;
}

ImportedPhoto import_photo(const std::string& path, const PhotoImportParams& params) {
    Image photo = read_radiance_image(path);  // (a lossy HDR photograph's small negatives read as 0)
    const int orientation = apply_orientation(photo);
    ImportedPhoto result = import_photo_image(photo, path, params);
    result.photo_path = path;
    result.exif_orientation = orientation;
    result.pixel_type = photo.file_pixel_type;
    return result;
}


size_t spread_index(int k, int tries, int count) {
    return tries <= 1 ? 0 : size_t(std::lround(double(k) * (count - 1) / (tries - 1)));
}

namespace {

// A photograph file as the geometry helpers look at it (find_sky_circle, the obstruction
// detectors): read and turned as import_photo reads it, refused as it refuses it, display-encoded
// (an HDR file tone-mapped to grey).
Image encoded_photo(const std::string& path, const PhotoImportParams& params) {
    Image photo = read_radiance_image(path);
    apply_orientation(photo);
    check_photo_fits(photo, path, params);
    if (is_display_encoded(photo, path, params.encoding)) return photo;
    return tone_mapped_grey(to_rgb_mat(photo, path));
}

}  // namespace

SkyCircle find_photo_sky_circle(const std::string& path, const PhotoImportParams& params, std::array<int, 2>* size,
                                std::string* caution) {
    const Image encoded = encoded_photo(path, params);
    if (size) *size = {encoded.width, encoded.height};
    return find_sky_circle(encoded, path, params.min_radius_fraction, params.max_radius_fraction, caution);
}

std::vector<unsigned char> find_sequence_obstructions(const std::vector<std::string>& photos, const SkyCircle& circle,
                                                      const PhotoImportParams& params, int max_photos,
                                                      Image* percentile_out) {
    if (photos.empty()) throw Error("no photographs to find obstructions in");
    const int n = int(photos.size()), tries = std::min(n, std::max(1, max_photos));
    // The k-th largest encoded value per pixel and channel, k a fifth of the photos (the 80th
    // percentile): kept as the k largest so far, 8-bit, k x the photo's size in memory.
    const int k = std::max(1, int(std::lround(0.2 * tries)));
    int width = 0, height = 0, channels = 0;
    std::vector<unsigned char> top;  // [pixel * channels + c][k], descending
    for (int t = 0; t < tries; ++t) {
        const std::string& path = photos[spread_index(t, tries, n)];
        const Image encoded = encoded_photo(path, params);
        if (t == 0) {
            width = encoded.width, height = encoded.height, channels = std::min(encoded.channels, 3);
            top.assign(size_t(width) * height * channels * k, 0);
        } else if (encoded.width != width || encoded.height != height) {
            throw_file_error(path, "is " + std::to_string(encoded.width) + " x " + std::to_string(encoded.height) +
                                       " pixels, but the sequence's photographs are " + std::to_string(width) + " x " +
                                       std::to_string(height));
        }
        tbb::parallel_for(0, height, [&](int y) {
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < channels; ++c) {
                    const float v = encoded.at(x, y, std::min(c, encoded.channels - 1));
                    unsigned char q = (unsigned char)std::lround(std::clamp(std::isfinite(v) ? v : 0.0f, 0.0f, 1.0f) *
                                                                 255);
                    unsigned char* slot = &top[((size_t(y) * width + x) * channels + c) * k];
                    for (int i = 0; i < k; ++i)
                        if (q > slot[i]) std::swap(q, slot[i]);  // insert, the smallest falls off
                }
        });
    }
    Image percentile(width, height, channels);
    for (size_t p = 0; p < size_t(width) * height * channels; ++p) percentile.pixels[p] = top[p * k + (k - 1)] / 255.0f;
    std::vector<unsigned char> out = detect_dark_obstructions(percentile, circle);
    const std::vector<unsigned char> thin = detect_thin_dark_structures(percentile, circle);
    for (size_t p = 0; p < out.size(); ++p) out[p] = out[p] || thin[p];
    if (percentile_out) *percentile_out = std::move(percentile);
    return out;
}

std::optional<SequenceColourShading> find_sequence_colour_shading(const std::vector<std::string>& photos,
                                                                  PhotoImportParams params, int max_photos) {
    if (photos.empty()) throw Error("no photographs to measure colour shading on");
    params.resolution = 128;
    params.colour_shading.reset();
    params.fill_method = PhotoImportParams::FillMethod::Smooth;
    constexpr int kBands = 18;  // 5 % of the radius each, to 90 %
    const CloudMaskParams rule{CloudRule::RedBlueRatio, kWsisegBestRedBlueThreshold};
    const int n = int(photos.size()), tries = std::min(n, std::max(1, max_photos));
    std::vector<std::vector<double>> rg(kBands), bg(kBands);  // per band, one value per overcast photo
    SequenceColourShading out;
    for (int t = 0; t < tries; ++t) {
        const std::string& path = photos[spread_index(t, tries, n)];
        ++out.tried;
        ImportedPhoto imp;
        try {
            imp = import_photo(path, params);
        } catch (const Error&) {
            continue;  // the import proper names it
        }
        if (!imp.display_referred) continue;
        const int m = imp.sky.resolution;
        const double c = (m - 1) / 2.0;
        // Overcast: nearly every seen pixel within half the radius is cloud by the rule (where the
        // shading is weak). Then every seen pixel is a grey, at every radius.
        long centre = 0, cloudy = 0;
        std::vector<std::vector<double>> prg(kBands), pbg(kBands);
        for (int j = 0; j < m; ++j)
            for (int i = 0; i < m; ++i) {
                const size_t p = size_t(j) * m + i;
                const double r = std::hypot(i - c, j - c) / (m / 2.0);
                const Color v = imp.sky.pixel(i, j);
                if (r >= 0.9 || imp.not_sky[p] || imp.clipped[p] || !(v.minCoeff() > 0)) continue;
                if (r < 0.5) {
                    ++centre;
                    cloudy += is_cloud(imp.encoded(v[0]), imp.encoded(v[1]), imp.encoded(v[2]), rule);
                }
                const int b = std::min(kBands - 1, int(r * 20));
                prg[size_t(b)].push_back(std::log(double(v[0]) / v[1]));
                pbg[size_t(b)].push_back(std::log(double(v[2]) / v[1]));
            }
        if (centre < 200 || cloudy < 0.95 * centre) continue;
        // Against the photo's own zenith (the first 30 % of the radius).
        std::vector<double> zrg, zbg;
        for (int b = 0; b < 6; ++b)
            zrg.insert(zrg.end(), prg[size_t(b)].begin(), prg[size_t(b)].end()),
                zbg.insert(zbg.end(), pbg[size_t(b)].begin(), pbg[size_t(b)].end());
        if (zrg.size() < 50) continue;
        const double zr = quantile(zrg, 0.5), zb = quantile(zbg, 0.5);
        ++out.overcast;
        for (int b = 0; b < kBands; ++b)
            if (prg[size_t(b)].size() >= 30) {
                rg[size_t(b)].push_back(quantile(prg[size_t(b)], 0.5) - zr);
                bg[size_t(b)].push_back(quantile(pbg[size_t(b)], 0.5) - zb);
            }
    }
    if (out.overcast < 3) return std::nullopt;
    // Medians over the photos per band, fitted as a r^2 + b r^4 (0 at the zenith).
    Eigen::MatrixXd a(kBands, 2);
    Eigen::VectorXd yr(kBands), yb(kBands);
    int rows = 0;
    for (int b = 0; b < kBands; ++b) {
        if (int(rg[size_t(b)].size()) * 2 < out.overcast) continue;
        const double r = (b + 0.5) / 20, r2 = r * r;
        a(rows, 0) = r2, a(rows, 1) = r2 * r2;
        yr(rows) = quantile(rg[size_t(b)], 0.5), yb(rows) = quantile(bg[size_t(b)], 0.5);
        ++rows;
    }
    if (rows < 10) return std::nullopt;
    const Eigen::MatrixXd am = a.topRows(rows);
    const Eigen::Vector2d fr = am.colPivHouseholderQr().solve(yr.head(rows)),
                          fb = am.colPivHouseholderQr().solve(yb.head(rows));
    out.shading = PhotoImportParams::ColourShading{fr(0), fr(1), fb(0), fb(1), 0.9};
    out.rms_fit = std::sqrt(((am * fr - yr.head(rows)).squaredNorm() + (am * fb - yb.head(rows)).squaredNorm()) /
                            (2.0 * rows));
    return out;
}

SequenceSkyCircle find_sequence_sky_circle(const std::vector<std::string>& photos, const PhotoImportParams& params,
                                           int max_photos) {
    if (photos.empty()) throw Error("no photographs to find a sky circle in");
    SequenceSkyCircle out;
    std::vector<double> xs, ys, rs;
    std::string first;
    const int n = int(photos.size()), tries = std::min(n, std::max(1, max_photos));
    for (int k = 0; k < tries; ++k) {
        // Spread over the sequence: a dark start (dawn) or a run of overcast frames is not all it sees.
        const std::string& path = photos[spread_index(k, tries, n)];
        ++out.tried;
        std::array<int, 2> size{0, 0};
        SkyCircle c;
        try {
            std::string caution;
            c = find_photo_sky_circle(path, params, &size, &caution);
            if (!caution.empty()) out.cautions.push_back(path + ": " + caution);
        } catch (const Error& e) {
            out.not_found.push_back(e.what());
            continue;
        }
        // One camera, one size: a photograph of another size belongs to another camera (or was
        // cropped or scaled), and one circle cannot serve both.
        if (rs.empty()) {
            out.photo_size = size, first = path;
        } else if (size != out.photo_size) {
            throw_file_error(path, "is " + std::to_string(size[0]) + " x " + std::to_string(size[1]) + " pixels, but " +
                                       first + " is " + std::to_string(out.photo_size[0]) + " x " +
                                       std::to_string(out.photo_size[1]) +
                                       ": a sequence is one camera's photographs, all of one size (import the "
                                       "others apart)");
        }
        xs.push_back(c.center_x), ys.push_back(c.center_y), rs.push_back(c.radius);
    }
    out.found = int(rs.size());
    if (rs.empty())
        throw Error("no sky circle found in any of " + std::to_string(out.tried) + " photographs of the sequence (" +
                    out.not_found.front() +
                    (out.not_found.front().find("--center") == std::string::npos
                         ? "); give its centre and radius (--center X,Y --radius R)"
                         : ")"));
    out.circle = SkyCircle{quantile(xs, 0.5), quantile(ys, 0.5), quantile(rs, 0.5)};
    for (size_t i = 0; i < rs.size(); ++i) {
        out.centre_spread_px = std::max(out.centre_spread_px,
                                        std::hypot(xs[i] - out.circle.center_x, ys[i] - out.circle.center_y));
        out.radius_spread_px = std::max(out.radius_spread_px, std::abs(rs[i] - out.circle.radius));
    }
    return out;
}

namespace {

ImportedPhoto import_checked_photo(const Image& photo, const std::string& name, const PhotoImportParams& params,
                                   const Image* extra_not_sky);

}  // namespace

void check_photo_fits(const Image& photo, const std::string& name, const PhotoImportParams& params) {
    // A sky circle needs room: a photo a few pixels wide (or one row) is not an all-sky photograph,
    // and OpenCV's resizing and circle search would assert on it.
    if (!photo.empty() && (photo.width < kMinPhotoSide || photo.height < kMinPhotoSide))
        throw_file_error(name, "the photograph is " + std::to_string(photo.width) + " x " +
                                   std::to_string(photo.height) +
                                   " pixels: too small for an all-sky photograph (each "
                                   "side at least " +
                                   std::to_string(kMinPhotoSide) + ")");
    if (const auto& s = params.circle_photo_size;
        s && !photo.empty() && (photo.width != (*s)[0] || photo.height != (*s)[1]))
        throw_file_error(name, "the photograph is " + std::to_string(photo.width) + " x " +
                                   std::to_string(photo.height) + " pixels, but " +
                                   (params.circle_source.empty() ? std::string("the given sky circle")
                                                                 : params.circle_source + "'s sky circle") +
                                   " was measured on " + std::to_string((*s)[0]) + " x " + std::to_string((*s)[1]) +
                                   " photographs: another camera? " +
                                   (params.circle_source == "the sequence"
                                        ? std::string("Import it apart (its own circle is found)")
                                        : std::string("Import it without a preset (the circle is found)")));
}

ImportedPhoto import_photo_image(const Image& photo, const std::string& name, const PhotoImportParams& params,
                                 const Image* extra_not_sky) {
    check_photo_fits(photo, name, params);
    try {
        return import_checked_photo(photo, name, params, extra_not_sky);
    } catch (const cv::Exception& e) {
        // Out of memory is said as every command says it (cli/main.cpp: the inputs and what to make
        // smaller).
        if (e.code == cv::Error::StsNoMem) throw std::bad_alloc();
        // Any other OpenCV failure still names the file instead of surfacing as a raw assertion.
        throw_file_error(name, "OpenCV failed on this " + std::to_string(photo.width) + " x " +
                                   std::to_string(photo.height) + " photograph: " + e.err);
    }
}

namespace {

ImportedPhoto import_checked_photo(const Image& photo, const std::string& name, const PhotoImportParams& params,
                                   const Image* extra_not_sky) {
    const int n = params.resolution;
    if (n < 8 || n > 16384) throw Error("sky resolution " + std::to_string(n) + " is not in 8..16384 pixels");
    if (photo.empty()) throw_file_error(name, "image has no pixels");

    ImportedPhoto out;
    out.photo_path = name;
    out.display_referred = is_display_encoded(photo, name, params.encoding);
    cv::Mat rgb = to_rgb_mat(photo, name);

    // Geometry: the circle given, or found.
    out.geometry.lens = params.lens;
    out.geometry.north_deg = params.north_deg;
    out.geometry.mirrored = params.mirrored;
    out.geometry.tilt_deg = params.tilt_deg;
    out.geometry.tilt_azimuth_deg = params.tilt_azimuth_deg;
    if (params.circle) {
        out.geometry.circle = *params.circle;
        if (!(params.circle->radius > 0)) throw Error("the sky circle's radius must be positive");
    } else {
        out.geometry.circle = find_sky_circle(out.display_referred ? photo : tone_mapped_grey(rgb), name,
                                              params.min_radius_fraction, params.max_radius_fraction,
                                              &out.circle_caution);
        out.circle_detected = true;
    }
    const SkyCircle circle = out.geometry.circle;

    // Not-sky mask in the photo's grid (0/1), from the file, the caller and detection.
    cv::Mat not_sky = cv::Mat::zeros(rgb.size(), CV_8U);
    if (!params.mask_path.empty()) {
        auto m = load_not_sky_mask(params.mask_path, params.mask_layout, photo.width, photo.height);
        for (int y = 0; y < rgb.rows; ++y)
            for (int x = 0; x < rgb.cols; ++x) not_sky.at<unsigned char>(y, x) = m[size_t(y) * rgb.cols + x];
    }
    if (extra_not_sky) {
        if (extra_not_sky->width != photo.width || extra_not_sky->height != photo.height)
            throw_file_error(name, "the not-sky mask given does not have the photograph's size");
        for (int y = 0; y < rgb.rows; ++y)
            for (int x = 0; x < rgb.cols; ++x)
                if (extra_not_sky->at(x, y, 0) > 0.5f) not_sky.at<unsigned char>(y, x) = 1;
    }
    for (const auto& r : params.not_sky_rects) {
        cv::Rect rect = cv::Rect(r[0], r[1], r[2], r[3]) & cv::Rect(0, 0, rgb.cols, rgb.rows);
        if (rect.area() > 0) not_sky(rect).setTo(1);
    }
    std::optional<ShadowBand> shadow_band = params.shadow_band;
    bool detect_obstructions = params.detect_obstructions;
    if (shadow_band && shadow_band->find_in_photo) {
        // No time to put it at the sun: found in the photograph, else taken as a dark object.
        const std::vector<unsigned char> hidden(not_sky.datastart, not_sky.dataend);
        out.shadow_band_found = find_shadow_band(out.display_referred ? photo : tone_mapped_grey(rgb), out.geometry,
                                                 *shadow_band, hidden);
        if (out.shadow_band_found) shadow_band->azimuth_deg = out.shadow_band_found->azimuth_deg;
        else shadow_band.reset(), detect_obstructions = true;
    }
    if (shadow_band || !params.horizon_obstructions.empty()) {
        std::vector<unsigned char> band(size_t(rgb.cols) * rgb.rows, 0);
        if (shadow_band) band = shadow_band_mask(*shadow_band, out.geometry, rgb.cols, rgb.rows);
        auto horizon = horizon_obstruction_mask(params.horizon_obstructions, circle, rgb.cols, rgb.rows);
        for (int y = 0; y < rgb.rows; ++y)
            for (int x = 0; x < rgb.cols; ++x) {
                const size_t p = size_t(y) * rgb.cols + x;
                if (band[p] || horizon[p]) not_sky.at<unsigned char>(y, x) = 1;
            }
    }
    if (detect_obstructions || params.detect_thin_obstructions) {
        const Image encoded = out.display_referred ? photo : tone_mapped_grey(rgb);
        std::vector<unsigned char> m, t;
        if (detect_obstructions) m = detect_dark_obstructions(encoded, circle);
        if (params.detect_thin_obstructions) t = detect_thin_dark_structures(encoded, circle);
        for (int y = 0; y < rgb.rows; ++y)
            for (int x = 0; x < rgb.cols; ++x) {
                const size_t p = size_t(y) * rgb.cols + x;
                if ((!m.empty() && m[p]) || (!t.empty() && t[p])) not_sky.at<unsigned char>(y, x) = 1;
            }
    }
    if (params.mask_dilate_px > 0 && cv::countNonZero(not_sky) > 0) {
        int k = 2 * params.mask_dilate_px + 1;
        cv::dilate(not_sky, not_sky, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)));
    }

    // Saturation, judged on the encoded values, then linear light.
    cv::Mat clipped = cv::Mat::zeros(rgb.size(), CV_8U);
    out.clip_level = 1.0;
    if (out.display_referred) {
        // A PNG's gAMA says its curve (OpenImageIO's oiio:ColorSpace "GammaG": values v mean v^G);
        // decoded as sRGB, a gamma-1.8 PNG came out 18-37 % dark per channel. --encoding srgb means
        // the sRGB curve whatever the header says.
        const std::optional<float> gamma = params.encoding == "auto" ? header_gamma(photo) : std::nullopt;
        if (gamma) out.encoding_gamma = *gamma;
        out.clip_level = params.clip_level >= 0 ? params.clip_level : find_clip_level(rgb, circle, not_sky);
        float level = float(out.clip_level);
        for (int y = 0; y < rgb.rows; ++y)
            for (int x = 0; x < rgb.cols; ++x) {
                cv::Vec3f& p = rgb.at<cv::Vec3f>(y, x);
                if (std::max({p[0], p[1], p[2]}) >= level - 0.5f / 255.0f) clipped.at<unsigned char>(y, x) = 1;
                for (int c = 0; c < 3; ++c)
                    p[c] = gamma ? std::pow(std::clamp(p[c], 0.0f, 1.0f), *gamma)
                                 : srgb_to_linear(std::min(p[c], 1.0f));
            }
    }

    // Downsampling a lot: area-average first so that remap's bilinear taps see ~1 photo pixel per
    // output pixel (otherwise it aliases).
    SkyCircle c = circle;
    double ratio = circle.radius / (n / 2.0);
    cv::Mat src = rgb, src_not_sky, src_clipped;
    not_sky.convertTo(src_not_sky, CV_32F);
    clipped.convertTo(src_clipped, CV_32F);
    if (ratio > 1.5) {
        double f = 1.0 / ratio;
        cv::Size size(std::max(1, int(std::lround(rgb.cols * f))), std::max(1, int(std::lround(rgb.rows * f))));
        double fx = double(size.width) / rgb.cols, fy = double(size.height) / rgb.rows;
        cv::resize(rgb, src, size, 0, 0, cv::INTER_AREA);
        cv::resize(src_not_sky, src_not_sky, size, 0, 0, cv::INTER_AREA);
        cv::resize(src_clipped, src_clipped, size, 0, 0, cv::INTER_AREA);
        c.center_x = (circle.center_x + 0.5) * fx - 0.5;
        c.center_y = (circle.center_y + 0.5) * fy - 0.5;
        c.radius = circle.radius * std::sqrt(fx * fy);
    }
    PhotoGeometry g = out.geometry;
    g.circle = c;

    // Canonical pixel -> photo pixel. Pixels beyond the horizon take the horizon's value along their
    // ray, so the inpainting below sees plausible neighbours at the rim instead of black.
    cv::Mat map_x(n, n, CV_32F), map_y(n, n, CV_32F);
    cv::Mat unseen = cv::Mat::zeros(n, n, CV_8U);
    const double rmax = 1.0 - 0.25 / n;
    tbb::parallel_for(tbb::blocked_range<int>(0, n), [&](const tbb::blocked_range<int>& rows) {
        for (int j = rows.begin(); j < rows.end(); ++j)
            for (int i = 0; i < n; ++i) {
                Vec2 uv = fisheye::pixel_center_uv(i, j, n);
                double u = uv.x(), v = uv.y(), r = std::sqrt(u * u + v * v);
                if (r > rmax) u *= rmax / r, v *= rmax / r;
                double x = -1, y = -1;
                bool ok = g.project(fisheye::direction_from_uv(u, v), &x, &y) && x >= -0.5 && y >= -0.5 &&
                          x <= src.cols - 0.5 && y <= src.rows - 0.5;
                map_x.at<float>(j, i) = float(x);
                map_y.at<float>(j, i) = float(y);
                if (!ok) unseen.at<unsigned char>(j, i) = 1;
            }
    });
    cv::Mat sky, sky_not_sky, sky_clipped;
    cv::remap(src, sky, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    cv::remap(src_not_sky, sky_not_sky, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(1.0));
    cv::remap(src_clipped, sky_clipped, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0.0));

    // Any obstruction in a pixel's bilinear footprint taints it: fill it.
    cv::Mat fill = (sky_not_sky > 0.01f) | (unseen > 0);
    {
        // A sky that is nearly all filled in is invented, not imported (a circle given off the
        // photograph, a mask that hides everything); one whose seen pixels are all black holds
        // no sky (a lens cap, a night frame, a black file): nothing a fill, a calibration or a
        // restored sun could make light from.
        const cv::Mat disc = sky_disc_mask(n), seen_sky = ~fill & disc;
        const double seen = double(cv::countNonZero(seen_sky)) / std::max(1, cv::countNonZero(disc));
        if (seen < kMinSeenSkyShare) {
            char text[160];
            std::snprintf(text, sizeof text,
                          "only %.1f%% of the sky disc is seen sky (the circle at %.1f, %.1f, radius %.1f px, "
                          "off the photograph, or a mask hiding it): nothing to import",
                          100.0 * seen, circle.center_x, circle.center_y, circle.radius);
            throw_file_error(name, text);
        }
        std::vector<cv::Mat> ch;
        cv::split(sky, ch);
        double brightest = 0;
        cv::minMaxLoc(cv::max(cv::max(ch[0], ch[1]), ch[2]), nullptr, &brightest, nullptr, nullptr, seen_sky);
        if (!(brightest > 0)) throw_file_error(name, "the sky it shows is black everywhere: nothing to import");
        // Its twin: white everywhere (a frame blown out by the sun, a blank file) holds no sky
        // either; calibrated on its mean it came out a flat grey sky, scored and moved as real.
        const double clipped = double(cv::countNonZero((sky_clipped > 0.25f) & seen_sky)) /
                               std::max(1, cv::countNonZero(seen_sky));
        if (clipped > 0.95) {
            char text[160];
            std::snprintf(text, sizeof text,
                          "%.1f%% of the sky it shows is clipped (saturated): overexposed, no sky to import",
                          100.0 * clipped);
            throw_file_error(name, text);
        }
    }
    out.not_sky.assign(size_t(n) * n, 0);
    out.clipped.assign(size_t(n) * n, 0);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            out.not_sky[size_t(j) * n + i] = fill.at<unsigned char>(j, i) ? 1 : 0;
            out.clipped[size_t(j) * n + i] = sky_clipped.at<float>(j, i) > 0.25f ? 1 : 0;
        }

    // A monochrome photograph (the Mobotix writes its night frames so, R = G = B at every pixel) has
    // no colour for the camera's colour shading to correct: divided out anyway, it gave grey frames
    // a pink rim (R/G 1.23 at the horizon).
    auto monochrome = [&] {
        for (int j = 0; j < n; ++j) {
            const cv::Vec3f* row = sky.ptr<cv::Vec3f>(j);
            for (int i = 0; i < n; ++i)
                if (row[i][0] != row[i][1] || row[i][2] != row[i][1]) return false;
        }
        return true;
    };
    if (const auto& shading = params.colour_shading; shading && !monochrome()) {
        // Before the fill, so what fills the hidden pixels (the horizon ring) comes from corrected sky.
        const double c = (n - 1) / 2.0;
        tbb::parallel_for(0, n, [&](int j) {
            cv::Vec3f* row = sky.ptr<cv::Vec3f>(j);
            const float* clipped = sky_clipped.ptr<float>(j);
            for (int i = 0; i < n; ++i) {
                const double r = std::min(shading->max_radius, std::hypot(i - c, j - c) / (n / 2.0)), r2 = r * r;
                const double keep = std::clamp(double(clipped[i]), 0.0, 1.0);
                row[i][0] *= float(std::exp(-(1 - keep) * (shading->rg2 * r2 + shading->rg4 * r2 * r2)));
                row[i][2] *= float(std::exp(-(1 - keep) * (shading->bg2 * r2 + shading->bg4 * r2 * r2)));
            }
        });
    }
    if (cv::countNonZero(fill) > 0) {
        if (params.inpaint) inpaint_float(sky, fill, params.fill_method);
        else sky.setTo(cv::Scalar::all(0), fill);
    }

    out.sky = SkyImage(n);
    out.sky.source = "photo:" + name;
    for (int j = 0; j < n; ++j) {
        const cv::Vec3f* row = sky.ptr<cv::Vec3f>(j);
        for (int i = 0; i < n; ++i) {
            if (!out.sky.in_disc(i, j)) {
                out.not_sky[size_t(j) * n + i] = 0;
                out.clipped[size_t(j) * n + i] = 0;
                continue;
            }
            out.sky.set_pixel(i, j,
                              Color(std::max(0.0f, row[i][0]), std::max(0.0f, row[i][1]), std::max(0.0f, row[i][2])));
        }
    }
    validate_sky(out.sky, name);  // e.g. an HDR photograph of 1e31 values: no sky to light with
    return out;
}

}  // namespace

CameraPreset camera_preset(const std::string& name) {
    CameraPreset p;
    p.name = name;
    p.params.circle_source = "the " + name + " preset";
    if (name == "arm-tsi") {
        // ARM SGP C1 Total Sky Imager (TSI-880): a camera looking down at a hemispherical mirror.
        // Geometry fitted to the TSI's own sun marker in tsi_cloudmask/ (212 frames, 0.07 px rms):
        // equisolid (r = R sqrt2 sin(theta/2), what a convex mirror seen from afar gives), north
        // up, mirrored; the shadow band's angle agrees with the sun's azimuth within 1 degree.
        p.params.lens = LensLaw::Equisolid;
        p.params.mirrored = true;
        p.params.north_deg = 0.0;
        p.params.circle = SkyCircle{243.1, 317.5, 230.8};
        p.params.circle_photo_size = std::array<int, 2>{480, 640};
        p.params.mask_layout = MaskLayout::TsiCloudMask;
        p.params.mask_dilate_px = 4;  // the band's blurred edge lies just outside the TSI's polygon
        p.params.min_radius_fraction = 0.45;
        p.params.max_radius_fraction = 0.52;
        p.latitude_deg = 36.605;
        p.longitude_deg = -97.485;
        p.elevation_m = 318;
        p.filename_utc_offset_hours = 0;
        p.sun_search_deg = 3;
        // Without the frame's mask: the imager's own obstructions as measured on its masks (every
        // 5th of the 892 masks of the three shared sets, photo pixels). Black in at least 97 % of
        // them: the camera arm (x 236-249, up from the housing) and the camera housing (x 223-262,
        // y 270-369). The rest is the band: a strip +-30 px about the line from the circle's centre
        // at the sun's azimuth (its centre line 0.09 +- 0.11 deg from it), starting 20 px behind
        // the centre. These reproduce the masks at IoU 0.958 (worst frame 0.947).
        // Above the housing, white cable ties on the arm reach 10-20 px either side of it (the
        // imager's masks call them cloud): a small rectangle of their own.
        p.fixed_not_sky_rects = {{236, 0, 14, 270}, {223, 270, 40, 100}, {225, 248, 43, 22}};
        p.shadow_band = ShadowBand{0.0, 30.0, -20.0};
        // Colour (docs/sky-import.md): its clouds come out green-grey, R/G 0.68-0.74 and B/G
        // 0.75-0.79 (log-chromaticity medians of r/b > 0.85 pixels, five frames 15:40-18:10Z),
        // and its clear sky's colour, seen from that grey, is stretched about 1.8x (R/G) and 1.0x (B/G)
        // the model's on broken-cloud days (fitted per photo; these are for photos without clear sky).
        p.colour = CameraColour{Color(0.712f, 1.0f, 0.771f), 1.8, 1.0};
        return p;
    }
    if (name == "mobotix") {
        // Mobotix at Ecole des Mines, Sophia Antipolis. Lens circle measured on the photographs;
        // equidistant as the source project assumed. North is uncertain (docs/sky-import.md): the
        // morning sun puts it at the bottom of the photo (about 180-195 deg), but the midday sun
        // track cannot be matched by any level camera at 43.6 N, so HDR recovery searches widely
        // for the sun.
        p.params.lens = LensLaw::Equidistant;
        p.params.mirrored = false;
        p.params.north_deg = 190.0;
        p.params.circle = SkyCircle{654.7, 479.4, 485.8};
        p.params.circle_photo_size = std::array<int, 2>{1280, 960};
        p.params.mask_layout = MaskLayout::AlonsoPlanarGreenIsNotSky;
        p.params.mask_dilate_px = 3;
        // The shipped mask stops near 82 deg: the rooftops beyond it are found as dark objects.
        p.params.detect_obstructions = true;
        // The burnt-in capture time (top right) and the logo (top left) reach into the circle.
        p.params.not_sky_rects = {{700, 0, 580, 30}, {0, 0, 40, 32}};
        p.params.min_radius_fraction = 0.46;
        p.params.max_radius_fraction = 0.52;
        // Its colour shading, measured on the 43 overcast frames of the model's fitting part
        // (frames 1-336 every 4th with under 1 % clear sky, seen pixels, per 5 % of the radius,
        // medians against the zenith's): red falls off towards the horizon, log(R/G) -0.25 at 79
        // degrees (22 % less red), B/G within 0.03; fitted within 0.01 (docs/sky-import.md).
        p.params.colour_shading = PhotoImportParams::ColourShading{-0.1534, -0.2407, -0.0509, 0.1090, 0.9};
        p.latitude_deg = 43.614;
        p.longitude_deg = 7.071;
        p.elevation_m = 140;
        p.filename_utc_offset_hours = 2;  // CEST: see docs/sky-import.md (dawn brightening)
        p.sun_search_deg = 35;
        // Without background_mask.png: its objects (masts, railings, roof edges) as a horizon
        // profile, {from, to (image degrees clockwise from the top), radius fraction where the
        // object starts}: the nearest object pixel per half degree of the mask in the photo's grid,
        // runs within 0.015 of the radius merged. Covers every mask pixel (and 35 % more: the
        // objects' notches); the rooftops beyond the mask are found as dark objects, as with it.
        p.horizon_obstructions = {
            {0.0, 9.0, 0.83},     {9.0, 14.0, 0.85},    {39.0, 45.0, 0.79},   {45.0, 48.5, 0.86},
            {48.5, 58.5, 0.83},   {73.5, 78.5, 0.82},   {130.5, 143.0, 0.86}, {143.0, 149.0, 0.80},
            {149.0, 149.5, 0.82}, {149.5, 151.5, 0.87}, {151.5, 157.5, 0.80}, {158.0, 163.5, 0.82},
            {164.5, 170.0, 0.82}, {173.5, 178.5, 0.84}, {179.5, 185.0, 0.85}, {217.5, 218.0, 0.94},
            {218.0, 224.5, 0.90}, {224.5, 239.0, 0.88}, {239.0, 240.0, 0.91}, {256.0, 268.0, 0.88},
            {269.5, 275.0, 0.87}, {275.0, 276.0, 0.89}, {276.5, 282.5, 0.85}, {282.5, 283.0, 0.88},
            {303.5, 311.0, 0.90}, {311.0, 322.5, 0.87}, {322.5, 329.0, 0.81}, {329.0, 335.5, 0.86},
            {335.5, 341.5, 0.82}, {345.0, 345.5, 0.85}, {345.5, 351.0, 0.83}, {353.0, 360.0, 0.84}};
        return p;
    }
    std::string names;
    for (const auto& n : camera_preset_names()) names += (names.empty() ? "" : ", ") + n;
    throw Error("unknown camera preset '" + name + "' (known: " + names + ")");
}

std::vector<std::string> camera_preset_names() { return {"arm-tsi", "mobotix"}; }

std::string find_preset_mask(const std::string& preset, const std::string& photo_path) {
    fs::path photo(photo_path);
    fs::path set_dir = photo.parent_path().parent_path();
    std::error_code ec;
    if (preset == "arm-tsi") {
        std::smatch m;
        std::string file = photo.filename().string();
        if (!std::regex_search(file, m, std::regex("(\\d{14}Z)"))) return "";
        fs::path mask = set_dir / "tsi_cloudmask" / ("tsicldmask_sgpC1_" + m[1].str() + ".png");
        return fs::exists(mask, ec) ? mask.string() : "";
    }
    if (preset == "mobotix") {
        fs::path mask = set_dir / "background_mask.png";
        return fs::exists(mask, ec) ? mask.string() : "";
    }
    return "";
}

namespace {

std::string clock_zone(double utc_offset_hours) {
    const int minutes = int(std::lround(std::abs(utc_offset_hours) * 60));
    char zone[16];
    std::snprintf(zone, sizeof zone, "%c%02d:%02d", utc_offset_hours < 0 ? '-' : '+', minutes / 60, minutes % 60);
    return zone;
}

// ISO 8601 from parts, "" unless they make a plausible date and time (years 1900-2199).
std::string iso_time(const std::string& y, const std::string& mo, const std::string& d, const std::string& h,
                     const std::string& mi, const std::string& sec, const std::string& zone) {
    const int year = std::stoi(y), month = std::stoi(mo), day = std::stoi(d), hour = std::stoi(h),
              minute = std::stoi(mi), second = sec.empty() ? 0 : std::stoi(sec);
    if (year < 1900 || year > 2199 || month < 1 || month > 12 || day < 1 || day > 31 || hour > 23 || minute > 59 ||
        second > 60)
        return "";
    return y + "-" + mo + "-" + d + "T" + h + ":" + mi + ":" + (sec.empty() ? "00" : sec) + zone;
}

// "Z", "+hh:mm", "-hhmm" as given -> "Z" / "+hh:mm"; "" when absent or implausible.
std::string zone_text(const std::string& z) {
    if (z.empty() || z == "Z") return z;
    const std::string digits = z.substr(1, 2) + z.substr(z.size() - 2);
    const int h = std::stoi(digits.substr(0, 2)), m = std::stoi(digits.substr(2));
    if (h > 14 || m > 59) return "";
    return z.substr(0, 1) + digits.substr(0, 2) + ":" + digits.substr(2);
}

}  // namespace

std::string time_from_file_name(const std::string& path, double utc_offset_hours, bool* zone_in_name) {
    const std::string file = fs::path(path).filename().string();
    if (zone_in_name) *zone_in_name = false;
    // Each pattern: the first match whose date and time are plausible.
    static const std::regex patterns[] = {
        // ISO-like with separators, optional seconds, fraction and zone.
        std::regex("(?:^|\\D)(\\d{4})-(\\d{2})-(\\d{2})[T_ ](\\d{2})[:\\-_.](\\d{2})(?:[:\\-_.](\\d{2}))?(?:\\.\\d+)?"
                   "(Z|[+\\-]\\d{2}:\\d{2}|[+\\-]\\d{4}(?!\\d))?(?!\\d)"),
        // Compact: 14 digits (optionally a separator after the date: ARM's archive names are
        // sgptsiskyimageC1.a1.20170524.163000.jpg), optional Z.
        std::regex("(?:^|\\D)(\\d{4})(\\d{2})(\\d{2})[T_.\\-]?(\\d{2})(\\d{2})(\\d{2})(Z?)(?!\\d)"),
        // Compact without seconds: date, a separator, 4 digits.
        std::regex("(?:^|\\D)(\\d{4})(\\d{2})(\\d{2})[T_\\-](\\d{2})(\\d{2})()()(?!\\d)"),
    };
    for (const std::regex& re : patterns) {
        for (auto it = std::sregex_iterator(file.begin(), file.end(), re); it != std::sregex_iterator(); ++it) {
            const std::smatch& m = *it;
            const std::string given = zone_text(m[7].str());
            const std::string zone = given.empty() ? clock_zone(utc_offset_hours) : given;
            const std::string iso = iso_time(m[1], m[2], m[3], m[4], m[5], m[6], zone);
            if (iso.empty()) continue;
            if (zone_in_name) *zone_in_name = !given.empty();
            return iso;
        }
    }
    return "";
}

PhotoTime photo_time(const std::string& path, double utc_offset_hours) {
    PhotoTime t;
    t.iso = time_from_file_name(path, utc_offset_hours, &t.zone_in_file);
    if (!t.iso.empty()) {
        t.source = "file name";
        return t;
    }
    // EXIF: "YYYY:MM:DD hh:mm:ss", its zone (EXIF 2.31) "+hh:mm". Only the time the photograph was
    // taken: DateTime is the time the file was last changed (any conversion or edit stamps it), and a
    // converted photo was calibrated against the sun of the moment it was converted.
    const std::vector<std::string> exif_values = image_header_strings(path, {"Exif:DateTimeOriginal",
                                                                             "Exif:OffsetTimeOriginal"});
    const std::string& when = exif_values[0];
    std::smatch m;
    static const std::regex exif("^\\s*(\\d{4}):(\\d{2}):(\\d{2})[ T](\\d{2}):(\\d{2}):(\\d{2})");
    if (!std::regex_search(when, m, exif)) return t;
    std::string given = exif_values[1];
    static const std::regex offset("^\\s*([+\\-]\\d{2}:\\d{2})\\s*$");
    std::smatch z;
    given = std::regex_search(given, z, offset) ? zone_text(z[1].str()) : "";
    t.iso = iso_time(m[1], m[2], m[3], m[4], m[5], m[6], given.empty() ? clock_zone(utc_offset_hours) : given);
    if (t.iso.empty()) return t;
    t.zone_in_file = !given.empty();
    t.source = "EXIF";
    return t;
}

}  // namespace dynsky
