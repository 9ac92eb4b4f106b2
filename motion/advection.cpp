#include "motion/advection.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <mutex>
#include <opencv2/imgproc.hpp>

#include "sky/fisheye.h"
#include "util/error.h"

namespace dynsky {

namespace {

cv::Mat sky_mat(const SkyImage& sky) {
    cv::Mat m(sky.resolution, sky.resolution, CV_32FC3, const_cast<float*>(sky.rgb.data()));
    return m;  // a view; callers clone when they keep it
}

}  // namespace

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


namespace {

SkyImage advect_along_arcs(const SkyImage& sky, const cv::Mat& flow, double fraction, bool from_end) {
    const int n = sky.resolution;
    if (flow.type() != CV_32FC2 || flow.rows != n || flow.cols != n)
        throw Error("advect_great_arc: flow must be " + std::to_string(n) + "x" + std::to_string(n) + " CV_32FC2");
    SkyImage out = sky;
    if (!from_end && fraction == 0.0) return out;
    if (from_end && fraction == 1.0) return out;
    // The lookup maps are smooth (the flow is), so they are computed on a grid of at most 256^2 and
    // resized: the per-pixel trigonometry then costs the same for 1024 and 2048 skies. (At 512^2 a
    // 1024 sky's constant-pace frame cost 362 ms; at 256^2 255 ms, its frames within 1e-5 of the
    // display range on average and 5/255 at worst.)
    const int m = std::min(n, 256);
    cv::Mat map_x(m, m, CV_32FC1), map_y(m, m, CV_32FC1);
    // The flow belongs to where content starts: output pixel q shows the source p whose own arc,
    // followed for `fraction`, ends at q. Found by fixed-point iteration from p = q (a few steps
    // suffice for flows that vary smoothly); each step rotates q back along p's arc.
    constexpr int kIterations = 8;
    tbb::parallel_for(0, m, [&](int cj) {
        for (int ci = 0; ci < m; ++ci) {
            const double i = (ci + 0.5) * n / m - 0.5, j = (cj + 0.5) * n / m - 0.5;
            const Vec3d d = fisheye::direction_from_pixel(i, j, n);
            double px = i, py = j;
            Vec3d src = d;
            for (int it = 0; it < kIterations; ++it) {
                cv::Vec2f f = sample_flow(flow, px, py);
                Vec3d from = fisheye::direction_from_pixel(px, py, n),
                      to = fisheye::direction_from_pixel(px + f[0], py + f[1], n);
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
                fisheye::pixel_from_direction(src, n, &nx, &ny);
                if (std::abs(nx - px) < 1e-3 && std::abs(ny - py) < 1e-3) break;
                px = nx, py = ny;
            }
            if (from_end) {
                // src is where q's content starts (p): the step after shows it at the end of p's
                // own arc. Carried back along the flow at q instead (the flow of where content
                // ends, not starts), the two steps' copies met a few pixels apart wherever the flow
                // varies, and every in-between frame of a 1024 px sky doubled its cloud edges.
                double fx, fy;
                fisheye::pixel_from_direction(src, n, &fx, &fy);
                const cv::Vec2f f = sample_flow(flow, fx, fy);
                src = fisheye::direction_from_pixel(fx + f[0], fy + f[1], n);  // the whole arc's end
            }
            double x, y;
            fisheye::pixel_from_direction(src, n, &x, &y);
            map_x.at<float>(cj, ci) = float(x);
            map_y.at<float>(cj, ci) = float(y);
        }
    });
    if (m != n) {
        cv::resize(map_x, map_x, cv::Size(n, n), 0, 0, cv::INTER_LINEAR);
        cv::resize(map_y, map_y, cv::Size(n, n), 0, 0, cv::INTER_LINEAR);
    }
    cv::Mat dst(n, n, CV_32FC3, out.rgb.data());
    // Bicubic: bilinear reads at a fractional offset soften the sky, so in-between frames were
    // blurred and each step sharp again (fine detail pulsed every medium step, 0.68 of the steps'
    // midway). Its overshoot is clamped to the source's range around each read (the 3 x 3 minimum
    // and maximum, read as the pixel is): no ringing at cloud edges or the rim, no negative light.
    const cv::Mat source = extend_past_rim(sky_mat(sky));
    cv::Mat lo, hi, low, high;
    cv::erode(source, lo, cv::Mat());
    cv::dilate(source, hi, cv::Mat());
    cv::remap(source, dst, map_x, map_y, cv::INTER_CUBIC, cv::BORDER_REPLICATE);
    cv::remap(lo, low, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    cv::remap(hi, high, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    cv::min(cv::max(dst, low), high, dst);
    clear_outside_disc(&out);
    return out;
}

}  // namespace

SkyImage advect_great_arc(const SkyImage& sky, const cv::Mat& flow, double fraction) {
    return advect_along_arcs(sky, flow, fraction, false);
}

SkyImage advect_great_arc_from_end(const SkyImage& end, const cv::Mat& flow, double fraction) {
    return advect_along_arcs(end, flow, fraction, true);
}

cv::Mat advect_by_flow(const cv::Mat& image, const cv::Mat& flow, double steps) {
    if (flow.type() != CV_32FC2 || flow.size() != image.size())
        throw Error("advect_by_flow: the flow must be CV_32FC2 of the image's size");
    cv::Mat map(flow.size(), CV_32FC2);
    for (int y = 0; y < flow.rows; ++y) {
        const cv::Vec2f* f = flow.ptr<cv::Vec2f>(y);
        cv::Vec2f* m = map.ptr<cv::Vec2f>(y);
        for (int x = 0; x < flow.cols; ++x) m[x] = cv::Vec2f(float(x - steps * f[x][0]), float(y - steps * f[x][1]));
    }
    cv::Mat out;
    cv::remap(image, out, map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar::all(0));
    return out;
}

cv::Mat extrapolate_farneback(const cv::Mat& previous, const cv::Mat& current, int steps,
                              const FarnebackParams& params) {
    return advect_by_flow(current, farneback_flow(previous, current, params), steps);
}

namespace {

// Bilinear lookup of a float image (any channel count) at map(x) (CV_32FC2, pixel coordinates),
// border replicate, in full float precision: cv::remap rounds positions to 1/32 pixel, which
// differs from PyTorch's grid_sample (the networks' training) by up to 0.006 on sharp edges.
cv::Mat remap_exact(const cv::Mat& src, const cv::Mat& map) {
    const int w = src.cols, h = src.rows, c = src.channels();
    cv::Mat out(map.size(), src.type());
    tbb::parallel_for(0, map.rows, [&](int y) {
        const cv::Vec2f* m = map.ptr<cv::Vec2f>(y);
        float* o = out.ptr<float>(y);
        for (int x = 0; x < map.cols; ++x) {
            // A non-finite source (never made by a finite flow) reads the corner rather than memory
            // outside the image: std::clamp passes NaN through, and int(NaN) is undefined.
            const float sx = std::isfinite(m[x][0]) ? m[x][0] : 0.0f, sy = std::isfinite(m[x][1]) ? m[x][1] : 0.0f;
            const float fx = std::clamp(sx, 0.0f, float(w - 1)), fy = std::clamp(sy, 0.0f, float(h - 1));
            const int x0 = std::min(int(fx), w - 2 < 0 ? 0 : w - 2), y0 = std::min(int(fy), h - 2 < 0 ? 0 : h - 2);
            const int x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
            const float tx = fx - x0, ty = fy - y0;
            const float* a = src.ptr<float>(y0) + size_t(x0) * c;
            const float* b = src.ptr<float>(y0) + size_t(x1) * c;
            const float* d = src.ptr<float>(y1) + size_t(x0) * c;
            const float* e = src.ptr<float>(y1) + size_t(x1) * c;
            for (int k = 0; k < c; ++k)
                o[size_t(x) * c + k] = (1 - ty) * ((1 - tx) * a[k] + tx * b[k]) + ty * ((1 - tx) * d[k] + tx * e[k]);
        }
    });
    return out;
}

// The pixel coordinates extend_past_rim samples for every output pixel (cached per size).
cv::Mat make_rim_map(int n);
const cv::Mat& rim_map(int n) {
    static std::mutex mutex;
    static std::map<int, cv::Mat> cache;
    std::lock_guard<std::mutex> lock(mutex);
    auto it = cache.find(n);
    if (it == cache.end()) it = cache.emplace(n, make_rim_map(n)).first;
    return it->second;
}

cv::Mat make_rim_map(int n) {
    const double r_in = 1.0 - 1.5 / n;
    cv::Mat map(n, n, CV_32FC2);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            double u = 2.0 * (i + 0.5) / n - 1.0, v = 2.0 * (j + 0.5) / n - 1.0, r = std::sqrt(u * u + v * v);
            if (r > r_in) u *= r_in / r, v *= r_in / r;
            map.at<cv::Vec2f>(j, i) = cv::Vec2f(float((u + 1.0) * n / 2.0 - 0.5), float((v + 1.0) * n / 2.0 - 0.5));
        }
    return map;
}

}  // namespace

cv::Mat warp_sources(const cv::Mat& flow, bool recycle) {
    if (flow.type() != CV_32FC2 || flow.rows != flow.cols)
        throw Error("warp_sources: the flow must be square CV_32FC2");
    const int n = flow.rows;
    const double c = (n - 1) / 2.0, r_in = (1.0 - 1.5 / n) * n / 2.0;
    cv::Scalar mean = cv::mean(flow, sky_disc_mask(n));
    double wx = mean[0], wy = mean[1];
    const double wn = std::hypot(wx, wy);
    const bool wrap = recycle && wn > 1e-3;
    if (wrap) wx /= wn, wy /= wn;
    cv::Mat map(flow.size(), CV_32FC2);
    for (int y = 0; y < n; ++y) {
        const cv::Vec2f* f = flow.ptr<cv::Vec2f>(y);
        cv::Vec2f* m = map.ptr<cv::Vec2f>(y);
        for (int x = 0; x < n; ++x) {
            double sx = x - f[x][0] - c, sy = y - f[x][1] - c, r2 = sx * sx + sy * sy;
            if (r2 > r_in * r_in) {
                const double d = sx * wx + sy * wy;
                if (wrap && d < 0) sx -= 2 * d * wx, sy -= 2 * d * wy;  // the upwind side reads downwind
            }
            m[x] = cv::Vec2f(float(sx + c), float(sy + c));
        }
    }
    return map;
}

cv::Mat extend_past_rim_exact(const cv::Mat& image) { return sample_exact(image, rim_map(image.rows)); }

cv::Mat sample_exact(const cv::Mat& image, const cv::Mat& positions) {
    cv::Mat src = image.depth() == CV_32F ? image : cv::Mat();
    if (src.empty()) image.convertTo(src, CV_32F);
    return remap_exact(src, positions);
}

cv::Mat traced_flow(const cv::Mat& flow, int steps) {
    if (flow.type() != CV_32FC2 || flow.rows != flow.cols)
        throw Error("traced_flow: the flow must be CV_32FC2 and square");
    const cv::Mat extended = extend_past_rim_exact(flow);
    cv::Mat identity(flow.size(), CV_32FC2), position;
    for (int y = 0; y < flow.rows; ++y)
        for (int x = 0; x < flow.cols; ++x) identity.at<cv::Vec2f>(y, x) = cv::Vec2f(float(x), float(y));
    position = identity.clone();
    for (int k = 0; k < steps; ++k) position -= k == 0 ? flow : sample_exact(extended, position);
    return identity - position;
}

cv::Mat warp_in_disc(const cv::Mat& image, const cv::Mat& flow) {
    if (flow.type() != CV_32FC2 || flow.size() != image.size() || image.rows != image.cols)
        throw Error("warp_in_disc: the flow must be CV_32FC2 of the (square) image's size");
    cv::Mat out = sample_exact(extend_past_rim_exact(image), warp_sources(flow));
    out.setTo(cv::Scalar::all(0), ~sky_disc_mask(image.rows));
    return out;
}

}  // namespace dynsky
