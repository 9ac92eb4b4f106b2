// Comparing predicted skies with real ones. The two baselines every cloud model must beat are
// persistence (the next frame is the current one) and Farneback extrapolation (the current frame
// advected by the optical flow of the previous pair, constant velocity: motion/advection.h).
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

#include "sky/fisheye.h"  // sky_disc_mask

namespace dynsky {

constexpr double kMaxPsnr = 100.0;

struct ImageComparison {
    double mse = 0.0;
    double psnr = 0.0;
    double ssim = 0.0;
};

// Throw dynsky::Error when sizes, types or the mask do not match, or the mask is empty.
double masked_mse(const cv::Mat& a, const cv::Mat& b, const cv::Mat& mask);
double psnr_from_mse(double mse);
double masked_ssim(const cv::Mat& a, const cv::Mat& b, const cv::Mat& mask);
ImageComparison compare_images(const cv::Mat& prediction, const cv::Mat& truth, const cv::Mat& mask);

// High-frequency energy: mean squared difference between the image and its Gaussian blur (sigma
// 2 px), over the mask's pixels and the channels. A rollout that blurs loses it; one that runs away
// gains it.
double high_frequency_energy(const cv::Mat& image, const cv::Mat& mask);

}  // namespace dynsky
