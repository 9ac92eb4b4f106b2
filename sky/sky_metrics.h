// Comparing predicted skies with real ones, and the two baselines every cloud model must beat:
// persistence (the next frame is the current one) and Farneback extrapolation (the current frame
// advected by the optical flow of the previous pair, constant velocity).
//
// Images here are the networks' [0, 1] form (sky/hdr_recovery.h), CV_32FC3 or CV_32FC1, N x N.
// Every metric is taken only over the pixels set in a CV_8UC1 mask (normally the sky disc, minus
// pixels a camera cannot see); the definitions follow ../shared/NOTES.md:
// - MSE: mean over masked pixels and channels of (a - b)^2.
// - PSNR: 10 log10(1 / MSE) (range 1), capped at kMaxPsnr for identical images. A sequence's
//   PSNR is the mean of its per-frame PSNRs (how the paper's 23.67 dB is computed).
// - SSIM: Wang et al. 2004 with an 11 x 11 Gaussian window, sigma 1.5, K1 = 0.01, K2 = 0.03,
//   dynamic range 1; the SSIM map of each channel averaged over the masked pixels, then over
//   channels. Unlike OpenCV contrib's quality module it does not assume a 0-255 range.
#pragma once

#include <opencv2/core.hpp>

namespace dynsky {

constexpr double kMaxPsnr = 100.0;

struct ImageComparison {
    double mse = 0.0;
    double psnr = 0.0;
    double ssim = 0.0;
};

// The sky disc of an N x N canonical image (pixel centres with r <= 1) as a CV_8UC1 mask (255 in).
cv::Mat sky_disc_mask(int resolution);

// Throw dynsky::Error when sizes, types or the mask do not match, or the mask is empty.
double masked_mse(const cv::Mat& a, const cv::Mat& b, const cv::Mat& mask);
double psnr_from_mse(double mse);
double masked_ssim(const cv::Mat& a, const cv::Mat& b, const cv::Mat& mask);
ImageComparison compare_images(const cv::Mat& prediction, const cv::Mat& truth, const cv::Mat& mask);

// Dense optical flow from `from` to `to` (OpenCV's Farneback on the luminance), CV_32FC2 in
// pixels: the content at x in `from` is near x + flow(x) in `to`.
struct FarnebackParams {
    double pyr_scale = 0.5;
    int levels = 3;
    int winsize = 15;
    int iterations = 3;
    int poly_n = 5;
    double poly_sigma = 1.2;
};
cv::Mat farneback_flow(const cv::Mat& from, const cv::Mat& to, const FarnebackParams& params = {});

// Advects an image along a flow field for `steps` steps at constant velocity:
// out(x) = image(x - steps * flow(x)) (bilinear; outside the image reads 0). The backward lookup
// through the flow at the destination is the usual first-order stand-in for forward splatting.
cv::Mat advect_by_flow(const cv::Mat& image, const cv::Mat& flow, double steps);

// The Farneback-extrapolation baseline: the flow of previous -> current, applied `steps` times to
// current.
cv::Mat extrapolate_farneback(const cv::Mat& previous, const cv::Mat& current, int steps,
                              const FarnebackParams& params = {});

}  // namespace dynsky
