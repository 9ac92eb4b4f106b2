#include "motion/flow.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "motion/cloud_layer_paths.h"
#include "sky/fisheye.h"
#include "util/error.h"
#include "util/parse.h"

namespace dynsky {

namespace {

cv::Mat sky_mat(const SkyImage& sky) {
    cv::Mat m(sky.resolution, sky.resolution, CV_32FC3, const_cast<float*>(sky.rgb.data()));
    return m;  // a view; callers clone when they keep it
}

// 1 inside the disc shrunk by margin_px, else 0 (CV_32FC1).
cv::Mat disc_weight(int n, double margin_px) {
    cv::Mat m(n, n, CV_32FC1);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            double u = 2.0 * (i + 0.5) / n - 1.0, v = 2.0 * (j + 0.5) / n - 1.0;
            double r_px = std::sqrt(u * u + v * v) * n / 2.0;
            m.at<float>(j, i) = r_px <= n / 2.0 - margin_px ? 1.0f : 0.0f;
        }
    return m;
}

cv::Mat to_grey(const cv::Mat& image) {
    if (image.channels() == 1) return image;
    cv::Mat grey;
    cv::cvtColor(image, grey, image.channels() == 4 ? cv::COLOR_RGBA2GRAY : cv::COLOR_RGB2GRAY);
    return grey;
}

}  // namespace

cv::Mat farneback(const cv::Mat& from, const cv::Mat& to, const FarnebackParams& p) {
    cv::Mat flow;
    cv::calcOpticalFlowFarneback(from, to, flow, p.pyr_scale, p.levels, p.winsize, p.iterations, p.poly_n, p.poly_sigma,
                                 0);
    return flow;
}

cv::Mat farneback_flow(const cv::Mat& from, const cv::Mat& to, const FarnebackParams& p) {
    if (from.empty() || from.size() != to.size() || from.type() != to.type())
        throw Error("farneback_flow: the two images differ in size or type, or are empty");
    cv::Mat g0, g1;
    // On the 0-255 scale of the 8-bit frames the usual parameters were tuned for.
    to_grey(from).convertTo(g0, CV_32F, 255.0);
    to_grey(to).convertTo(g1, CV_32F, 255.0);
    return farneback(g0, g1, p);
}

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
    if (from.resolution != to.resolution)
        throw Error("estimate_sky_flow: the two skies must have the same resolution (got " +
                    std::to_string(from.resolution) + " and " + std::to_string(to.resolution) + ")");
    if (from.resolution < 8)
        throw Error("the skies are " + std::to_string(from.resolution) + " x " + std::to_string(from.resolution) +
                    " pixels: too small to measure the clouds' motion (at least 8 x 8)");
    const int n = from.resolution, w = std::min(params.work_resolution, n);
    // Log luminance at the working size, one mapping for both images so brightness is comparable.
    auto log_lum = [&](const SkyImage& s) {
        cv::Mat small;
        cv::resize(sky_mat(s), small, cv::Size(w, w), 0, 0, cv::INTER_AREA);
        cv::Mat lum(w, w, CV_32FC1);
        for (int j = 0; j < w; ++j)
            for (int i = 0; i < w; ++i) {
                cv::Vec3f p = small.at<cv::Vec3f>(j, i);
                lum.at<float>(j, i) = std::log(std::max(luminance(p[0], p[1], p[2]), 0.0f) + 1e-3f);
            }
        return lum;
    };
    cv::Mat a = log_lum(from), b = log_lum(to);
    cv::Mat disc = disc_weight(w, 1.5);
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
    FarnebackParams fp = params.farneback;
    fp.winsize = std::max(5, w * fp.winsize / 512);
    flow = farneback(a8, b8, fp);

    // Confidence: texture to track in the first image (Farneback's estimate means nothing on flat areas).
    cv::Mat gx, gy, grad;
    cv::Sobel(ua, gx, CV_32F, 1, 0, 3, 1.0 / 8);
    cv::Sobel(ua, gy, CV_32F, 0, 1, 3, 1.0 / 8);
    cv::magnitude(gx, gy, grad);
    cv::blur(grad, grad, cv::Size(5, 5));
    cv::Mat conf = grad / params.min_texture;
    cv::min(conf, 1.0, conf);
    conf = conf.mul(disc_weight(w, 3.0));
    cv::Mat filled = fill_flow_holes(flow, conf, params.fill_sigma * w);
    cv::Mat out;
    cv::resize(filled, out, cv::Size(n, n), 0, 0, cv::INTER_LINEAR);
    out *= double(n) / w;
    return out;
}

cv::Mat rotation_flow(int n, const Vec3d& axis, double angle) {
    Eigen::AngleAxisd rot(angle, axis.normalized());
    Eigen::Matrix3d r = rot.toRotationMatrix();
    cv::Mat flow(n, n, CV_32FC2);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            double x, y;
            fisheye::pixel_from_direction(r * fisheye::direction_from_pixel(i, j, n), n, &x, &y);
            flow.at<cv::Vec2f>(j, i) = cv::Vec2f(float(x - i), float(y - j));
        }
    return flow;
}

cv::Mat smooth_motion(const cv::Mat& flow, const cv::Mat& trusted) {
    const double sigma = flow.rows / 32.0;
    cv::Mat out;
    if (trusted.empty() || cv::countNonZero(trusted) == 0) {
        cv::GaussianBlur(flow, out, cv::Size(0, 0), sigma, sigma, cv::BORDER_REPLICATE);
        return out;
    }
    cv::Mat w, w2, weight;
    trusted.convertTo(w, CV_32F, 1.0 / 255.0);
    cv::merge(std::vector<cv::Mat>{w, w}, w2);
    const cv::Mat weighted = flow.mul(w2);
    cv::GaussianBlur(weighted, out, cv::Size(0, 0), sigma, sigma, cv::BORDER_REPLICATE);
    cv::GaussianBlur(w, weight, cv::Size(0, 0), sigma, sigma, cv::BORDER_REPLICATE);
    // Far from every trusted pixel the weight vanishes: widen the reach there, never divide by ~0.
    cv::Mat wide_flow, wide_weight;
    cv::GaussianBlur(weighted, wide_flow, cv::Size(0, 0), 4 * sigma, 4 * sigma, cv::BORDER_REPLICATE);
    cv::GaussianBlur(w, wide_weight, cv::Size(0, 0), 4 * sigma, 4 * sigma, cv::BORDER_REPLICATE);
    for (int j = 0; j < out.rows; ++j)
        for (int i = 0; i < out.cols; ++i) {
            const float a = weight.at<float>(j, i), b = wide_weight.at<float>(j, i);
            cv::Vec2f& o = out.at<cv::Vec2f>(j, i);
            if (a > 1e-3f) o /= a;
            else o = b > 1e-6f ? wide_flow.at<cv::Vec2f>(j, i) / b : cv::Vec2f(0, 0);
        }
    return out;
}

MeasuredMotion consistent_motion(const cv::Mat& forward, const cv::Mat& backward, const cv::Mat& trusted) {
    if (forward.type() != CV_32FC2 || backward.type() != CV_32FC2 || forward.size() != backward.size() ||
        (!trusted.empty() && trusted.size() != forward.size()))
        throw Error("consistent_motion: the two flows (and the trusted mask) must be CV_32FC2 of one size");
    MeasuredMotion m;
    m.smoothed = smooth_motion(forward, trusted);
    m.confirmed = m.smoothed.clone();
    // The backward flow where each pixel's content lands: forward + that = 0 for a consistent pair.
    cv::Mat lands(forward.size(), CV_32FC2);
    for (int j = 0; j < forward.rows; ++j)
        for (int i = 0; i < forward.cols; ++i)
            lands.at<cv::Vec2f>(j, i) = cv::Vec2f(float(i), float(j)) + forward.at<cv::Vec2f>(j, i);
    cv::Mat back_at;
    cv::remap(backward, back_at, lands, cv::Mat(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    const double tau = 0.5 * forward.rows / 256.0;
    cv::Mat agree(forward.size(), CV_32FC1, cv::Scalar(0));
    for (int j = 0; j < forward.rows; ++j)
        for (int i = 0; i < forward.cols; ++i) {
            if (!trusted.empty() && !trusted.at<unsigned char>(j, i)) continue;
            const cv::Vec2f e = forward.at<cv::Vec2f>(j, i) + back_at.at<cv::Vec2f>(j, i);
            const float a = float(std::exp(-double(e.dot(e)) / (tau * tau)));
            agree.at<float>(j, i) = a;
            cv::Vec2f& o = m.confirmed.at<cv::Vec2f>(j, i);
            o = a * forward.at<cv::Vec2f>(j, i) + (1.0f - a) * o;
        }
    // The agreement around each pixel, over the trusted pixels and at the smoothing's scale.
    const double sigma = forward.rows / 32.0;
    cv::Mat w(forward.size(), CV_32FC1, cv::Scalar(1)), num, den;
    if (!trusted.empty()) trusted.convertTo(w, CV_32F, 1.0 / 255.0);
    cv::GaussianBlur(agree, num, cv::Size(0, 0), sigma, sigma, cv::BORDER_REPLICATE);
    cv::GaussianBlur(w, den, cv::Size(0, 0), sigma, sigma, cv::BORDER_REPLICATE);
    m.agreement = cv::min(num / cv::max(den, 1e-3f), 1.0f);
    return m;
}

MeasuredMotion measured_motion(const cv::Mat& previous, const cv::Mat& current, const cv::Mat& trusted) {
    return consistent_motion(farneback_flow(previous, current), farneback_flow(current, previous), trusted);
}

MeasuredMotion MeasuredMotion::at_resolution(int n) const {
    MeasuredMotion m{flow_at_resolution(smoothed, n), flow_at_resolution(confirmed, n), agreement};
    if (!agreement.empty() && agreement.rows != n)
        cv::resize(agreement, m.agreement, cv::Size(n, n), 0, 0,
                   n < agreement.rows ? cv::INTER_AREA : cv::INTER_LINEAR);
    return m;
}

cv::Mat flow_by_source(const cv::Mat& by_destination) {
    if (by_destination.empty()) return cv::Mat();
    if (by_destination.type() != CV_32FC2 || by_destination.rows != by_destination.cols)
        throw Error("flow_by_source: the flow must be square CV_32FC2");
    if (by_destination.rows < 2) return by_destination.clone();  // one displacement: its own inverse's
    // A smooth field (a wind's, a relaxed measurement): found on at most 256^2 and resized, as
    // advect_great_arc's maps are (at 1024^2 the iteration cost 16 reads a pixel).
    if (by_destination.cols > 256)
        return flow_at_resolution(flow_by_source(flow_at_resolution(by_destination, 256)), by_destination.cols);
    const cv::Mat& f = by_destination;
    const int w = f.cols, h = f.rows;
    cv::Mat out(h, w, CV_32FC2);
    tbb::parallel_for(0, h, [&](int py) {
        for (int px = 0; px < w; ++px) {
            cv::Vec2f d = f.at<cv::Vec2f>(py, px);
            for (int it = 0; it < 16; ++it) {
                const cv::Vec2f next = sample_flow(f, px + d[0], py + d[1]);
                const bool settled = std::abs(next[0] - d[0]) < 1e-3f && std::abs(next[1] - d[1]) < 1e-3f;
                d = next;
                if (settled) break;
            }
            out.at<cv::Vec2f>(py, px) = d;
        }
    });
    return out;
}

cv::Mat flow_at_resolution(const cv::Mat& flow, int n) {
    if (flow.rows == n) return flow;
    cv::Mat out;
    cv::resize(flow, out, cv::Size(n, n), 0, 0, n < flow.rows ? cv::INTER_AREA : cv::INTER_LINEAR);
    return out * (double(n) / flow.rows);
}

namespace {

// Flow of a layer displacement w (image axes, units of the layer's height) by destination: the
// point on the layer seen at each pixel, and the pixel its cloud was seen at; none beyond
// kMaxLayerZenith.
cv::Mat layer_flow(int n, double wx, double wy) {
    cv::Mat flow(n, n, CV_32FC2);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const double u = 2.0 * (i + 0.5) / n - 1.0, v = 2.0 * (j + 0.5) / n - 1.0;
            if (std::hypot(u, v) * kPiD / 2 > kMaxLayerZenith) {
                flow.at<cv::Vec2f>(j, i) = cv::Vec2f(0, 0);
                continue;
            }
            const cv::Vec2d source = pixel_of_layer_point(layer_point(i, j, n) - cv::Vec2d(wx, wy), n);
            flow.at<cv::Vec2f>(j, i) = cv::Vec2f(float(i - source[0]), float(j - source[1]));
        }
    return flow;
}

// The layer displacement over dt in image axes (east is left, north up), units of the height.
void layer_displacement(const Wind& w, double dt, double* wx, double* wy) {
    const double to = (w.from_deg + 180.0) * kPiD / 180.0, d = w.speed_mps * dt / w.cloud_height_m;
    const double east = d * std::sin(to), north = d * std::cos(to);
    *wx = -east, *wy = -north;
}

}  // namespace

cv::Mat wind_flow(int n, const Wind& wind, double dt) {
    if (!(wind.cloud_height_m > 0) || !std::isfinite(wind.speed_mps) || !std::isfinite(wind.from_deg))
        throw Error("wind: the cloud height must be positive and the speed and direction finite");
    double wx, wy;
    layer_displacement(wind, dt, &wx, &wy);
    // A layer moved more than a thousand times its height in one step (speed x dt / height) is no
    // motion a sky shows, and an infinite one (1e308 m/s, a height of 1e-308 m) has no flow at all.
    if (!(std::hypot(wx, wy) <= 1e3))
        throw Error("wind: " + number_text(wind.speed_mps) + " m/s at " + number_text(wind.cloud_height_m) +
                    " m moves the clouds " + number_text(std::hypot(wx, wy)) + " times their height in one " +
                    number_text(dt) + " s step: give a speed of at most 300 m/s and a height of at least 10 m");
    return layer_flow(n, wx, wy);
}

Wind fit_wind(const cv::Mat& flow, const cv::Mat& weight, double dt, double cloud_height_m) {
    const int n = flow.rows;
    cv::Mat wgt;
    weight.convertTo(wgt, CV_32F, weight.depth() == CV_8U ? 1.0 / 255.0 : 1.0);
    // Small-displacement Jacobian of layer_flow; two Gauss-Newton rounds for larger winds.
    double wx = 0, wy = 0;
    const double eps = 1e-3;
    for (int round = 0; round < 3; ++round) {
        cv::Mat f0 = layer_flow(n, wx, wy), fx = layer_flow(n, wx + eps, wy), fy = layer_flow(n, wx, wy + eps);
        double a11 = 0, a12 = 0, a22 = 0, b1 = 0, b2 = 0;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const float w = wgt.at<float>(j, i);
                if (!(w > 0)) continue;
                const cv::Vec2f jx = (fx.at<cv::Vec2f>(j, i) - f0.at<cv::Vec2f>(j, i)) / eps;
                const cv::Vec2f jy = (fy.at<cv::Vec2f>(j, i) - f0.at<cv::Vec2f>(j, i)) / eps;
                const cv::Vec2f r = flow.at<cv::Vec2f>(j, i) - f0.at<cv::Vec2f>(j, i);
                a11 += w * jx.dot(jx), a12 += w * jx.dot(jy), a22 += w * jy.dot(jy);
                b1 += w * jx.dot(r), b2 += w * jy.dot(r);
            }
        const double det = a11 * a22 - a12 * a12;
        if (!(std::abs(det) > 1e-12)) break;
        wx += (a22 * b1 - a12 * b2) / det, wy += (a11 * b2 - a12 * b1) / det;
    }
    // Back from image axes to a wind: east = -wx, north = -wy (units of height over dt).
    const double east = -wx, north = -wy, d = std::hypot(east, north);
    Wind w;
    w.cloud_height_m = cloud_height_m;
    w.speed_mps = d * cloud_height_m / dt;
    double to = std::atan2(east, north) * 180.0 / kPiD;
    w.from_deg = std::fmod(to + 180.0 + 720.0, 360.0);
    return w;
}

cv::Vec2f sample_flow(const cv::Mat& flow, double x, double y) {
    const int n = flow.cols;
    x = std::clamp(x, 0.0, n - 1.0), y = std::clamp(y, 0.0, n - 1.0);
    int x0 = std::min(int(x), n - 2), y0 = std::min(int(y), n - 2);
    float fx = float(x - x0), fy = float(y - y0);
    return (1 - fy) * ((1 - fx) * flow.at<cv::Vec2f>(y0, x0) + fx * flow.at<cv::Vec2f>(y0, x0 + 1)) +
           fy * ((1 - fx) * flow.at<cv::Vec2f>(y0 + 1, x0) + fx * flow.at<cv::Vec2f>(y0 + 1, x0 + 1));
}

cv::Vec2f flow_at_direction(const cv::Mat& flow, const Vec3d& direction) {
    double x, y;
    fisheye::pixel_from_direction(direction, flow.rows, &x, &y);
    return flow.at<cv::Vec2f>(std::clamp(int(std::lround(y)), 0, flow.rows - 1),
                              std::clamp(int(std::lround(x)), 0, flow.cols - 1));
}

}  // namespace dynsky
