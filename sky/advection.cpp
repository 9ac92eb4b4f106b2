#include "sky/advection.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "util/error.h"

namespace dynsky {

Vec3d direction_from_pixel(double x, double y, int n) {
    double u = 2.0 * (x + 0.5) / n - 1.0, v = 2.0 * (y + 0.5) / n - 1.0;
    double r = std::sqrt(u * u + v * v);
    double theta = r * kPiD / 2, phi = std::atan2(-u, -v);
    double s = std::sin(theta);
    return Vec3d(s * std::sin(phi), std::cos(theta), -s * std::cos(phi));
}

void pixel_from_direction(const Vec3d& w, int n, double* x, double* y) {
    double theta = std::acos(std::clamp(w.y() / w.norm(), -1.0, 1.0));
    double phi = std::atan2(w.x(), -w.z());
    double r = 2.0 * theta / kPiD;
    double u = -r * std::sin(phi), v = -r * std::cos(phi);
    *x = (u + 1.0) * n / 2.0 - 0.5;
    *y = (v + 1.0) * n / 2.0 - 0.5;
}

namespace {

cv::Mat sky_mat(const SkyImage& sky) {
    cv::Mat m(sky.resolution, sky.resolution, CV_32FC3, const_cast<float*>(sky.rgb.data()));
    return m;  // a view; callers clone when they keep it
}

cv::Mat disc_mask(int n, double margin_px) {
    cv::Mat m(n, n, CV_32FC1);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            double u = 2.0 * (i + 0.5) / n - 1.0, v = 2.0 * (j + 0.5) / n - 1.0;
            double r_px = std::sqrt(u * u + v * v) * n / 2.0;
            m.at<float>(j, i) = r_px <= n / 2.0 - margin_px ? 1.0f : 0.0f;
        }
    return m;
}

}  // namespace

cv::Mat fill_flow_holes(const cv::Mat& flow, const cv::Mat& confidence, double sigma_px) {
    CV_Assert(flow.type() == CV_32FC2 && confidence.type() == CV_32FC1 && flow.size() == confidence.size());
    cv::Mat c2;
    cv::merge(std::vector<cv::Mat>{confidence, confidence}, c2);
    cv::Mat weighted = flow.mul(c2), num, den;
    cv::GaussianBlur(weighted, num, cv::Size(0, 0), sigma_px, sigma_px, cv::BORDER_REFLECT);
    cv::GaussianBlur(confidence, den, cv::Size(0, 0), sigma_px, sigma_px, cv::BORDER_REFLECT);
    cv::Mat out(flow.size(), CV_32FC2);
    for (int j = 0; j < flow.rows; ++j)
        for (int i = 0; i < flow.cols; ++i) {
            float c = confidence.at<float>(j, i), d = den.at<float>(j, i);
            cv::Vec2f filled = d > 1e-4f ? num.at<cv::Vec2f>(j, i) / d : cv::Vec2f(0, 0);
            out.at<cv::Vec2f>(j, i) = c * flow.at<cv::Vec2f>(j, i) + (1.0f - c) * filled;
        }
    return out;
}

cv::Mat estimate_sky_flow(const SkyImage& from, const SkyImage& to, const SkyFlowParams& params) {
    if (from.resolution != to.resolution || from.resolution < 8)
        throw Error("estimate_sky_flow: the two skies must have the same resolution (got " +
                    std::to_string(from.resolution) + " and " + std::to_string(to.resolution) + ")");
    const int n = from.resolution, w = std::min(params.work_resolution, n);
    // Log luminance at the working size, one mapping for both images so brightness is comparable.
    auto log_lum = [&](const SkyImage& s) {
        cv::Mat small;
        cv::resize(sky_mat(s), small, cv::Size(w, w), 0, 0, cv::INTER_AREA);
        cv::Mat lum(w, w, CV_32FC1);
        for (int j = 0; j < w; ++j)
            for (int i = 0; i < w; ++i) {
                cv::Vec3f p = small.at<cv::Vec3f>(j, i);
                lum.at<float>(j, i) = std::log(std::max(0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2], 0.0f) + 1e-3f);
            }
        return lum;
    };
    cv::Mat a = log_lum(from), b = log_lum(to);
    cv::Mat disc = disc_mask(w, 1.5);
    std::vector<float> values;
    for (int j = 0; j < w; ++j)
        for (int i = 0; i < w; ++i)
            if (disc.at<float>(j, i) > 0) values.push_back(a.at<float>(j, i)), values.push_back(b.at<float>(j, i));
    std::sort(values.begin(), values.end());
    float lo = values[values.size() / 100], hi = values[values.size() * 99 / 100];
    if (hi - lo < 1e-3f) hi = lo + 1e-3f;
    auto to8 = [&](const cv::Mat& m, cv::Mat* unit) {
        *unit = (m - lo) / (hi - lo);
        cv::Mat c;
        cv::min(cv::max(*unit, 0.0), 1.0, c);
        *unit = c.mul(disc);
        cv::Mat out;
        unit->convertTo(out, CV_8UC1, 255.0);
        return out;
    };
    cv::Mat ua, ub;
    cv::Mat a8 = to8(a, &ua), b8 = to8(b, &ub);
    cv::Mat flow;
    int win = std::max(5, w * 15 / 512);
    cv::calcOpticalFlowFarneback(a8, b8, flow, 0.5, 5, win, 3, 5, 1.2, 0);

    // Confidence: texture to track in the first image (Farneback's estimate means nothing on flat areas).
    cv::Mat gx, gy, grad;
    cv::Sobel(ua, gx, CV_32F, 1, 0, 3, 1.0 / 8);
    cv::Sobel(ua, gy, CV_32F, 0, 1, 3, 1.0 / 8);
    cv::magnitude(gx, gy, grad);
    cv::blur(grad, grad, cv::Size(5, 5));
    cv::Mat conf = grad / params.min_texture;
    cv::min(conf, 1.0, conf);
    conf = conf.mul(disc_mask(w, 3.0));
    cv::Mat filled = fill_flow_holes(flow, conf, params.fill_sigma * w);
    cv::Mat out;
    cv::resize(filled, out, cv::Size(n, n), 0, 0, cv::INTER_LINEAR);
    out *= double(n) / w;
    return out;
}

namespace {

cv::Vec2f sample_flow(const cv::Mat& flow, double x, double y) {
    const int n = flow.cols;
    x = std::clamp(x, 0.0, n - 1.0), y = std::clamp(y, 0.0, n - 1.0);
    int x0 = std::min(int(x), n - 2), y0 = std::min(int(y), n - 2);
    float fx = float(x - x0), fy = float(y - y0);
    return (1 - fy) * ((1 - fx) * flow.at<cv::Vec2f>(y0, x0) + fx * flow.at<cv::Vec2f>(y0, x0 + 1)) +
           fy * ((1 - fx) * flow.at<cv::Vec2f>(y0 + 1, x0) + fx * flow.at<cv::Vec2f>(y0 + 1, x0 + 1));
}

// The sky with every pixel outside the disc holding the rim's value along its radius, so that
// bilinear lookups at the horizon never mix in the black corners.
cv::Mat extend_past_rim(const cv::Mat& src) {
    const int n = src.cols;
    const double r_in = 1.0 - 1.5 / n;
    cv::Mat map_x(n, n, CV_32FC1), map_y(n, n, CV_32FC1);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            double u = 2.0 * (i + 0.5) / n - 1.0, v = 2.0 * (j + 0.5) / n - 1.0, r = std::sqrt(u * u + v * v);
            if (r > r_in) u *= r_in / r, v *= r_in / r;
            map_x.at<float>(j, i) = float((u + 1.0) * n / 2.0 - 0.5);
            map_y.at<float>(j, i) = float((v + 1.0) * n / 2.0 - 0.5);
        }
    cv::Mat out;
    cv::remap(src, out, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    return out;
}

}  // namespace

SkyImage advect_great_arc(const SkyImage& sky, const cv::Mat& flow, double fraction) {
    const int n = sky.resolution;
    if (flow.type() != CV_32FC2 || flow.rows != n || flow.cols != n)
        throw Error("advect_great_arc: flow must be " + std::to_string(n) + "x" + std::to_string(n) + " CV_32FC2");
    SkyImage out = sky;
    if (fraction == 0.0) return out;
    // The lookup maps are smooth (the flow is), so they are computed on a grid of at most 512^2 and
    // resized: the per-pixel trigonometry then costs the same for 1024 and 2048 skies.
    const int m = std::min(n, 512);
    cv::Mat map_x(m, m, CV_32FC1), map_y(m, m, CV_32FC1);
    // The flow belongs to where content starts: output pixel q shows the source p whose own arc,
    // followed for `fraction`, ends at q. Found by fixed-point iteration from p = q (a few steps
    // suffice for flows that vary smoothly); each step rotates q back along p's arc.
    constexpr int kIterations = 8;
    tbb::parallel_for(0, m, [&](int cj) {
        for (int ci = 0; ci < m; ++ci) {
            const double i = (ci + 0.5) * n / m - 0.5, j = (cj + 0.5) * n / m - 0.5;
            const Vec3d d = direction_from_pixel(i, j, n);
            double px = i, py = j;
            Vec3d src = d;
            for (int it = 0; it < kIterations; ++it) {
                cv::Vec2f f = sample_flow(flow, px, py);
                Vec3d from = direction_from_pixel(px, py, n), to = direction_from_pixel(px + f[0], py + f[1], n);
                Vec3d c = from.cross(to);
                double s = c.norm();
                if (s < 1e-12) {
                    src = d;
                } else {
                    Vec3d axis = c / s;
                    double g = -fraction * std::atan2(s, from.dot(to));
                    // Rodrigues (q need not be perpendicular to the axis).
                    src = d * std::cos(g) + axis.cross(d) * std::sin(g) + axis * axis.dot(d) * (1 - std::cos(g));
                }
                double nx, ny;
                pixel_from_direction(src, n, &nx, &ny);
                if (std::abs(nx - px) < 1e-3 && std::abs(ny - py) < 1e-3) break;
                px = nx, py = ny;
            }
            double x, y;
            pixel_from_direction(src, n, &x, &y);
            map_x.at<float>(cj, ci) = float(x);
            map_y.at<float>(cj, ci) = float(y);
        }
    });
    if (m != n) {
        cv::resize(map_x, map_x, cv::Size(n, n), 0, 0, cv::INTER_LINEAR);
        cv::resize(map_y, map_y, cv::Size(n, n), 0, 0, cv::INTER_LINEAR);
    }
    cv::Mat dst(n, n, CV_32FC3, out.rgb.data());
    cv::remap(extend_past_rim(sky_mat(sky)), dst, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    clear_outside_disc(&out);
    return out;
}

cv::Mat rotation_flow(int n, const Vec3d& axis, double angle) {
    Eigen::AngleAxisd rot(angle, axis.normalized());
    Eigen::Matrix3d r = rot.toRotationMatrix();
    cv::Mat flow(n, n, CV_32FC2);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            double x, y;
            pixel_from_direction(r * direction_from_pixel(i, j, n), n, &x, &y);
            flow.at<cv::Vec2f>(j, i) = cv::Vec2f(float(x - i), float(y - j));
        }
    return flow;
}

}  // namespace dynsky
