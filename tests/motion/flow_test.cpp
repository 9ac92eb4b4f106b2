// Winds as flow fields (motion/flow.h): a uniform wind on a cloud layer against the procedural
// sky's exact cloud motion, its directions, and fitting a wind back to a measured flow.
#include "motion/flow.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

#include "sky/fisheye.h"
#include "sky/procedural_clouds.h"
#include "util/error.h"
#include "util/math.h"

namespace dynsky {
namespace {

// Median over cloud pixels of |wind_flow - exact| / |exact|, and the median |exact|.
void compare_with_procedural(double from_deg, double speed, double dt, double* rel_error, double* median_px) {
    const int n = 128;
    ProceduralSkyParams p;
    p.seed = 5;
    p.coverage = 0.6;
    p.layers = {cumulus_layer()};
    p.layers[0].wind_from_deg = from_deg, p.layers[0].wind_speed_mps = speed, p.layers[0].evolution_time_s = 0;
    Image exact;
    render_procedural_sky(p, 0.0, n, &exact, dt);
    cv::Mat flow = wind_flow(n, Wind{from_deg, speed, p.layers[0].altitude_m}, dt);
    std::vector<double> rel, mag;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            if (exact.at(i, j, 2) < 0.5) continue;  // cloud pixels only
            const double ex = exact.at(i, j, 0), ey = exact.at(i, j, 1);
            const cv::Vec2f f = flow.at<cv::Vec2f>(j, i);
            const double m = std::hypot(ex, ey);
            if (m < 0.05) continue;
            rel.push_back(std::hypot(f[0] - ex, f[1] - ey) / m), mag.push_back(m);
        }
    ASSERT_GT(rel.size(), 500u);
    *rel_error = median(rel), *median_px = median(mag);
}

TEST(WindFlow, MatchesTheProceduralSkysExactMotionInEveryDirection) {
    for (double from : {0.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0}) {
        double rel = 0, px = 0;
        compare_with_procedural(from, 10.0, 5.0, &rel, &px);
        EXPECT_GT(px, 0.5) << from;  // the test moves clouds by more than half a pixel
        // By destination (wind_flow) vs by source (the procedural flow): they differ to second order
        // in the displacement (1.3 px here; at 8 px per step, 8 %).
        EXPECT_LT(rel, 0.03) << "wind from " << from << " deg: median relative error " << rel;
    }
}

TEST(WindFlow, AWesterlyMovesOverheadCloudsEastwardThatIsLeftInTheImage) {
    const int n = 65;  // odd: one pixel centre at the zenith
    cv::Mat f = wind_flow(n, Wind{270.0, 15.0, 1500.0}, 10.0);
    const cv::Vec2f z = f.at<cv::Vec2f>(32, 32);
    // 150 m at 1500 m overhead: atan(0.1) = 5.71 deg = 5.71 / 90 of the radius (32.5 px).
    EXPECT_NEAR(z[0], -std::atan(0.1) / (kPiD / 2) * n / 2, 0.02);
    EXPECT_NEAR(z[1], 0.0, 1e-3);
    cv::Mat north = wind_flow(n, Wind{180.0, 15.0, 1500.0}, 10.0);  // from the south: towards the north, up
    EXPECT_LT(north.at<cv::Vec2f>(32, 32)[1], -1.0f);
    // Near the horizon a layer moves far less in angle than overhead.
    EXPECT_LT(std::abs(f.at<cv::Vec2f>(32, 2)[0]), 0.2 * std::abs(z[0]));
}

// The same motion told by where content starts: the content at p goes to p + S(p), and the wind's
// flow (by destination) says that what arrives there came from p. Read one for the other, the
// in-between frames of animate's 1024 px default sky met their two halves up to 5 px apart.
TEST(WindFlow, ByDestinationAndBySourceTellTheSameMotion) {
    const int n = 256;
    const cv::Mat by_destination = wind_flow(n, Wind{240, 20, 1500}, 30);
    const cv::Mat by_source = flow_by_source(by_destination);
    double worst = 0, apart = 0;
    for (int y = 20; y < n - 20; y += 7)
        for (int x = 20; x < n - 20; x += 7) {
            if (fisheye::pixel_center_uv(x, y, n).norm() > 0.85) continue;  // well inside the disc
            const cv::Vec2f s = by_source.at<cv::Vec2f>(y, x);
            const double ex = x + s[0], ey = y + s[1];
            if (ex < 1 || ey < 1 || ex > n - 2 || ey > n - 2) continue;
            // Bilinear F at the end: it must lead back to (x, y).
            const int x0 = int(ex), y0 = int(ey);
            const double fx = ex - x0, fy = ey - y0;
            auto f = [&](int i, int j) { return by_destination.at<cv::Vec2f>(j, i); };
            const cv::Vec2f d = float((1 - fy) * (1 - fx)) * f(x0, y0) + float((1 - fy) * fx) * f(x0 + 1, y0) +
                                float(fy * (1 - fx)) * f(x0, y0 + 1) + float(fy * fx) * f(x0 + 1, y0 + 1);
            worst = std::max(worst, std::hypot(ex - d[0] - x, ey - d[1] - y));
            apart = std::max(apart, double(cv::norm(s - by_destination.at<cv::Vec2f>(y, x))));
        }
    std::printf("by source back to the start within %.4f px; the two readings differ by up to %.2f px\n", worst, apart);
    EXPECT_LT(worst, 0.01);
    EXPECT_GT(apart, 0.5) << "a wind whose flow varies: the test shows something";
    EXPECT_TRUE(flow_by_source(cv::Mat()).empty());
}

TEST(WindFlow, FittingAWindRecoversIt) {
    const int n = 96;
    for (double from : {10.0, 200.0, 300.0}) {
        Wind truth{from, 9.0, 1500.0};
        cv::Mat flow = wind_flow(n, truth, 30.0);
        cv::Mat weight(n, n, CV_32FC1, cv::Scalar(1.0f));
        Wind w = fit_wind(flow, weight, 30.0, 1500.0);
        EXPECT_NEAR(w.speed_mps, 9.0, 0.05) << from;
        EXPECT_NEAR(std::remainder(w.from_deg - from, 360.0), 0.0, 0.5) << from;
    }
}

TEST(WindFlow, RejectsBadLayers) {
    EXPECT_THROW(wind_flow(32, Wind{270, 10, 0}, 10), Error);
    EXPECT_THROW(wind_flow(32, Wind{270, std::nan(""), 1500}, 10), Error);
}

// A layer moving as one inside the disc, measured as zero outside it and on a static sun: smoothed
// over the trusted pixels only, the clouds' flow keeps its speed up to the rim and beside the sun;
// smoothed over everything, it is pulled towards zero there.
TEST(SmoothMotion, AveragesOverTrustedPixelsOnly) {
    const int n = 256;
    const cv::Mat disc = sky_disc_mask(n);
    cv::Mat sun = cv::Mat::zeros(n, n, CV_8UC1);
    cv::circle(sun, cv::Point(170, 100), 10, cv::Scalar(255), cv::FILLED);
    const cv::Mat trusted = disc & ~sun;
    cv::Mat flow(n, n, CV_32FC2, cv::Scalar(3.0f, -1.0f));
    flow.setTo(cv::Scalar(0.0f, 0.0f), ~trusted);
    const cv::Mat plain = smooth_motion(flow), masked = smooth_motion(flow, trusted);
    double worst_plain = 0, worst_masked = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            if (!disc.at<unsigned char>(j, i)) continue;
            worst_plain = std::max(worst_plain, std::abs(plain.at<cv::Vec2f>(j, i)[0] - 3.0));
            worst_masked = std::max(worst_masked, std::abs(masked.at<cv::Vec2f>(j, i)[0] - 3.0) +
                                                      std::abs(masked.at<cv::Vec2f>(j, i)[1] + 1.0));
        }
    EXPECT_GT(worst_plain, 1.0);    // the rim and the sun pull it to zero
    EXPECT_LT(worst_masked, 1e-4);  // exact, the sun's pixels filled from around it
    // Nothing trusted anywhere near: filled from farther, never divided by ~0.
    cv::Mat corner = cv::Mat::zeros(n, n, CV_8UC1);
    corner(cv::Rect(0, 0, 8, 8)).setTo(255);
    const cv::Mat far = smooth_motion(flow, corner);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) ASSERT_TRUE(std::isfinite(far.at<cv::Vec2f>(j, i)[0]));
}

// Two layers side by side, each moving as one: where the flow measured back confirms the forward
// flow, consistent_motion's confirmed field keeps the sharp edge between them that smoothing blurs;
// where it does not (a backward flow that disagrees), it is smooth_motion's field.
TEST(ConsistentMotion, KeepsConfirmedFlowSharpAndSmoothsTheRest) {
    const int n = 256;
    const cv::Vec2f left(3.0f, 0.0f), right(-2.0f, 1.0f);
    cv::Mat forward(n, n, CV_32FC2), backward(n, n, CV_32FC2);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            forward.at<cv::Vec2f>(j, i) = i < n / 2 ? left : right;
            backward.at<cv::Vec2f>(j, i) = i < n / 2 ? -left : -right;
        }
    const MeasuredMotion m = consistent_motion(forward, backward);
    const cv::Mat smoothed = smooth_motion(forward), &kept = m.confirmed;
    EXPECT_LT(cv::norm(m.smoothed, smoothed, cv::NORM_INF), 1e-6);
    double worst_smoothed = 0, worst_kept = 0;
    for (int j = 0; j < n; ++j)
        for (int i = n / 2 - 12; i < n / 2 + 12; ++i) {
            if (std::abs(i - n / 2) < 4) continue;  // content that crosses the edge lands on the other layer
            const cv::Vec2f truth = forward.at<cv::Vec2f>(j, i);
            worst_smoothed = std::max(worst_smoothed, double(cv::norm(smoothed.at<cv::Vec2f>(j, i) - truth)));
            worst_kept = std::max(worst_kept, double(cv::norm(kept.at<cv::Vec2f>(j, i) - truth)));
        }
    EXPECT_GT(worst_smoothed, 1.0);
    EXPECT_LT(worst_kept, 1e-3);
    // Agreement everywhere but where content crosses the edge.
    EXPECT_GT(m.agreement.at<float>(n / 2, n / 4), 0.99f);
    // A backward flow that does not confirm it (here: no motion back): the smoothed field.
    const MeasuredMotion unconfirmed = consistent_motion(forward, cv::Mat::zeros(n, n, CV_32FC2));
    EXPECT_LT(cv::norm(unconfirmed.confirmed, smoothed, cv::NORM_INF), 1e-4);
    double most = 0;
    cv::minMaxLoc(unconfirmed.agreement, nullptr, &most);
    EXPECT_LT(most, 1e-6);
    // Untrusted pixels take the smoothed field too.
    const cv::Mat none = cv::Mat::zeros(n, n, CV_8UC1);
    EXPECT_THROW(consistent_motion(forward, backward(cv::Rect(0, 0, 8, 8))), Error);
    const cv::Mat masked = consistent_motion(forward, backward, none).confirmed;
    EXPECT_LT(cv::norm(masked, smooth_motion(forward, none), cv::NORM_INF), 1e-4);
}

}  // namespace
}  // namespace dynsky
