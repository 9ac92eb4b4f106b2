#include "motion/sun_patch.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <opencv2/imgproc.hpp>
#include <opencv2/photo.hpp>

#include "sky/clear_sky.h"
#include "sky/fisheye.h"
#include "util/error.h"
#include "util/math.h"

namespace dynsky {

namespace {

cv::Mat saturated_pixels(const cv::Mat& unit) {
    std::vector<cv::Mat> ch;
    cv::split(unit, ch);
    return (ch[0] >= 0.999f) | (ch[1] >= 0.999f) | (ch[2] >= 0.999f);
}

int sun_cut_radius(int n) { return int(std::ceil(n / 180.0)) + 2; }  // 1 degree + 2 px

}  // namespace

cv::Mat sun_cut_mask(int n, const Vec3d& sun) {
    cv::Mat mask = cv::Mat::zeros(n, n, CV_8UC1);
    if (!(sun.y() > 0)) return mask;
    double x, y;
    fisheye::pixel_from_direction(sun.normalized(), n, &x, &y);
    // remove_sun's disc, dilated by one pixel as it dilates its cut (3 x 3: the square's corners too).
    const int r = sun_cut_radius(n), ci = int(std::lround(x)), cj = int(std::lround(y));
    for (int j = std::max(0, cj - r - 1); j <= std::min(n - 1, cj + r + 1); ++j)
        for (int i = std::max(0, ci - r - 1); i <= std::min(n - 1, ci + r + 1); ++i) {
            const int dx = std::max(0, std::abs(i - ci) - 1), dy = std::max(0, std::abs(j - cj) - 1);
            if (dx * dx + dy * dy <= r * r) mask.at<uint8_t>(j, i) = 255;
        }
    return mask;
}

cv::Mat sun_cone_mask(int n, const Vec3d& sun, double degrees) {
    cv::Mat mask(n, n, CV_8UC1, cv::Scalar(0));
    const Vec3d s = sun.normalized();
    const double cos_max = std::cos(degrees * kPiD / 180);
    double x, y;
    fisheye::pixel_from_direction(s, n, &x, &y);
    // The cone's pixels lie within this many pixels of the sun's (a degree spans n / 180 px radially
    // and at most pi / 2 times that across, at the horizon; 2 px spare).
    const int reach = int(std::ceil(degrees * n / 180.0 * kPiD / 2)) + 2;
    const int ci = int(std::lround(x)), cj = int(std::lround(y));
    for (int j = std::max(0, cj - reach); j <= std::min(n - 1, cj + reach); ++j)
        for (int i = std::max(0, ci - reach); i <= std::min(n - 1, ci + reach); ++i)
            if (fisheye::pixel_center_uv(i, j, n).squaredNorm() <= 1 &&
                fisheye::direction_from_pixel(i, j, n).dot(s) >= cos_max)
                mask.at<uint8_t>(j, i) = 255;
    return mask;
}

cv::Mat sun_unseen_mask(int n, const Vec3d& sun) {
    cv::Mat mask = sun_cut_mask(n, sun);
    if (!(sun.y() > 0)) return mask;
    return mask | sun_cone_mask(n, sun, kSunUnseenDeg);
}

SunPatch remove_sun(SkyImage* sky) {
    SunPatch patch;
    if (!sky->sun_direction || sky->sun_direction->y() <= 0) return patch;
    const int n = sky->resolution;
    double x, y;
    fisheye::pixel_from_direction(sky->sun_direction->cast<double>(), n, &x, &y);
    const int ci = int(std::lround(x)), cj = int(std::lround(y));
    const int radius = sun_cut_radius(n), margin = 3 * radius;
    const int i0 = std::max(0, ci - margin), i1 = std::min(n - 1, ci + margin);
    const int j0 = std::max(0, cj - margin), j1 = std::min(n - 1, cj + margin);
    if (i1 <= i0 || j1 <= j0) return patch;
    std::vector<float> around;
    for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i)
            if (sky->in_disc(i, j)) around.push_back(luminance(sky->pixel(i, j)));
    if (around.empty()) return patch;
    const float threshold = 20.0f * std::max(median(std::move(around)), 1e-6f);
    patch.fx = x - ci, patch.fy = y - cj;

    const int w = i1 - i0 + 1, h = j1 - j0 + 1;
    cv::Mat mask = cv::Mat::zeros(h, w, CV_8UC1);
    for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i)
            if ((i - ci) * (i - ci) + (j - cj) * (j - cj) <= radius * radius && sky->in_disc(i, j) &&
                luminance(sky->pixel(i, j)) > threshold)
                mask.at<uint8_t>(j - j0, i - i0) = 255;
    if (cv::countNonZero(mask) == 0) return patch;
    cv::dilate(mask, mask, cv::Mat());  // the disc's soft limb too
    // Filled with the clear sky's background of its sun (Hosek-Wilkie, no disc) times the median
    // ratio of the sky to it on the pixels around the cut, per channel: the aureole peaks at the
    // sun, and an inpainting from the surroundings (cv::inpaint, Telea) left a hole darker than the
    // background, with specks of 0.4 and 4 x it at 128 px, which the cloud models took for a dark
    // cloud and carried off with the wind (a dark speck leaving the sun of a clear sky).
    ClearSkyParams cp;
    cp.sun_direction = sky->sun_direction->cast<double>();
    cp.sun_disc = false;
    const ClearSkyModel clear(cp, false);
    std::vector<float> ratios[3];
    for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
            if (mask.at<uint8_t>(j - j0, i - i0) || !sky->in_disc(i, j)) continue;
            const Color b = clear.sky_radiance(fisheye::direction_from_pixel(i, j, n)), v = sky->pixel(i, j);
            for (int c = 0; c < 3; ++c)
                if (b[c] > 0) ratios[c].push_back(v[c] / b[c]);
        }
    Color ratio = Color::Ones();
    for (int c = 0; c < 3; ++c)
        if (!ratios[c].empty()) ratio[c] = median(std::move(ratios[c]));
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            if (!mask.at<uint8_t>(j, i) || !sky->in_disc(i + i0, j + j0)) continue;
            const Color before = sky->pixel(i + i0, j + j0);
            const Color fill = clear.sky_radiance(fisheye::direction_from_pixel(i + i0, j + j0, n)) * ratio;
            const Color after = before.min(fill.max(0.0f));
            sky->set_pixel(i + i0, j + j0, after);
            patch.di.push_back(i + i0 - ci), patch.dj.push_back(j + j0 - cj);
            patch.excess.push_back(before - after);
        }
    return patch;
}

SunPatch clear_sun_patch(int n, const Vec3d& sun_in, double turbidity) {
    SunPatch patch;
    const Vec3d sun = sun_in.normalized();
    if (!(sun.y() > 0)) return patch;
    ClearSkyParams cp;
    cp.sun_direction = sun;
    cp.turbidity = turbidity;
    const ClearSkyModel model(cp, false);
    double x, y;
    fisheye::pixel_from_direction(sun, n, &x, &y);
    const int ci = int(std::lround(x)), cj = int(std::lround(y));
    patch.fx = x - ci, patch.fy = y - cj;
    std::map<std::pair<int, int>, Color> disc;  // a pixel may come several times
    model.splat_sun_disc(n, [&](int i, int j, const Color& c) {
        disc.emplace(std::make_pair(j, i), Color::Zero()).first->second += c;
    });
    for (const auto& [p, c] : disc) {
        patch.di.push_back(p.second - ci), patch.dj.push_back(p.first - cj);
        patch.excess.push_back(c);
    }
    return patch;
}

double sun_patch_share(const SunPatch& patch, int n, const Vec3d& sun_in, double turbidity) {
    const Vec3d sun = sun_in.normalized();
    if (patch.empty() || !(sun.y() > 0)) return 0.0;
    ClearSkyParams cp;
    cp.sun_direction = sun;
    cp.turbidity = turbidity;
    const double clear = luminance(ClearSkyModel(cp, false).sun_irradiance());
    if (!(clear > 0)) return 0.0;
    double x, y;
    fisheye::pixel_from_direction(sun, n, &x, &y);
    const int ci = int(std::lround(x)), cj = int(std::lround(y));
    double e = 0;
    for (size_t k = 0; k < patch.di.size(); ++k)
        e += luminance(patch.excess[k]) * fisheye::pixel_solid_angle(ci + patch.di[k], cj + patch.dj[k], n);
    return e / clear;
}

void insert_sun(SkyImage* sky, const SunPatch& patch, const Vec3d& direction, double weight) {
    if (patch.empty() || direction.y() <= 0 || weight == 0.0) return;
    const int n = sky->resolution;
    double x, y;
    fisheye::pixel_from_direction(direction, n, &x, &y);
    const int ci = int(std::lround(x)), cj = int(std::lround(y));
    // The displacement within the pixel grid: the patch's pixel (ci, cj) plus the sun's move
    // inside it, split into a whole-pixel part and bilinear weights. Zero at the cut's own
    // position (within a float direction's rounding), so the sun goes back on its pixels bit for bit.
    auto split = [](double shift, int* whole, double* frac) {
        if (std::abs(shift) < 1e-3) shift = 0;
        *whole = int(std::floor(shift));
        *frac = shift - *whole;
    };
    int wx, wy;
    double ax, ay;
    split((x - ci) - patch.fx, &wx, &ax);
    split((y - cj) - patch.fy, &wy, &ay);
    auto add = [&](int i, int j, const Color& c) {
        if (i < 0 || j < 0 || i >= n || j >= n || !sky->in_disc(i, j)) return;
        sky->set_pixel(i, j, sky->pixel(i, j) + c);
    };
    for (size_t k = 0; k < patch.di.size(); ++k) {
        const int i = ci + wx + patch.di[k], j = cj + wy + patch.dj[k];
        const Color e = float(weight) * patch.excess[k];
        if (ax == 0 && ay == 0) {
            add(i, j, e);
            continue;
        }
        add(i, j, float((1 - ax) * (1 - ay)) * e);
        if (ax > 0) add(i + 1, j, float(ax * (1 - ay)) * e);
        if (ay > 0) add(i, j + 1, float((1 - ax) * ay) * e);
        if (ax > 0 && ay > 0) add(i + 1, j + 1, float(ax * ay) * e);
    }
}

double sun_pixel_solid_angle(int n, const Vec3d& direction) {
    double x = 0, y = 0;
    fisheye::pixel_from_direction(direction, n, &x, &y);
    const int i0 = int(std::floor(x)), j0 = int(std::floor(y));
    const double ax = x - i0, ay = y - j0;
    double omega[2][2];
    for (int dj = 0; dj < 2; ++dj)
        for (int di = 0; di < 2; ++di) {
            const int i = i0 + di, j = j0 + dj;
            omega[dj][di] = i < 0 || j < 0 || i >= n || j >= n ? 0.0 : fisheye::pixel_solid_angle(i, j, n);
        }
    // At the rim a neighbour outside the disc has none: the nearest pixel's there.
    if (!(omega[0][0] > 0 && omega[0][1] > 0 && omega[1][0] > 0 && omega[1][1] > 0)) {
        const int i = std::clamp(int(std::lround(x)), 0, n - 1), j = std::clamp(int(std::lround(y)), 0, n - 1);
        return fisheye::pixel_solid_angle(i, j, n);
    }
    return (1 - ay) * ((1 - ax) * omega[0][0] + ax * omega[0][1]) + ay * ((1 - ax) * omega[1][0] + ax * omega[1][1]);
}

Color sun_patch_relight(int n, const Vec3d& from, const Vec3d& to, double turbidity) {
    ClearSkyParams p;
    p.turbidity = turbidity;
    p.sun_disc = true;
    p.sun_direction = from;
    const Color before = ClearSkyModel(p, false).sun_irradiance();
    p.sun_direction = to;
    const Color after = ClearSkyModel(p, false).sun_irradiance();
    const double omega_from = sun_pixel_solid_angle(n, from), omega_to = sun_pixel_solid_angle(n, to);
    const double moved = omega_from > 0 && omega_to > 0 ? omega_from / omega_to : 1.0;
    Color factor = Color::Ones();
    for (int k = 0; k < 3; ++k) factor[k] = float(moved) * (before[k] > 0 ? after[k] / before[k] : 1.0f);
    return factor;
}

std::optional<Vec3d> sun_from_brightest_pixels(const SkyImage& sky) {
    const int n = sky.resolution;
    cv::Mat lum(n, n, CV_32FC1, cv::Scalar(0));
    std::vector<float> values;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            if (sky.in_disc(i, j)) {
                const float l = float(luminance(sky.pixel(i, j)));
                lum.at<float>(j, i) = std::isfinite(l) ? l : 0.0f;
                values.push_back(lum.at<float>(j, i));
            }
    if (values.empty()) return std::nullopt;
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    const double median_lum = values[values.size() / 2];
    double top = 0;
    cv::minMaxLoc(lum, nullptr, &top);
    if (!(top > 0) || !(top > 2.0 * median_lum)) return std::nullopt;
    const cv::Mat bright = lum >= 0.98f * float(top);
    cv::Mat labels, stats, centroids;
    const int count = cv::connectedComponentsWithStats(bright, labels, stats, centroids, 8, CV_32S);
    int best = 0;
    for (int l = 1; l < count; ++l)
        if (best == 0 || stats.at<int>(l, cv::CC_STAT_AREA) > stats.at<int>(best, cv::CC_STAT_AREA)) best = l;
    if (best == 0) return std::nullopt;
    constexpr double kPi = 3.14159265358979323846;
    const double area = stats.at<int>(best, cv::CC_STAT_AREA), disc = 0.25 * kPi * n * n;
    const double d = std::max(stats.at<int>(best, cv::CC_STAT_WIDTH), stats.at<int>(best, cv::CC_STAT_HEIGHT));
    if (area > 0.03 * disc || area < 0.33 * 0.25 * kPi * d * d) return std::nullopt;
    const Vec3d sun = fisheye::direction_from_pixel(centroids.at<double>(best, 0), centroids.at<double>(best, 1), n);
    // Near the horizon an overexposed cloud or haze can be the brightest; a sun that is 1000 x the
    // sky's median is a sun there too (a sunset HDRI's, 1.7 degrees up: left in, its sky moved as
    // overcast and its glow was dragged across the sky).
    const double floor = top > 1000.0 * median_lum ? 0.0 : std::sin(5.0 * kPi / 180.0);
    if (!(sun.y() > floor)) return std::nullopt;
    return sun.normalized();
}

cv::Mat fill_saturated_pixels(cv::Mat* unit) {
    cv::Mat& state = *unit;
    const cv::Mat disc_big = sky_disc_mask(state.rows);
    cv::Mat sun = saturated_pixels(state);
    if (cv::countNonZero(sun) > 0) {
        cv::dilate(sun, sun, cv::Mat());
        // Filled from the unclipped pixels around them by normalised convolution (a Gaussian-weighted
        // mean of the known neighbours, widening until every pixel has some): unlike Telea's
        // inpainting on float images it cannot overshoot (it did, to 2.3 on a clear sky's sun).
        cv::Mat known = (~sun) & disc_big, weight, values;
        known.convertTo(weight, CV_32F, 1.0 / 255.0);
        cv::Mat weight3;
        cv::merge(std::vector<cv::Mat>{weight, weight, weight}, weight3);
        cv::Mat remaining = sun.clone();
        for (double sigma = 1.0; sigma <= state.rows && cv::countNonZero(remaining) > 0; sigma *= 2) {
            cv::Mat num, den;
            cv::GaussianBlur(state.mul(weight3), num, cv::Size(0, 0), sigma, sigma, cv::BORDER_REFLECT);
            cv::GaussianBlur(weight, den, cv::Size(0, 0), sigma, sigma, cv::BORDER_REFLECT);
            for (int y = 0; y < state.rows; ++y)
                for (int x = 0; x < state.cols; ++x) {
                    if (!remaining.at<uint8_t>(y, x) || den.at<float>(y, x) < 1e-3f) continue;
                    state.at<cv::Vec3f>(y, x) = num.at<cv::Vec3f>(y, x) / den.at<float>(y, x);
                    remaining.at<uint8_t>(y, x) = 0;
                }
        }
        cv::min(cv::max(state, 0.0), 1.0, state);
        state.setTo(cv::Scalar::all(0), ~disc_big);
    }
    return sun;
}

void restore_pixels(SkyImage* sky, const SkyImage& from, const cv::Mat& mask, double transmittance) {
    const float t = float(std::clamp(transmittance, 0.0, 1.0));
    for (int y = 0; y < sky->resolution; ++y)
        for (int x = 0; x < sky->resolution; ++x)
            if (mask.at<uint8_t>(y, x)) sky->set_pixel(x, y, t * from.pixel(x, y) + (1.0f - t) * sky->pixel(x, y));
}

double cloudiness(const Color& v, const Color& m, const SunTransmittanceParams& p) {
    const double lv = luminance(v), lm = luminance(m);
    if (!(lm > 0) || !(m[2] > 0)) return 0.0;
    const double rb = (v[0] + 1e-9) / (v[2] + 1e-9), rb_clear = m[0] / m[2];
    const double brightness = std::max(lv, 1e-12) / lm;
    // How far towards cloud, in units of each threshold (1: at the threshold).
    const double whiter = std::log(rb / rb_clear) / std::log(p.cloud_ratio);
    const double departs = std::abs(std::log(brightness)) / std::log(p.brightness_ratio);
    const double x = std::max(whiter, departs);
    if (p.edge_softness <= 0) return x > 1 ? 1 : 0;
    return smoothstep01((x - (1 - p.edge_softness)) / (2 * p.edge_softness));
}

namespace {

// The clear share of the pixels within outer_deg of the sun (cloud_at(i, j, direction): the
// pixel's cloudiness, negative to leave it out), each weighted by 1 / (angle^2 + core_deg^2),
// through the smoothstep from covered_share to clear_share; 1 when no pixel counts.
template <typename CloudAt>
double transmittance_around_sun(int n, const Vec3d& sun, const SunTransmittanceParams& p, CloudAt cloud_at) {
    const double cos_in = std::cos(p.inner_deg * kPiD / 180), cos_out = std::cos(p.outer_deg * kPiD / 180);
    // The ring's bounding box in pixels (the mapping is equidistant: 90 degrees = n / 2 pixels).
    double sx, sy;
    fisheye::pixel_from_direction(sun, n, &sx, &sy);
    const int reach = int(std::ceil(p.outer_deg / 90.0 * n / 2)) + 2;
    // About 4000 samples whatever the resolution.
    const int stride = std::max(1, int(reach * 2 / 64));
    double clear = 0, total = 0;
    for (int j = std::max(0, int(sy) - reach); j <= std::min(n - 1, int(sy) + reach); j += stride)
        for (int i = std::max(0, int(sx) - reach); i <= std::min(n - 1, int(sx) + reach); i += stride) {
            if (fisheye::pixel_center_uv(i, j, n).squaredNorm() > 1.0f) continue;  // SkyImage::in_disc
            const Vec3d w = fisheye::direction_from_pixel(i, j, n);
            const double c = w.dot(sun);
            if (c > cos_in || c < cos_out || w.y() < 0.05) continue;
            const double cloud = cloud_at(i, j, w);
            if (cloud < 0) continue;
            const double angle = std::acos(std::clamp(c, -1.0, 1.0)), core = p.core_deg * kPiD / 180;
            const double weight = 1.0 / (angle * angle + core * core);  // the cloud at the sun counts most
            total += weight;
            clear += weight * (1 - cloud);
        }
    if (!(total > 0)) return 1.0;
    // The clear share through a smoothstep: three quarters clear around the sun lets it all
    // through, a quarter none (a sun is behind a cloud or not; the share only says how likely).
    return smoothstep01((clear / total - p.covered_share) / (p.clear_share - p.covered_share));
}

}  // namespace

double estimate_sun_transmittance(const SkyImage& sky, const Vec3d& sun_in, const SunTransmittanceParams& p) {
    const Vec3d sun = sun_in.normalized();
    if (!(sun.y() > 0.0)) return 1.0;
    ClearSkyParams cp;
    cp.sun_direction = sun;
    cp.turbidity = p.turbidity;
    cp.sun_disc = false;
    const ClearSkyModel model(cp, false);
    return transmittance_around_sun(sky.resolution, sun, p, [&](int i, int j, const Vec3d& w) {
        const Color m = model.sky_radiance(w);
        if (!(luminance(m) > 0) || !(m[2] > 0)) return -1.0;
        return cloudiness(sky.pixel(i, j), m, p);
    });
}

double sun_transmittance_of_opacity(const cv::Mat& opacity, const Vec3d& sun_in, const SunTransmittanceParams& p) {
    const Vec3d sun = sun_in.normalized();
    if (!(sun.y() > 0.0) || opacity.empty()) return 1.0;
    if (opacity.type() != CV_32FC1 || opacity.rows != opacity.cols)
        throw Error("sun transmittance: the opacity map must be square CV_32FC1");
    return transmittance_around_sun(opacity.rows, sun, p, [&](int i, int j, const Vec3d&) {
        return double(std::clamp(opacity.at<float>(j, i), 0.0f, 1.0f));
    });
}

double sun_weight_reference(double start_transmittance, double input_sun_share) {
    return std::max({start_transmittance, std::min(1.0, input_sun_share), 0.05});
}

double relative_transmittance(double moved, double start) {
    const double e = std::max(0.0, 0.05 - start);
    return std::clamp((moved + e) / (start + e), 0.0, 1.0);
}

double relative_sun_transmittance(const SkyImage& moved, const SkyImage& start, std::optional<Vec3d> sun) {
    if (!sun && start.sun_direction) sun = start.sun_direction->cast<double>();
    if (!sun) return 1.0;
    return relative_transmittance(estimate_sun_transmittance(moved, *sun), estimate_sun_transmittance(start, *sun));
}

double opacity_sun_weight(double moved_opacity_t, double start_opacity_t, double start_look, double input_sun_share,
                          double travel, double start_cloud_share) {
    const double own = relative_transmittance(moved_opacity_t, start_opacity_t);
    if (start_look < 0.05 && input_sun_share >= 0.05 && start_cloud_share >= kOvercastCloudShare) return own;
    const double moved = std::clamp(moved_opacity_t / sun_weight_reference(start_opacity_t, input_sun_share), 0.0, 1.0);
    travel = std::clamp(travel, 0.0, 1.0);
    return (1.0 - travel) * own + travel * moved;
}

double cloud_share(const cv::Mat& opacity) {
    if (opacity.empty()) return 1.0;
    const cv::Mat disc = sky_disc_mask(opacity.rows);
    const int all = cv::countNonZero(disc);
    return all ? double(cv::countNonZero((opacity >= 0.5) & disc)) / all : 1.0;
}

double sun_diameter_px(int resolution) { return 0.53 / 90.0 * resolution / 2.0; }

double sun_travel_fraction(double displacement_px, int resolution) {
    // The sun's own diameter: clouds that moved less have not changed what covers it.
    return std::clamp(displacement_px / sun_diameter_px(resolution), 0.0, 1.0);
}

}  // namespace dynsky
