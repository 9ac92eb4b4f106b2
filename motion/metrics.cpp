#include "motion/metrics.h"

#include <opencv2/imgproc.hpp>

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

}  // namespace

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

double high_frequency_energy(const cv::Mat& image, const cv::Mat& mask) {
    cv::Mat blurred, diff;
    cv::GaussianBlur(image, blurred, cv::Size(0, 0), 2.0, 2.0, cv::BORDER_REFLECT);
    cv::subtract(image, blurred, diff);
    diff = diff.mul(diff);
    cv::Scalar s = cv::sum(diff.setTo(0, ~mask));
    return (s[0] + s[1] + s[2]) / (3.0 * cv::countNonZero(mask));
}

}  // namespace dynsky
