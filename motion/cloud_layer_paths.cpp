#include "motion/cloud_layer_paths.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "util/error.h"
#include "util/math.h"

namespace dynsky {

namespace {

constexpr double kHalfPi = 1.5707963267948966;
constexpr double kMaxZenith = 88.0 * kHalfPi / 90.0;  // as motion/flow.h wind_flow

inline double zenith_of(double u, double v) { return std::min(std::hypot(u, v) * kHalfPi, kMaxZenith); }

}  // namespace

cv::Vec2d layer_point(double x, double y, int n) {
    const double u = 2.0 * (x + 0.5) / n - 1.0, v = 2.0 * (y + 0.5) / n - 1.0, r = std::hypot(u, v);
    if (r < 1e-12) return {0.0, 0.0};
    const double rho = std::tan(zenith_of(u, v));
    return {rho * u / r, rho * v / r};
}

cv::Vec2d pixel_of_layer_point(const cv::Vec2d& p, int n) {
    const double rho = std::hypot(p[0], p[1]);
    const double r = rho < 1e-12 ? 0.0 : std::atan(rho) / kHalfPi / rho;
    return {(p[0] * r + 1.0) * n / 2.0 - 0.5, (p[1] * r + 1.0) * n / 2.0 - 0.5};
}

cv::Vec2d layer_step_of_flow(const cv::Mat& flow) {
    if (flow.type() != CV_32FC2 || flow.rows != flow.cols || flow.rows < 2)
        throw Error("layer_step_of_flow: expected a square CV_32FC2 flow");
    const int n = flow.rows;
    std::vector<double> dx, dy;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const double u = 2.0 * (x + 0.5) / n - 1.0, v = 2.0 * (y + 0.5) / n - 1.0;
            if (u * u + v * v > 0.25) continue;
            const cv::Vec2f f = flow.at<cv::Vec2f>(y, x);
            const cv::Vec2d d = layer_point(x, y, n) - layer_point(x - f[0], y - f[1], n);
            dx.push_back(d[0]), dy.push_back(d[1]);
        }
    if (dx.empty()) return {0.0, 0.0};
    return {median(dx), median(dy)};
}

CloudLayerPaths::CloudLayerPaths(int n, const cv::Vec2d& step, const CloudLayerPathsParams& params)
    : n_(n), step_(step), params_(params) {
    if (n < 2) throw Error("CloudLayerPaths: the resolution must be at least 2");
    if (!(params.tile_zenith_deg > 10 && params.tile_zenith_deg < 85) || !(params.max_stretch >= 1) ||
        !(params.entry_band > 0) || !(params.cycle_band > 0 && params.cycle_band < 1))
        throw Error("CloudLayerPaths: parameters out of range");
    const double length = std::hypot(step[0], step[1]);
    moving_ = std::isfinite(length) && length > 1e-9;
    along_ = moving_ ? step / length : cv::Vec2d(1, 0);
    across_ = cv::Vec2d(-along_[1], along_[0]);
    tile_radius_ = std::tan(params.tile_zenith_deg * kHalfPi / 90.0);
    trigger_radius_.create(n, n, CV_64FC1);
    beyond_.assign(size_t(n) * n, 0);
    points_.create(n, n, CV_64FC2);
    const double root_stretch = std::sqrt(params.max_stretch);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const double u = 2.0 * (x + 0.5) / n - 1.0, v = 2.0 * (y + 0.5) / n - 1.0;
            const double trigger = std::min(std::acos(std::cos(zenith_of(u, v)) / root_stretch), kMaxZenith);
            trigger_radius_.at<double>(y, x) = std::max(tile_radius_, std::tan(trigger));
            beyond_[size_t(y) * n + x] = std::hypot(u, v) * kHalfPi > kMaxZenith;
            points_.at<cv::Vec2d>(y, x) = layer_point(x, y, n);
        }
}

CloudLayerPaths::Reads CloudLayerPaths::at(double k) const {
    Reads reads;
    for (int i = 0; i < 4; ++i) {
        reads.positions[i].create(n_, n_, CV_32FC2);
        reads.weights[i] = cv::Mat::zeros(n_, n_, CV_32FC1);
    }
    const double R = tile_radius_, beta = params_.cycle_band;
    const double centre = (n_ - 1) / 2.0, rim = (1.0 - 1.5 / n_) * n_ / 2.0, band = 0.03 * n_ / 2.0;
    tbb::parallel_for(0, n_, [&](int y) {
        cv::Vec2f* pos[4];
        float* wgt[4];
        for (int i = 0; i < 4; ++i)
            pos[i] = reads.positions[i].ptr<cv::Vec2f>(y), wgt[i] = reads.weights[i].ptr<float>(y);
        const double* trigger = trigger_radius_.ptr<double>(y);
        const cv::Vec2d* point = points_.ptr<cv::Vec2d>(y);
        for (int x = 0; x < n_; ++x) {
            for (int i = 0; i < 4; ++i) pos[i][x] = cv::Vec2f(float(x), float(y));
            if (beyond_[y * n_ + x]) {  // past 88 degrees the layer does not move (as wind_flow)
                wgt[3][x] = 1.0f;
                continue;
            }
            const cv::Vec2d source = point[x] - k * step_;
            const double s = source.dot(along_), c = source.dot(across_);
            // The real start image, while the cloud's start position is in the tile or not too
            // foreshortened.
            const double rho_t = trigger[x], s_t = -std::sqrt(std::max(rho_t * rho_t - c * c, R * R));
            const double into_tile = moving_ ? std::clamp((s_t - s) / (params_.entry_band * rho_t), 0.0, 1.0) : 0.0;
            const cv::Vec2d real = pixel_of_layer_point(source, n_);
            pos[0][x] = cv::Vec2f(float(real[0]), float(real[1]));
            // A read from the last few percent of the radius is of sky barely resolved: the pixel
            // shows what the start showed there instead (the horizon hardly moves).
            const double r_src = std::hypot(real[0] - centre, real[1] - centre);
            const double own = std::clamp((r_src - (rim - band)) / band, 0.0, 1.0);
            wgt[0][x] = float((1.0 - into_tile) * (1.0 - own));
            wgt[3][x] = float((1.0 - into_tile) * own);
            if (into_tile <= 0.0) continue;
            // The recycled tile: pass j >= 1 reads the strip -R <= s < R of the same streamline
            // (one period 2 R for all of them, so passes do not shear), mirrored across the wind
            // on odd passes.
            const double t = (-R - s) / (2.0 * R);
            auto pass = [&](double j) {
                const double sj = s + 2.0 * R * j, cj = std::fmod(j, 2.0) == 1.0 ? -c : c;
                const cv::Vec2d p = pixel_of_layer_point(sj * along_ + cj * across_, n_);
                return cv::Vec2f(float(p[0]), float(p[1]));
            };
            const double m = std::floor(t);
            if (t >= 1.0 && t - m < beta) {
                const double b = (t - m) / beta;
                pos[1][x] = pass(m), wgt[1][x] = float(into_tile * (1.0 - b));
                pos[2][x] = pass(m + 1), wgt[2][x] = float(into_tile * b);
            } else {
                pos[1][x] = pass(std::max(1.0, std::ceil(t))), wgt[1][x] = float(into_tile);
            }
        }
    });
    return reads;
}

}  // namespace dynsky
