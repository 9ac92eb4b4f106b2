// The recycled layer paths of long rollouts (motion/cloud_layer_paths.h): exact layer translation
// while the clouds are in view, weights that sum to one, and a period of two mirrored passes.
#include "motion/cloud_layer_paths.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "motion/flow.h"

namespace dynsky {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(CloudLayerPaths, LayerPointsRoundTrip) {
    const int n = 256;
    for (int y = 0; y < n; y += 7)
        for (int x = 0; x < n; x += 5) {
            const double u = 2.0 * (x + 0.5) / n - 1, v = 2.0 * (y + 0.5) / n - 1;
            if (std::hypot(u, v) > 0.97) continue;  // beyond 88 degrees the layer is clamped
            const cv::Vec2d back = pixel_of_layer_point(layer_point(x, y, n), n);
            EXPECT_NEAR(back[0], x, 1e-6);
            EXPECT_NEAR(back[1], y, 1e-6);
        }
}

TEST(CloudLayerPaths, TheStepOfAWindsFlowIsItsDisplacement) {
    for (double from : {0.0, 70.0, 200.0, 315.0}) {
        const Wind wind{from, 10.0, 1500.0};
        const double dt = 30.0, d = wind.speed_mps * dt / wind.cloud_height_m, to = (from + 180.0) * kPi / 180.0;
        // Image axes: +x is west, +y is south (north up, east left).
        const cv::Vec2d step = layer_step_of_flow(wind_flow(128, wind, dt));
        EXPECT_NEAR(step[0], -d * std::sin(to), 1e-3) << from;
        EXPECT_NEAR(step[1], -d * std::cos(to), 1e-3) << from;
    }
}

TEST(CloudLayerPaths, FirstStepsReadTheLayerTranslatedByTheWind) {
    const int n = 128;
    const Wind wind{250.0, 12.0, 1500.0};
    const cv::Mat flow = wind_flow(n, wind, 30.0);
    CloudLayerPaths paths(n, layer_step_of_flow(flow));
    ASSERT_TRUE(paths.moving());
    const CloudLayerPaths::Reads reads = paths.at(1.0);
    int checked = 0;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const double u = 2.0 * (x + 0.5) / n - 1, v = 2.0 * (y + 0.5) / n - 1;
            if (std::hypot(u, v) > 0.5) continue;  // within 45 degrees of the zenith: short of the seam
            ASSERT_FLOAT_EQ(reads.weights[0].at<float>(y, x), 1.0f);
            const cv::Vec2f f = flow.at<cv::Vec2f>(y, x), p = reads.positions[0].at<cv::Vec2f>(y, x);
            EXPECT_NEAR(p[0], x - f[0], 0.01);
            EXPECT_NEAR(p[1], y - f[1], 0.01);
            ++checked;
        }
    EXPECT_GT(checked, 3000);
}

TEST(CloudLayerPaths, LongRolloutsRecycleWithAPeriodOfTwoMirroredPasses) {
    const int n = 96;
    const cv::Vec2d step(0.1, -0.05);
    CloudLayerPathsParams params;
    CloudLayerPaths paths(n, step, params);
    const double R = std::tan(params.tile_zenith_deg * kPi / 180.0);
    const double period = 4.0 * R / std::hypot(step[0], step[1]);  // two passes of 2 R each
    const double k = 20.0 * period + 3.3;                          // hours of steps
    const CloudLayerPaths::Reads a = paths.at(k), b = paths.at(k + period), half = paths.at(k + period / 2);
    double max_diff = 0, mirrored_diff = 0;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            float sum = 0;
            for (int i = 0; i < CloudLayerPaths::kReadCount; ++i) {
                sum += a.weights[i].at<float>(y, x);
                EXPECT_GE(a.weights[i].at<float>(y, x), 0.0f);
                max_diff = std::max(max_diff, double(cv::norm(a.positions[i].at<cv::Vec2f>(y, x) -
                                                              b.positions[i].at<cv::Vec2f>(y, x))) *
                                                  a.weights[i].at<float>(y, x));
                mirrored_diff += cv::norm(a.positions[i].at<cv::Vec2f>(y, x) - half.positions[i].at<cv::Vec2f>(y, x));
            }
            EXPECT_NEAR(sum, 1.0f, 1e-5);
        }
    EXPECT_LT(max_diff, 0.05);                // one period later: the same reads
    EXPECT_GT(mirrored_diff / (n * n), 1.0);  // half a period later: other (mirrored) clouds
}

TEST(CloudLayerPaths, NoWindNoRecycling) {
    CloudLayerPaths paths(64, cv::Vec2d(0, 0));
    EXPECT_FALSE(paths.moving());
    const CloudLayerPaths::Reads r = paths.at(1000.0);
    EXPECT_EQ(cv::countNonZero(r.weights[CloudLayerPaths::kTileRead]), 0);
    EXPECT_EQ(cv::countNonZero(r.weights[CloudLayerPaths::kLeavingRead]), 0);
}

// The seam where passes meet is cut through clear sky: on a layer that is cloud everywhere but
// along a wavy clear lane (and its copy one period downwind), the seam follows the lane; with no
// opacity given it is straight, at the tile's upwind edge.
TEST(CloudLayerPaths, TheSeamRunsThroughClearSky) {
    const int n = 512;
    const cv::Vec2d step(0.2, 0.0);  // the wind along +x: s = x, c = y on the layer
    CloudLayerPathsParams params;
    CloudLayerPaths paths(n, step, params);
    const double R = std::tan(params.tile_zenith_deg * kPi / 180.0), P = paths.period();
    EXPECT_NEAR(paths.seam(0.7), -R, 1e-9);
    auto lane = [&](double c) { return -R + 0.3 * std::cos(1.5 * c); };  // symmetric in c (mirrored passes)
    cv::Mat opacity(n, n, CV_32FC1, cv::Scalar(1));
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const cv::Vec2d p = layer_point(x, y, n);
            const double d = std::min(std::abs(p[0] - lane(p[1])), std::abs(p[0] - P - lane(p[1])));
            if (d < 0.25) opacity.at<float>(y, x) = 0;
        }
    paths.choose_seam(opacity);
    double worst = 0;
    for (double c = -2.0; c <= 2.0; c += 0.05) worst = std::max(worst, std::abs(paths.seam(c) - lane(c)));
    std::printf("seam off the clear lane by at most %.3f (lane half-width 0.25; a straight seam 0.3)\n", worst);
    EXPECT_LT(worst, 0.15);
}

// Pixels upwind of the seam at the start (near the upwind horizon) and those downwind of it switch
// into the tile by different rules; where they meet, the share of the tile must not jump (it did,
// 0 to 1 across one pixel: a hard arc fixed in the image, 3-9 minutes into fast rollouts).
TEST(CloudLayerPaths, NoHardEdgeWhereThePixelsUpwindOfTheSeamMeetTheRest) {
    const int n = 256;
    const cv::Vec2d step(0.24, 0.0);  // 12 m/s at 1500 m, 30 s steps, along +x
    auto largest_jump = [&](const CloudLayerPathsParams& params) {
        CloudLayerPaths paths(n, step, params);
        double worst = 0;
        for (double k : {4.0, 8.0, 12.0, 18.0}) {
            const CloudLayerPaths::Reads reads = paths.at(k);
            cv::Mat tile = reads.weights[CloudLayerPaths::kTileRead] + reads.weights[CloudLayerPaths::kLeavingRead];
            for (int y = 0; y < n; ++y)
                for (int x = 0; x + 1 < n; ++x) {
                    const double u = 2.0 * (x + 1.0) / n - 1, v = 2.0 * (y + 0.5) / n - 1;
                    if (std::hypot(u, v) > 0.9) continue;
                    worst = std::max(worst, double(std::abs(tile.at<float>(y, x + 1) - tile.at<float>(y, x))));
                }
        }
        return worst;
    };
    const double blended = largest_jump(CloudLayerPathsParams{});
    CloudLayerPathsParams hard;
    hard.seam_edge_band = 1e-6;  // the two rules meeting at the seam line
    const double cut = largest_jump(hard);
    std::printf("largest step of the tile's share between neighbours: %.2f (rules meeting at the line: %.2f)\n",
                blended, cut);
    EXPECT_GT(cut, 0.8);
    EXPECT_LT(blended, 0.25);
}

}  // namespace
}  // namespace dynsky
