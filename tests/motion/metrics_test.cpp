// Metrics against closed forms, and the Farneback baseline against known motion.
#include "motion/advection.h"
#include "motion/metrics.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>

#include "util/error.h"

namespace dynsky {
namespace {

cv::Mat full_mask(int n) { return cv::Mat(n, n, CV_8UC1, cv::Scalar(255)); }

// A smooth random texture (blurred noise), like clouds at a coarse scale.
cv::Mat texture(int n, int seed, double blur = 2.5) {
    cv::RNG rng(seed);
    cv::Mat noise(n, n, CV_32FC3);
    rng.fill(noise, cv::RNG::UNIFORM, 0.0, 1.0);
    cv::GaussianBlur(noise, noise, cv::Size(0, 0), blur);
    cv::normalize(noise, noise, 0.05, 0.95, cv::NORM_MINMAX);
    return noise;
}

TEST(SkyMetrics, MseAndPsnrOfAConstantOffset) {
    cv::Mat a(32, 32, CV_32FC3, cv::Scalar(0.3, 0.5, 0.7));
    cv::Mat b = a + cv::Scalar(0.1, 0.1, 0.1);
    EXPECT_NEAR(masked_mse(a, b, full_mask(32)), 0.01, 1e-8);  // float images
    EXPECT_NEAR(psnr_from_mse(0.01), 20.0, 1e-9);
    EXPECT_NEAR(compare_images(a, b, full_mask(32)).psnr, 20.0, 1e-5);  // float images
    EXPECT_DOUBLE_EQ(psnr_from_mse(0.0), kMaxPsnr);
}

TEST(SkyMetrics, OnlyMaskedPixelsCount) {
    cv::Mat a(16, 16, CV_32FC3, cv::Scalar::all(0.5)), b = a.clone();
    cv::Mat mask = cv::Mat::zeros(16, 16, CV_8UC1);
    mask(cv::Rect(0, 0, 8, 16)).setTo(255);
    b(cv::Rect(8, 0, 8, 16)).setTo(cv::Scalar::all(1.0));  // differs only outside the mask
    EXPECT_DOUBLE_EQ(masked_mse(a, b, mask), 0.0);
    b.at<cv::Vec3f>(3, 2) = cv::Vec3f(0.5f, 0.5f, 0.9f);  // one channel of one masked pixel
    EXPECT_NEAR(masked_mse(a, b, mask), 0.16 / (128.0 * 3), 1e-9);
}

TEST(SkyMetrics, SsimOfConstantImagesIsTheLuminanceTerm) {
    // Constant images have zero variance: SSIM = (2 mx my + C1) / (mx^2 + my^2 + C1), C1 = 0.01^2.
    const double mx = 0.4, my = 0.6, c1 = 1e-4;
    cv::Mat a(24, 24, CV_32FC1, cv::Scalar(mx)), b(24, 24, CV_32FC1, cv::Scalar(my));
    EXPECT_NEAR(masked_ssim(a, b, full_mask(24)), (2 * mx * my + c1) / (mx * mx + my * my + c1), 1e-6);
    EXPECT_NEAR(masked_ssim(a, a, full_mask(24)), 1.0, 1e-9);
}

TEST(SkyMetrics, SsimIsSymmetricAndPenalisesNoiseMoreThanGain) {
    cv::Mat a = texture(48, 1), b = a * 0.7;
    double s_ab = masked_ssim(a, b, full_mask(48)), s_ba = masked_ssim(b, a, full_mask(48));
    EXPECT_NEAR(s_ab, s_ba, 1e-9);
    EXPECT_LT(s_ab, 1.0);
    EXPECT_GT(s_ab, 0.8);
    // Noise lowers it much more than a gain.
    cv::Mat noisy = a.clone();
    cv::RNG rng(7);
    cv::Mat n(a.size(), a.type());
    rng.fill(n, cv::RNG::NORMAL, 0.0, 0.1);
    noisy += n;
    EXPECT_LT(masked_ssim(a, noisy, full_mask(48)), s_ab - 0.2);
}

TEST(SkyMetrics, DiscMaskCoversPiOverFourOfTheSquare) {
    cv::Mat m = sky_disc_mask(256);
    EXPECT_NEAR(cv::countNonZero(m) / (256.0 * 256.0), 3.14159265358979 / 4.0, 0.002);
}

TEST(SkyMetrics, AdvectionByAnIntegerFlowIsAShift) {
    cv::Mat img = texture(40, 3);
    cv::Mat flow(40, 40, CV_32FC2, cv::Scalar(2.0f, 1.0f));
    cv::Mat out = advect_by_flow(img, flow, 1.0);
    for (int y = 1; y < 40; ++y)
        for (int x = 2; x < 40; ++x)
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(out.at<cv::Vec3f>(y, x)[c], img.at<cv::Vec3f>(y - 1, x - 2)[c], 1e-5f);
    EXPECT_EQ(out.at<cv::Vec3f>(0, 0)[0], 0.0f);  // read from outside: 0
    // Two steps of (2, 1) = one of (4, 2).
    cv::Mat two = advect_by_flow(img, flow, 2.0);
    EXPECT_NEAR(two.at<cv::Vec3f>(20, 20)[1], img.at<cv::Vec3f>(18, 16)[1], 1e-5f);
}

TEST(SkyMetrics, FarnebackRecoversAKnownShiftAndBeatsPersistence) {
    const int n = 96;
    cv::Mat big = texture(n + 20, 5, 3.0);
    // Content moves by (+1.5, -1) px per frame: frame k is the texture shifted by k (1.5, -1).
    cv::Mat f0, f1, f2;
    auto shifted = [&](double dx, double dy) {
        cv::Mat out, m = (cv::Mat_<double>(2, 3) << 1, 0, dx, 0, 1, dy);
        cv::warpAffine(big, out, m, big.size(), cv::INTER_CUBIC, cv::BORDER_REFLECT);
        return out(cv::Rect(10, 10, n, n)).clone();
    };
    f0 = shifted(0, 0), f1 = shifted(1.5, -1), f2 = shifted(3, -2);
    cv::Mat flow = farneback_flow(f0, f1);
    ASSERT_EQ(flow.type(), CV_32FC2);
    cv::Scalar mean = cv::mean(flow(cv::Rect(16, 16, n - 32, n - 32)));
    EXPECT_NEAR(mean[0], 1.5, 0.15);
    EXPECT_NEAR(mean[1], -1.0, 0.15);
    cv::Mat inner = cv::Mat::zeros(n, n, CV_8UC1);
    inner(cv::Rect(8, 8, n - 16, n - 16)).setTo(255);
    double extrapolated = compare_images(extrapolate_farneback(f0, f1, 1), f2, inner).psnr;
    double persistence = compare_images(f1, f2, inner).psnr;
    EXPECT_GT(extrapolated, persistence + 8.0) << extrapolated << " vs " << persistence;
}

TEST(SkyMetrics, MismatchedInputsThrowClearly) {
    cv::Mat a(8, 8, CV_32FC3, cv::Scalar::all(0)), b(9, 9, CV_32FC3, cv::Scalar::all(0));
    try {
        masked_mse(a, b, full_mask(8));
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("differ in size"), std::string::npos) << e.what();
    }
    EXPECT_THROW(masked_ssim(a, a, cv::Mat::zeros(8, 8, CV_8UC1)), Error);  // empty mask
    EXPECT_THROW(masked_mse(a, a, full_mask(9)), Error);
}

}  // namespace
}  // namespace dynsky
