// Great-arc advection (the paper's Lambda) against rotations of the sphere, whose paths are known
// analytically, and the flow estimate against a known rotation.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "motion/advection.h"
#include "sky/fisheye.h"

namespace dynsky {
namespace {

Vec3d unit_from_angles_deg(double zenith_deg, double azimuth_deg) {
    return fisheye::direction_from_angles(zenith_deg * kPiD / 180, azimuth_deg * kPiD / 180);
}

// Background 1 plus a Gaussian blob (angular sigma) of height 10 around `centre`.
SkyImage blob_sky(int n, const Vec3d& centre, double sigma_deg) {
    SkyImage sky(n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            if (!sky.in_disc(i, j)) continue;
            double a = std::acos(std::clamp(fisheye::direction_from_pixel(i, j, n).dot(centre), -1.0, 1.0)) * 180 /
                       kPiD;
            float v = float(1.0 + 10.0 * std::exp(-0.5 * a * a / (sigma_deg * sigma_deg)));
            sky.set_pixel(i, j, Color(v, v, v));
        }
    return sky;
}

// Solid-angle-weighted centroid direction and integral of (radiance - background).
void blob_moments(const SkyImage& sky, Vec3d* centroid, double* integral) {
    Vec3d sum = Vec3d::Zero();
    double total = 0;
    for (int j = 0; j < sky.resolution; ++j)
        for (int i = 0; i < sky.resolution; ++i) {
            if (!sky.in_disc(i, j)) continue;
            double w = std::max(0.0, double(sky.pixel(i, j)[0]) - 1.0) *
                       fisheye::pixel_solid_angle(i, j, sky.resolution);
            sum += w * fisheye::direction_from_pixel(i, j, sky.resolution);
            total += w;
        }
    *centroid = sum.normalized();
    *integral = total;
}

// n x n uniform noise (seed) blurred over sigma pixels and stretched to [lo, hi].
cv::Mat smooth_noise(int n, int seed, double sigma, double lo, double hi) {
    cv::Mat noise(n, n, CV_32FC1);
    cv::RNG rng(seed);
    rng.fill(noise, cv::RNG::UNIFORM, 0.0, 1.0);
    cv::GaussianBlur(noise, noise, cv::Size(0, 0), sigma);
    cv::normalize(noise, noise, lo, hi, cv::NORM_MINMAX);
    return noise;
}

double angle_deg(const Vec3d& a, const Vec3d& b) {
    return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180 / kPiD;
}

TEST(Advection, PixelDirectionRoundTrip) {
    for (double x : {0.0, 10.3, 63.5, 127.0})
        for (double y : {0.0, 40.7, 100.0}) {
            double x2, y2;
            fisheye::pixel_from_direction(fisheye::direction_from_pixel(x, y, 128), 128, &x2, &y2);
            EXPECT_NEAR(x, x2, 1e-9);
            EXPECT_NEAR(y, y2, 1e-9);
        }
    // Same mapping as sky/fisheye.h at pixel centres.
    Vec3 w = fisheye::direction_from_uv(fisheye::pixel_center_uv(17, 90, 128));
    EXPECT_LT((fisheye::direction_from_pixel(17, 90, 128) - w.cast<double>()).norm(), 1e-6);
}

TEST(Advection, ZeroFractionIsIdentity) {
    SkyImage sky = blob_sky(64, unit_from_angles_deg(30, 45), 5);
    cv::Mat flow = rotation_flow(64, Vec3d(1, 0, 0), 0.3);
    EXPECT_EQ(advect_great_arc(sky, flow, 0.0).rgb, sky.rgb);
}

// A feature carried by a rotation about a tilted axis passes 20 degrees from the zenith: half of
// the flow must put it on the great circle, at the analytic half-way rotation, not on the straight
// image line between the start and end pixels.
TEST(Advection, FeatureFollowsGreatCircleAcrossZenith) {
    const int n = 256;
    const Vec3d axis = unit_from_angles_deg(70, 90);  // 20 degrees above the eastern horizon
    const double beta = 120 * kPiD / 180;
    // Start: on the circle perpendicular to the axis, 60 degrees before its highest point.
    Vec3d top = Eigen::AngleAxisd(kPiD / 2, Vec3d(0, 0, 1)) * axis;  // perpendicular, highest point
    ASSERT_NEAR(top.dot(axis), 0.0, 1e-12);
    Vec3d start = Eigen::AngleAxisd(-beta / 2, axis) * top;
    SkyImage sky = blob_sky(n, start, 3.0);
    cv::Mat flow = rotation_flow(n, axis, beta);
    for (double f : {1.0 / 3.0, 0.5, 2.0 / 3.0}) {
        SkyImage moved = advect_great_arc(sky, flow, f);
        Vec3d centroid;
        double integral;
        blob_moments(moved, &centroid, &integral);
        Vec3d analytic = Eigen::AngleAxisd(f * beta, axis) * start;
        // Straight image line between start and end pixels, at the same fraction.
        double x0, y0, x1, y1;
        fisheye::pixel_from_direction(start, n, &x0, &y0);
        fisheye::pixel_from_direction(Eigen::AngleAxisd(beta, axis) * start, n, &x1, &y1);
        Vec3d straight = fisheye::direction_from_pixel(x0 + f * (x1 - x0), y0 + f * (y1 - y0), n);
        EXPECT_LT(angle_deg(centroid, analytic), 0.7) << "fraction " << f;
        EXPECT_GT(angle_deg(straight, analytic), 5.0) << "the test must tell the two paths apart";
    }
}

// A cloud carried from the zenith to 65 degrees keeps its solid angle along a great arc; shifting
// the image in a straight line by the same pixel displacement shrinks it by sinc(theta) (~20%).
TEST(Advection, NearHorizonAreaIsNotStretched) {
    const int n = 256;
    SkyImage sky = blob_sky(n, Vec3d(0, 1, 0), 4.0);
    Vec3d c0;
    double i0;
    blob_moments(sky, &c0, &i0);
    const double angle = 65 * kPiD / 180;
    SkyImage moved = advect_great_arc(sky, rotation_flow(n, Vec3d(1, 0, 0), angle), 1.0);
    Vec3d c1;
    double i1;
    blob_moments(moved, &c1, &i1);
    EXPECT_NEAR(i1 / i0, 1.0, 0.03);
    EXPECT_LT(angle_deg(c1, Eigen::AngleAxisd(angle, Vec3d(1, 0, 0)) * Vec3d(0, 1, 0)), 0.5);

    double x0, y0, x1, y1;
    fisheye::pixel_from_direction(Vec3d(0, 1, 0), n, &x0, &y0);
    fisheye::pixel_from_direction(Eigen::AngleAxisd(angle, Vec3d(1, 0, 0)) * Vec3d(0, 1, 0), n, &x1, &y1);
    cv::Mat src(n, n, CV_32FC3, sky.rgb.data()), dst;
    cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, x1 - x0, 0, 1, y1 - y0);
    cv::warpAffine(src, dst, shift, src.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    SkyImage shifted(n);
    std::memcpy(shifted.rgb.data(), dst.data, shifted.rgb.size() * sizeof(float));
    clear_outside_disc(&shifted);
    Vec3d c2;
    double i2;
    blob_moments(shifted, &c2, &i2);
    double expected = fisheye::sinc(angle);  // the straight shift's solid-angle ratio
    EXPECT_NEAR(i2 / i0, expected, 0.03);
    EXPECT_LT(i2 / i0, 0.85);
}

// Above 512 the lookup maps are computed coarsely and resized: a 1024 sky still moves exactly.
TEST(Advection, HighResolutionSkyMovesToTheAnalyticPlace) {
    const int n = 1024;
    Vec3d start = unit_from_angles_deg(40, 30);
    SkyImage sky = blob_sky(n, start, 2.0);
    const Vec3d axis(1, 0, 0);
    const double angle = 10 * kPiD / 180;
    SkyImage moved = advect_great_arc(sky, rotation_flow(n, axis, angle), 1.0);
    Vec3d c0, c1;
    double i0, i1;
    blob_moments(sky, &c0, &i0);
    blob_moments(moved, &c1, &i1);
    EXPECT_LT(angle_deg(c1, Eigen::AngleAxisd(angle, axis) * c0), 0.1);
    EXPECT_NEAR(i1 / i0, 1.0, 0.01);
}

// In-between frames keep the sky's fine detail: a bilinear read at a fractional offset softened
// them, so detail pulsed every medium step (midway 0.68 of the steps' in an animation). A sky of
// fine noise moved by half a pixel's worth of rotation keeps at least 80 % of its Laplacian's
// energy, and no value leaves the range of the source.
TEST(Advection, AFractionalMoveKeepsFineDetail) {
    const int n = 256;
    SkyImage sky(n);
    const cv::Mat noise = smooth_noise(n, 3, 0.8, 1.0, 3.0);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) sky.set_pixel(i, j, Color::Constant(noise.at<float>(j, i)));
    clear_outside_disc(&sky);
    // 0.5 px at the zenith: 90 / (n / 2) degrees per pixel.
    const SkyImage moved = advect_great_arc(sky, rotation_flow(n, Vec3d(1, 0, 0), 0.5 * 90.0 / (n / 2) * kPiD / 180),
                                            1.0);
    auto laplacian_energy = [&](const SkyImage& s) {
        double e = 0;
        for (int j = n / 4; j < 3 * n / 4; ++j)
            for (int i = n / 4; i < 3 * n / 4; ++i) {
                const double l = 4 * s.pixel(i, j)[0] - s.pixel(i - 1, j)[0] - s.pixel(i + 1, j)[0] -
                                 s.pixel(i, j - 1)[0] - s.pixel(i, j + 1)[0];
                e += l * l;
            }
        return e;
    };
    const double kept = laplacian_energy(moved) / laplacian_energy(sky);
    std::printf("fine detail kept after half a pixel's move: %.2f\n", kept);
    EXPECT_GT(kept, 0.8);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            if (sky.in_disc(i, j)) {
                EXPECT_GE(moved.pixel(i, j)[0], 1.0f - 1e-4f) << i << " " << j;
                EXPECT_LE(moved.pixel(i, j)[0], 3.0f + 1e-4f) << i << " " << j;
            }
}

// An in-between frame's two halves meet: the start carried forward by a fraction of its flow and
// the step after carried back from the end (advect_great_arc_from_end, the flow read where content
// starts) put a cloud in the same place. Carried back along the flow read where content ends (the
// old in-between), the copies of a strong wind's clouds met up to 7.7 degrees apart (0.28 now), and
// in every in-between frame of animate's 1024 px sky cloud edges showed twice.
TEST(Advection, BothHalvesOfAnInBetweenFrameMeet) {
    const int n = 256;
    const cv::Mat flow = wind_flow(n, Wind{270, 25, 1500}, 30);  // 750 m a step at 1.5 km: a strong wind
    double worst_new = 0, worst_old = 0;
    for (const double zenith : {20.0, 45.0, 60.0})
        for (const double azimuth : {90.0, 200.0, 300.0}) {
            const SkyImage start = blob_sky(n, unit_from_angles_deg(zenith, azimuth), 1.5);
            const SkyImage end = advect_great_arc(start, flow, 1.0);
            for (const double s : {0.3, 0.5, 0.8}) {
                Vec3d a, b, old;
                double ia, ib, iold;
                blob_moments(advect_great_arc(start, flow, s), &a, &ia);
                blob_moments(advect_great_arc_from_end(end, flow, s), &b, &ib);
                blob_moments(advect_great_arc(end, flow, -(1.0 - s)), &old, &iold);
                worst_new = std::max(worst_new, angle_deg(a, b));
                worst_old = std::max(worst_old, angle_deg(a, old));
                // Within half a pixel (0.35 degrees at 256 px).
                EXPECT_LT(angle_deg(a, b), 0.35) << zenith << " " << azimuth << " s " << s;
            }
        }
    std::printf("the halves' blobs apart: at most %.3f deg (read where content ends: %.3f)\n", worst_new, worst_old);
    EXPECT_EQ(advect_great_arc_from_end(blob_sky(n, unit_from_angles_deg(30, 10), 2.0), flow, 1.0).rgb,
              blob_sky(n, unit_from_angles_deg(30, 10), 2.0).rgb)
        << "the end itself at fraction 1";
}

// Textured sky rotated by a known small rotation: the Farneback estimate matches the rotation's
// flow, and a large featureless disc (the inside of a big cloud) gets its surroundings' motion.
TEST(Advection, FlowEstimateMatchesKnownRotationAndFillsHoles) {
    const int n = 256;
    SkyImage sky(n);
    const cv::Mat noise = smooth_noise(n, 7, 2.5, 0.2, 5.0);
    const int hi = 150, hj = 110, hr = 22;  // the featureless hole
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            float v = (i - hi) * (i - hi) + (j - hj) * (j - hj) < hr * hr ? 3.0f : noise.at<float>(j, i);
            sky.set_pixel(i, j, Color(v, v, v));
        }
    clear_outside_disc(&sky);
    cv::Mat truth = rotation_flow(n, Vec3d(0.3, 0.2, 1).normalized(), 2.5 * kPiD / 180);
    SkyImage next = advect_great_arc(sky, truth, 1.0);
    SkyFlowParams params;
    params.work_resolution = n;
    cv::Mat est = estimate_sky_flow(sky, next, params);
    std::vector<double> errors;
    double hole_error = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            double u = 2.0 * (i + 0.5) / n - 1, v = 2.0 * (j + 0.5) / n - 1;
            if (u * u + v * v > 0.75 * 0.75) continue;
            // The truth is the backward map's flow; for a small rotation forward and backward agree to O(angle^2).
            double e = cv::norm(est.at<cv::Vec2f>(j, i) - truth.at<cv::Vec2f>(j, i));
            if (i == hi && j == hj) hole_error = e;
            errors.push_back(e);
        }
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    double truth_mag = cv::norm(truth.at<cv::Vec2f>(hj, hi));
    EXPECT_GT(truth_mag, 3.0);
    EXPECT_LT(errors[errors.size() / 2], 0.5) << "median endpoint error, pixels";
    EXPECT_LT(hole_error, 0.35 * truth_mag) << "hole centre: flow filled from the surroundings";
}

}  // namespace
// The Farneback baseline applies a flow h times along its streamlines: for a rotation about the
// centre (a curved path), the traced displacement lands on the circle where a straight warp by
// h F drifts outwards; for a uniform flow both are h F.
TEST(Advection, ATracedFlowFollowsCurvedPaths) {
    const int n = 65;
    const double c = (n - 1) / 2.0, w = 0.05;  // radians per step
    cv::Mat rotation(n, n, CV_32FC2), uniform(n, n, CV_32FC2, cv::Scalar(1.5f, -0.5f));
    // By destination: x - F(x) is x rotated back by w.
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const double dx = x - c, dy = y - c;
            const double sx = c + std::cos(w) * dx + std::sin(w) * dy, sy = c - std::sin(w) * dx + std::cos(w) * dy;
            rotation.at<cv::Vec2f>(y, x) = cv::Vec2f(float(x - sx), float(y - sy));
        }
    const int h = 6;
    const cv::Mat traced = traced_flow(rotation, h);
    double worst_traced = 0, worst_linear = 0;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const double dx = x - c, dy = y - c;
            if (std::hypot(dx, dy) > 20 || std::hypot(dx, dy) < 10) continue;
            const double sx = c + std::cos(h * w) * dx + std::sin(h * w) * dy,
                         sy = c - std::sin(h * w) * dx + std::cos(h * w) * dy;
            const cv::Vec2f t = traced.at<cv::Vec2f>(y, x), f = rotation.at<cv::Vec2f>(y, x) * float(h);
            worst_traced = std::max(worst_traced, std::hypot(x - t[0] - sx, y - t[1] - sy));
            worst_linear = std::max(worst_linear, std::hypot(x - f[0] - sx, y - f[1] - sy));
        }
    EXPECT_LT(worst_traced, 0.05);  // bilinear reads of a smooth flow
    EXPECT_GT(worst_linear, 0.5);   // a straight line cuts the corner
    EXPECT_LT(cv::norm(traced_flow(uniform, h), uniform * double(h), cv::NORM_INF), 1e-4);
    EXPECT_LT(cv::norm(traced_flow(rotation, 1), rotation, cv::NORM_INF), 1e-4);  // float round-off of x - (x - F)
}

}  // namespace dynsky
