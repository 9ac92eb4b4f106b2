#include "motion/cloud_layer_paths.h"

#include <tbb/parallel_for.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "util/error.h"
#include "util/math.h"

namespace dynsky {

namespace {

constexpr double kHalfPi = 1.5707963267948966;

inline double zenith_of(double u, double v) { return std::min(std::hypot(u, v) * kHalfPi, kMaxLayerZenith); }

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
        !(params.entry_band > 0) || !(params.seam_edge_band > 0) ||
        !(params.seam_range >= 0 && params.seam_range < 0.9) || !(params.seam_slope > 0))
        throw Error("CloudLayerPaths: parameters out of range");
    const double length = std::hypot(step[0], step[1]);
    moving_ = std::isfinite(length) && length > 1e-9;
    along_ = moving_ ? step / length : cv::Vec2d(1, 0);
    across_ = cv::Vec2d(-along_[1], along_[0]);
    tile_radius_ = std::tan(params.tile_zenith_deg * kHalfPi / 90.0);
    seam_ = {-tile_radius_}, seam_step_ = 1.0;
    trigger_radius_.create(n, n, CV_64FC1);
    beyond_.assign(size_t(n) * n, 0);
    points_.create(n, n, CV_64FC2);
    const double root_stretch = std::sqrt(params.max_stretch);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const double u = 2.0 * (x + 0.5) / n - 1.0, v = 2.0 * (y + 0.5) / n - 1.0;
            const double trigger = std::min(std::acos(std::cos(zenith_of(u, v)) / root_stretch), kMaxLayerZenith);
            trigger_radius_.at<double>(y, x) = std::max(tile_radius_, std::tan(trigger));
            beyond_[size_t(y) * n + x] = std::hypot(u, v) * kHalfPi > kMaxLayerZenith;
            points_.at<cv::Vec2d>(y, x) = layer_point(x, y, n);
        }
}

void CloudLayerPaths::choose_seam(const cv::Mat& opacity) {
    if (opacity.type() != CV_32FC1 || opacity.rows != n_ || opacity.cols != n_)
        throw Error("CloudLayerPaths::choose_seam: expected a CV_32FC1 opacity of the paths' resolution");
    if (!moving_ || params_.seam_range <= 0) return;
    // The opacity widened by 2 % of the radius (a max filter), so the seam keeps clear of cloud edges.
    cv::Mat wide;
    const int r = std::max(1, int(std::lround(0.02 * n_ / 2.0)));
    cv::dilate(opacity, wide, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * r + 1, 2 * r + 1)));
    auto opacity_at = [&](double s, double c) {
        const cv::Vec2d p = pixel_of_layer_point(s * along_ + c * across_, n_);
        const int x = std::clamp(int(std::lround(p[0])), 0, n_ - 1), y = std::clamp(int(std::lround(p[1])), 0, n_ - 1);
        return double(wide.at<float>(y, x));
    };
    // Candidates a_j across [-R (1 + range), -R (1 - range)], streamlines c_i = i dc over 3 R; the
    // cost of cutting at (c, a): the opacity at both ends of both mirrored strips (where the passes
    // meet), plus a little for leaving the tile's edge (a tie-break towards the middle).
    const double R = tile_radius_, P = period(), lo = -R * (1 + params_.seam_range), hi = -R * (1 - params_.seam_range);
    const int na = 49, nc = 97;
    const double da = (hi - lo) / (na - 1), dc = 3.0 * R / (nc - 1);
    const int reach = std::max(1, int(std::floor(params_.seam_slope * dc / da)));
    std::vector<double> best(size_t(na) * nc);
    std::vector<int> from(size_t(na) * nc, 0);
    for (int i = 0; i < nc; ++i) {
        const double c = i * dc;
        for (int j = 0; j < na; ++j) {
            const double a = lo + j * da;
            double cost = opacity_at(a, c) + opacity_at(a, -c) + opacity_at(a + P, c) + opacity_at(a + P, -c) +
                          0.01 * std::abs(a + R) / R;
            if (i > 0) {
                int arg = std::max(0, j - reach);
                for (int jj = arg; jj <= std::min(na - 1, j + reach); ++jj)
                    if (best[size_t(i - 1) * na + jj] < best[size_t(i - 1) * na + arg]) arg = jj;
                cost += best[size_t(i - 1) * na + arg];
                from[size_t(i) * na + j] = arg;
            }
            best[size_t(i) * na + j] = cost;
        }
    }
    int j = 0;
    for (int jj = 1; jj < na; ++jj)
        if (best[size_t(nc - 1) * na + jj] < best[size_t(nc - 1) * na + j]) j = jj;
    seam_.assign(nc, 0.0);
    for (int i = nc - 1; i >= 0; --i) {
        seam_[i] = lo + j * da;
        j = from[size_t(i) * na + j];
    }
    seam_step_ = dc;
}

double CloudLayerPaths::seam(double c) const {
    const double t = std::abs(c) / seam_step_;
    const size_t i = size_t(t);
    if (i + 1 >= seam_.size()) return seam_.back();
    return seam_[i] + (t - double(i)) * (seam_[i + 1] - seam_[i]);
}

CloudLayerPaths::Reads CloudLayerPaths::at(double k) const {
    Reads reads;
    for (int i = 0; i < kReadCount; ++i) {
        reads.positions[i].create(n_, n_, CV_32FC2);
        reads.weights[i] = cv::Mat::zeros(n_, n_, CV_32FC1);
    }
    const double R = tile_radius_, P = period();
    const double centre = (n_ - 1) / 2.0, rim = (1.0 - 1.5 / n_) * n_ / 2.0, band = 0.03 * n_ / 2.0;
    tbb::parallel_for(0, n_, [&](int y) {
        cv::Vec2f* pos[kReadCount];
        float* wgt[kReadCount];
        for (int i = 0; i < kReadCount; ++i)
            pos[i] = reads.positions[i].ptr<cv::Vec2f>(y), wgt[i] = reads.weights[i].ptr<float>(y);
        const double* trigger = trigger_radius_.ptr<double>(y);
        const cv::Vec2d* point = points_.ptr<cv::Vec2d>(y);
        for (int x = 0; x < n_; ++x) {
            for (int i = 0; i < kReadCount; ++i) pos[i][x] = cv::Vec2f(float(x), float(y));
            if (beyond_[y * n_ + x]) {  // past 88 degrees the layer does not move (as wind_flow)
                wgt[kOwnRead][x] = 1.0f;
                continue;
            }
            const cv::Vec2d source = point[x] - k * step_;
            const double s = source.dot(along_), c = source.dot(across_), a = seam(c);
            // Where the pixel's path has crossed the seam: the tile, pass j >= 1 (mirrored across the
            // wind on odd passes).
            double into_tile = 0;
            if (moving_ && s < a) {
                // Upwind of the seam at the start (near the upwind horizon) a pixel keeps the real
                // start while it is not too foreshortened, then dissolves into the tile; downwind
                // of it, a pixel reads the tile once its path has crossed the seam. Within
                // seam_edge_band of the seam line the downwind pixels blend in the upwind rule,
                // so the two meet without a hard arc fixed in the image.
                const double rho_t = trigger[x], s_t = -std::sqrt(std::max(rho_t * rho_t - c * c, R * R));
                const double upwind_rule = std::clamp((s_t - s) / (params_.entry_band * rho_t), 0.0, 1.0);
                const double past_seam = point[x].dot(along_) - a;
                const double w = past_seam < 0 ? 0.0 : std::min(1.0, past_seam / (params_.seam_edge_band * R));
                into_tile = w + (1.0 - w) * upwind_rule;
            }
            if (into_tile > 0) {
                // Pass j, and over the first seam_band of it the pass before (j - 1 = 0: the real
                // start) taking its leave: no seam is clear everywhere.
                const double passes = (a - s) / P, j = std::max(1.0, std::ceil(passes));
                const double leave = std::clamp(1.0 - (passes - (j - 1.0)) / params_.seam_band, 0.0, 1.0);
                auto pass = [&](double i) {
                    const double ci = std::fmod(i, 2.0) == 1.0 ? -c : c;
                    const cv::Vec2d p = pixel_of_layer_point((s + i * P) * along_ + ci * across_, n_);
                    return cv::Vec2f(float(p[0]), float(p[1]));
                };
                pos[kTileRead][x] = pass(j);
                wgt[kTileRead][x] = float(into_tile * (1.0 - leave));
                if (leave > 0 && j >= 2)
                    pos[kLeavingRead][x] = pass(j - 1), wgt[kLeavingRead][x] = float(into_tile * leave);
                if (leave > 0 && j < 2) into_tile *= 1.0 - leave;  // the real start continues
                if (into_tile >= 1) continue;
            }
            // The real start image along the layer's path. A read from the last few percent of the
            // radius is of sky barely resolved: the pixel shows what the start showed there instead
            // (the horizon hardly moves).
            const cv::Vec2d real = pixel_of_layer_point(source, n_);
            pos[kRealRead][x] = cv::Vec2f(float(real[0]), float(real[1]));
            const double r_src = std::hypot(real[0] - centre, real[1] - centre);
            const double own = std::clamp((r_src - (rim - band)) / band, 0.0, 1.0);
            wgt[kRealRead][x] = float((1.0 - into_tile) * (1.0 - own));
            wgt[kOwnRead][x] = float((1.0 - into_tile) * own);
        }
    });
    return reads;
}

}  // namespace dynsky
