#include "sky/sky_metrics.h"

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include <cmath>
#include <string>

#include "sky/fisheye.h"
#include "util/error.h"

namespace dynsky {

namespace {

void check_pair(const cv::Mat& a, const cv::Mat& b, const cv::Mat& mask, const char* what) {
    if (a.empty() || b.empty()) throw Error(std::string(what) + ": empty image");
    if (a.size() != b.size() || a.type() != b.type())
        throw Error(std::string(what) + ": images differ in size or type (" + std::to_string(a.cols) + "x" +
                    std::to_string(a.rows) + " vs " + std::to_string(b.cols) + "x" + std::to_string(b.rows) + ")");
    if (a.depth() != CV_32F) throw Error(std::string(what) + ": images must be 32-bit float");
    if (mask.size() != a.size() || mask.type() != CV_8UC1)
        throw Error(std::string(what) + ": the mask must be 8-bit, one channel, the images' size");
    if (cv::countNonZero(mask) == 0) throw Error(std::string(what) + ": the mask selects no pixel");
}

cv::Mat to_grey(const cv::Mat& image) {
    if (image.channels() == 1) return image;
    cv::Mat grey;
    cv::cvtColor(image, grey, image.channels() == 4 ? cv::COLOR_RGBA2GRAY : cv::COLOR_RGB2GRAY);
    return grey;
}

}  // namespace

cv::Mat sky_disc_mask(int resolution) {
    cv::Mat mask(resolution, resolution, CV_8UC1);
    for (int j = 0; j < resolution; ++j)
        for (int i = 0; i < resolution; ++i)
            mask.at<uint8_t>(j, i) = fisheye::pixel_center_uv(i, j, resolution).squaredNorm() <= 1.0f ? 255 : 0;
    return mask;
}

double masked_mse(const cv::Mat& a, const cv::Mat& b, const cv::Mat& mask) {
    check_pair(a, b, mask, "mse");
    cv::Mat diff;
    cv::subtract(a, b, diff, cv::noArray(), CV_64F);
    diff = diff.mul(diff);
    cv::Scalar sum = cv::sum(diff.setTo(0, ~mask));
    double total = 0;
    for (int c = 0; c < a.channels(); ++c) total += sum[c];
    return total / (double(cv::countNonZero(mask)) * a.channels());
}

double psnr_from_mse(double mse) {
    if (!(mse >= 0)) return std::nan("");
    if (mse <= std::pow(10.0, -kMaxPsnr / 10.0)) return kMaxPsnr;
    return std::min(kMaxPsnr, 10.0 * std::log10(1.0 / mse));
}

double masked_ssim(const cv::Mat& a, const cv::Mat& b, const cv::Mat& mask) {
    check_pair(a, b, mask, "ssim");
    const double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;  // (K L)^2 with L = 1
    const cv::Size window(11, 11);
    const double sigma = 1.5;
    std::vector<cv::Mat> ca, cb;
    cv::split(a, ca);
    cv::split(b, cb);
    double total = 0;
    const double count = cv::countNonZero(mask);
    for (size_t c = 0; c < ca.size(); ++c) {
        cv::Mat x, y;
        ca[c].convertTo(x, CV_64F);
        cb[c].convertTo(y, CV_64F);
        // Reflected borders: the image edge (outside the disc, 0 in both) is not a real feature.
        auto blur = [&](const cv::Mat& m) {
            cv::Mat out;
            cv::GaussianBlur(m, out, window, sigma, sigma, cv::BORDER_REFLECT);
            return out;
        };
        cv::Mat mx = blur(x), my = blur(y);
        cv::Mat sxx = blur(x.mul(x)) - mx.mul(mx);
        cv::Mat syy = blur(y.mul(y)) - my.mul(my);
        cv::Mat sxy = blur(x.mul(y)) - mx.mul(my);
        cv::Mat num = (2 * mx.mul(my) + c1).mul(2 * sxy + c2);
        cv::Mat den = (mx.mul(mx) + my.mul(my) + c1).mul(sxx + syy + c2);
        cv::Mat map;
        cv::divide(num, den, map);
        total += cv::sum(map.setTo(0, ~mask))[0] / count;
    }
    return total / double(ca.size());
}

ImageComparison compare_images(const cv::Mat& prediction, const cv::Mat& truth, const cv::Mat& mask) {
    ImageComparison r;
    r.mse = masked_mse(prediction, truth, mask);
    r.psnr = psnr_from_mse(r.mse);
    r.ssim = masked_ssim(prediction, truth, mask);
    return r;
}

cv::Mat farneback_flow(const cv::Mat& from, const cv::Mat& to, const FarnebackParams& p) {
    if (from.empty() || from.size() != to.size() || from.type() != to.type())
        throw Error("farneback_flow: the two images differ in size or type, or are empty");
    cv::Mat g0, g1;
    // On the 0-255 scale of the 8-bit frames the usual parameters were tuned for.
    to_grey(from).convertTo(g0, CV_32F, 255.0);
    to_grey(to).convertTo(g1, CV_32F, 255.0);
    cv::Mat flow;
    cv::calcOpticalFlowFarneback(g0, g1, flow, p.pyr_scale, p.levels, p.winsize, p.iterations, p.poly_n,
                                 p.poly_sigma, 0);
    return flow;
}

cv::Mat advect_by_flow(const cv::Mat& image, const cv::Mat& flow, double steps) {
    if (flow.type() != CV_32FC2 || flow.size() != image.size())
        throw Error("advect_by_flow: the flow must be CV_32FC2 of the image's size");
    cv::Mat map(flow.size(), CV_32FC2);
    for (int y = 0; y < flow.rows; ++y) {
        const cv::Vec2f* f = flow.ptr<cv::Vec2f>(y);
        cv::Vec2f* m = map.ptr<cv::Vec2f>(y);
        for (int x = 0; x < flow.cols; ++x)
            m[x] = cv::Vec2f(float(x - steps * f[x][0]), float(y - steps * f[x][1]));
    }
    cv::Mat out;
    cv::remap(image, out, map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar::all(0));
    return out;
}

cv::Mat extrapolate_farneback(const cv::Mat& previous, const cv::Mat& current, int steps,
                              const FarnebackParams& params) {
    return advect_by_flow(current, farneback_flow(previous, current, params), steps);
}

}  // namespace dynsky
