#include "sky/fill_seams.h"

#include <gtest/gtest.h>

#include <cmath>

#include "util/error.h"

namespace dynsky {
namespace {

// A sky-like ramp outside; inside a disc, the same ramp with a texture, shifted by a level step
// (a fill copied from brighter sky). The solve takes the step away and keeps the texture.
TEST(FillSeams, ALevelStepIsRemovedAndTheTextureKept) {
    const int n = 96;
    cv::Mat image(n, n, CV_32FC3), region = cv::Mat::zeros(n, n, CV_8UC1);
    auto ramp = [](int x, int y) { return 40.0 + 0.2 * x + 0.1 * y; };
    auto texture = [](int x, int y) { return 3.0 * std::sin(0.9 * x) * std::cos(0.7 * y); };
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const bool inside = std::hypot(x - 48.0, y - 40.0) < 20.0;
            const double v = ramp(x, y) + (inside ? 12.0 + texture(x, y) : 0.0);
            image.at<cv::Vec3f>(y, x) = cv::Vec3f(float(v), float(0.5 * v), float(-v));
            if (inside) region.at<unsigned char>(y, x) = 255;
        }
    const cv::Mat before = image.clone();
    remove_fill_seams(&image, region);
    double offset = 0, texture_error = 0, texture_power = 0;
    int count = 0;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            if (!region.at<unsigned char>(y, x)) {
                ASSERT_EQ(image.at<cv::Vec3f>(y, x), before.at<cv::Vec3f>(y, x)) << "known pixels are kept";
                continue;
            }
            const cv::Vec3f v = image.at<cv::Vec3f>(y, x);
            EXPECT_NEAR(v[1], 0.5 * v[0], 1e-3);  // channels solved alike (linear)
            const double departure = v[0] - ramp(x, y);
            offset += departure, ++count;
            texture_error += std::pow(departure - texture(x, y), 2), texture_power += std::pow(texture(x, y), 2);
        }
    offset /= count;
    EXPECT_LT(std::abs(offset), 1.0) << "the 12-unit step is taken away";
    EXPECT_LT(texture_error / texture_power, 0.2) << "the fill's texture is kept";
    // No step at the region's edge: a region pixel and its known neighbour differ by about the
    // ramp's and the texture's own differences, not by the step.
    double edge = 0;
    int edges = 0;
    for (int y = 1; y < n - 1; ++y)
        for (int x = 1; x < n - 1; ++x)
            if (region.at<unsigned char>(y, x) && !region.at<unsigned char>(y, x + 1))
                edge += std::abs(image.at<cv::Vec3f>(y, x)[0] - image.at<cv::Vec3f>(y, x + 1)[0]), ++edges;
    ASSERT_GT(edges, 10);
    EXPECT_LT(edge / edges, 3.0);
}

TEST(FillSeams, ARegionWithNothingKnownAroundItIsAnError) {
    cv::Mat image(8, 8, CV_32FC1, cv::Scalar(1)), region(8, 8, CV_8UC1, cv::Scalar(255));
    EXPECT_THROW(remove_fill_seams(&image, region), Error);
    cv::Mat wrong(8, 8, CV_8UC3);
    EXPECT_THROW(remove_fill_seams(&wrong, region), Error);
}

}  // namespace
}  // namespace dynsky
