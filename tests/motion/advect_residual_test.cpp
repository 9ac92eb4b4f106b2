// The advect-residual cloud model (motion/advect_residual.h) with the shipped weights
// (networks/models/advect_residual): OpenCV dnn and the C++ warp agree with PyTorch on the
// reference pair, clouds follow a requested wind in every direction, clear skies stay clear, and
// rollouts from each kind of start stay finite, in range, within the luminance band and keep their
// detail.
#include "motion/advect_residual.h"
#include "motion/sun_patch.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>

#include "motion/advection.h"
#include "motion/metrics.h"
#include "motion/network_step_model.h"
#include "motion/sky_timeline.h"
#include "sky/clear_sky.h"
#include "sky/fisheye.h"
#include "sky/preset_import.h"
#include "sky/procedural_clouds.h"
#include "tests/test_support.h"
#include "util/data_path.h"
#include "util/error.h"
#include "util/math.h"
#include "util/npy.h"

namespace dynsky {
namespace {

namespace fs = std::filesystem;

std::string shipped() { return data_path("networks/models/advect_residual"); }

cv::Mat nchw_to_mat(const NpyArray& a) {
    const int c = int(a.shape[1]), n = int(a.shape[2]);
    std::vector<cv::Mat> planes;
    for (int k = 0; k < c; ++k)
        planes.push_back(cv::Mat(n, n, CV_32F, const_cast<float*>(a.data.data() + size_t(k) * n * n)).clone());
    cv::Mat m;
    cv::merge(planes, m);
    return m;
}

TEST(AdvectResidual, OpenCvAndTheWarpAgreeWithPyTorch) {
    AdvectResidualNetwork net = AdvectResidualNetwork::load(shipped());
    const std::string f = shipped() + "/";
    cv::Mat image = nchw_to_mat(read_npy(f + "reference_image.npy")),
            flow = nchw_to_mat(read_npy(f + "reference_flow.npy"));
    cv::Mat input = nchw_to_mat(read_npy(f + "reference_input.npy")),
            output = nchw_to_mat(read_npy(f + "reference_output.npy"));
    ASSERT_EQ(image.rows, net.info().resolution);
    cv::Mat compensation;  // B - warp(B) for a model trained on the compensated warp
    if (fs::exists(f + "reference_background.npy")) {
        cv::Mat background = nchw_to_mat(read_npy(f + "reference_background.npy"));
        compensation = background - warp_in_disc(background, flow);
        compensation.setTo(cv::Scalar::all(0), ~sky_disc_mask(background.rows));
    }
    EXPECT_LT(cv::norm(net.network_input(image, flow, compensation), input, cv::NORM_INF), 1e-4);  // the warp
    EXPECT_LT(cv::norm(net.run(input), output, cv::NORM_INF), 1e-4);                               // the network
}

// A procedural cumulus sky with frozen shapes and the given wind, at n px, and its exact flow.
SkyImage procedural(uint64_t seed, double from_deg, double speed, int n, double dt, Image* flow) {
    ProceduralSkyParams p;
    p.seed = seed;
    p.coverage = 0.5;
    p.layers = {cumulus_layer()};
    p.layers[0].wind_from_deg = from_deg, p.layers[0].wind_speed_mps = speed, p.layers[0].evolution_time_s = 0;
    p.clear_sky.sun_direction = fisheye::direction_from_angles(0.9, 1.0);
    return render_procedural_sky(p, 0.0, n, flow, dt);
}

double angle_deg(const cv::Vec2f& a, const cv::Vec2f& b) {
    return std::abs(std::remainder(std::atan2(a[1], a[0]) - std::atan2(b[1], b[0]), 2 * kPiD)) * 180 / kPiD;
}

TEST(AdvectResidual, CloudsFollowTheRequestedWindInEveryDirection) {
    AdvectResidualNetwork net = AdvectResidualNetwork::load(shipped());
    const int n = 128;
    const double dt = net.info().dt, speed = 12.0;
    for (int d = 0; d < 8; ++d) {
        const double from = 22.5 + 45.0 * d;  // not the training set's exact directions
        Image exact;
        SkyImage sky = procedural(900 + d, from, speed, n, dt, &exact);  // seeds never trained on
        CloudMotion motion;
        motion.wind = Wind{from, speed, 1500.0};
        SkyImage next;
        net.rollout(sky, net.motion_flow(sky, motion, dt, n), 1, [&](int, const SkyImage& s) { next = s; });
        // The motion produced, measured on the images themselves, against the requested (exact) one.
        cv::Mat produced = farneback_flow(to_network_form(sky, net.info().form),
                                          to_network_form(next, net.info().form));
        std::vector<double> angles, ratios;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const cv::Vec2f want(exact.at(i, j, 0), exact.at(i, j, 1));
                if (exact.at(i, j, 2) < 0.5 || std::hypot(want[0], want[1]) < 0.5) continue;  // clouds that move
                const cv::Vec2f got = produced.at<cv::Vec2f>(j, i);
                angles.push_back(angle_deg(got, want));
                ratios.push_back(std::hypot(got[0], got[1]) / std::hypot(want[0], want[1]));
            }
        ASSERT_GT(angles.size(), 300u) << from;
        EXPECT_LT(median(angles), 15.0) << "wind from " << from << " deg";
        EXPECT_NEAR(median(ratios), 1.0, 0.2) << "wind from " << from << " deg";
    }
}

// Mean R/G and B/G of the outermost ring of the disc (r > 0.9): a coloured rim shows up here.
std::pair<double, double> rim_colour(const SkyImage& s) {
    double r = 0, g = 0, b = 0;
    for (int j = 0; j < s.resolution; ++j)
        for (int i = 0; i < s.resolution; ++i) {
            const Vec2 uv = fisheye::pixel_center_uv(i, j, s.resolution);
            if (!s.in_disc(i, j) || uv.norm() < 0.9f) continue;
            const Color c = s.pixel(i, j);
            r += c[0], g += c[1], b += c[2];
        }
    return {r / g, b / g};
}

struct RolloutStats {
    double rim_rg0 = 0, rim_bg0 = 0, rim_change = 0;  // largest relative change of R/G or B/G at the rim
    bool finite = true;
    float min = 1, max = 0;
    double mean0 = 0, mean_min = 1e30, mean_max = 0, hf0 = 0, hf_min = 1e30, cover0 = 0, cover_max = 0, cover_min = 1;
    double blue0 = 0, blue_max = 0;  // mean B / (R + G + B) of the disc
};

RolloutStats roll(AdvectResidualNetwork& net, const SkyImage& sky, const CloudMotion& motion, int steps,
                  const std::function<void(int, const SkyImage&)>& also = nullptr) {
    const int n = net.info().resolution;
    const cv::Mat disc = sky_disc_mask(n);
    // The sun's pixels (the start's clipped ones, restored into every step and dimmed when a cloud
    // moves over the sun: motion/sun_patch.h) are left out of the mean: the band is about the
    // clouds, and a sun covered on purpose is not a drift.
    cv::Mat start_form = to_network_form(sky, net.info().form);
    const cv::Mat sun = fill_saturated_pixels(&start_form);
    RolloutStats r;
    auto measure = [&](const SkyImage& s, bool first) {
        cv::Mat u = to_network_form(s, net.info().form, n);
        double lo, hi;
        cv::minMaxLoc(u.reshape(1), &lo, &hi);
        r.finite = r.finite && cv::checkRange(u);
        r.min = std::min(r.min, float(lo)), r.max = std::max(r.max, float(hi));
        double lum = 0;
        int count = 0;
        for (int j = 0; j < s.resolution; ++j)
            for (int i = 0; i < s.resolution; ++i)
                if (s.in_disc(i, j) && !sun.at<uint8_t>(j, i)) lum += luminance(s.pixel(i, j)), ++count;
        lum /= count;
        const double hf = high_frequency_energy(u, disc);
        const double cover = double(cv::countNonZero(network_cloud_mask(u, net.info().form) & disc)) /
                             cv::countNonZero(disc);
        const auto [rg, bg] = rim_colour(s);
        if (first) r.mean0 = lum, r.hf0 = hf, r.cover0 = cover, r.rim_rg0 = rg, r.rim_bg0 = bg;
        r.rim_change = std::max({r.rim_change, std::abs(rg / r.rim_rg0 - 1), std::abs(bg / r.rim_bg0 - 1)});
        r.mean_min = std::min(r.mean_min, lum), r.mean_max = std::max(r.mean_max, lum);
        r.hf_min = std::min(r.hf_min, hf), r.cover_max = std::max(r.cover_max, cover);
        r.cover_min = std::min(r.cover_min, cover);
        const cv::Scalar m = cv::mean(u, disc);
        const double blue = m[2] / std::max(m[0] + m[1] + m[2], 1e-12);
        if (first) r.blue0 = blue;
        r.blue_max = std::max(r.blue_max, blue);
    };
    measure(sky, true);
    net.rollout(sky, net.motion_flow(sky, motion, net.info().dt, sky.resolution), steps, [&](int k, const SkyImage& s) {
        measure(s, false);
        if (also) also(k, s);
    });
    return r;
}

// A sky smaller than the network (a 32 px preview, a 2 px sky) is stepped at the network's
// resolution and each step comes back at its own: before, "the state is smaller than the network's
// 64 px", after writing the first frames.
TEST(AdvectResidual, ASkySmallerThanTheNetworkStepsAtItsOwnResolution) {
    ProceduralSkyParams pc;
    pc.coverage = 0.5;
    pc.clear_sky.sun_disc = false;  // the clouds' light alone (the sun's dimming is tested elsewhere)
    const SkyImage big = render_procedural_sky(pc, 0.0, 128);
    for (int n : {32, 2}) {
        SkyImage small = resampled_sky(big, n);
        CloudMotion motion;
        motion.wind = Wind{270.0, 12.0, 1500.0};
        SkyTimeline timeline(small, make_network_step_model(shipped(), motion), 30.0);
        const SkyImage last = timeline.sky_at(120.0);  // 4 steps
        ASSERT_EQ(last.resolution, n);
        double mean0 = 0, mean = 0, moved = 0;
        for (size_t p = 0; p < last.rgb.size(); ++p) {
            ASSERT_TRUE(std::isfinite(last.rgb[p]));
            mean0 += small.rgb[p], mean += last.rgb[p], moved += std::abs(last.rgb[p] - small.rgb[p]);
        }
        std::printf("%d px: mean %.3f of the start, moved %.3f\n", n, mean / mean0, moved / mean0);
        EXPECT_NEAR(mean / mean0, 1.0, 0.2) << n;
        if (n == 32) {
            EXPECT_GT(moved / mean0, 0.02) << "the clouds of the 32 px sky did not move";
        }
    }
}

TEST(AdvectResidual, ClearSkiesStayClearUnderAnyWind) {
    AdvectResidualNetwork net = AdvectResidualNetwork::load(shipped());
    const double elevations[] = {5, 15, 30, 50, 75};
    for (int k = 0; k < 5; ++k) {
        ClearSkyParams p;
        p.sun_direction = fisheye::direction_from_angles((90 - elevations[k]) * kPiD / 180, 0.7 + 1.2 * k);
        p.turbidity = 3;
        SkyImage sky = make_clear_sky(p, 128);
        CloudMotion motion;
        motion.wind = Wind{45.0 + 70.0 * k, 15.0, 1500.0};
        RolloutStats r = roll(net, sky, motion, 120);
        EXPECT_TRUE(r.finite);
        EXPECT_LE(r.cover_max, r.cover0 + 0.03) << "sun elevation " << elevations[k];
        EXPECT_LT(r.rim_change, 0.05) << "sun elevation " << elevations[k] << ": the rim's colour changed";
        EXPECT_NEAR(r.mean_max / r.mean0, 1.0, 0.2) << "sun elevation " << elevations[k];
        EXPECT_NEAR(r.mean_min / r.mean0, 1.0, 0.2) << "sun elevation " << elevations[k];
    }
}

// A hazy clear sky's glow, and a downloaded HDRI's (brighter and whiter than the model's), stays on
// its sun under a wind: read as cloud it was torn off it (a white crescent downwind, a pink hole at
// the sun; a turbidity-9 sky's pixels 0.4-9 x their start after 10 steps), and a cloud moved onto the
// sun later did not dim it.
TEST(AdvectResidual, AHazySkysGlowStaysOnItsSun) {
    AdvectResidualNetwork net = AdvectResidualNetwork::load(shipped());
    const Vec3d sun = fisheye::direction_from_angles((90 - 35) * kPiD / 180, 2.4);
    auto sky_of = [&](double turbidity, double glow) {
        ClearSkyParams p;
        p.sun_direction = sun;
        p.turbidity = turbidity;
        SkyImage sky = make_clear_sky(p, 128);
        const double median = 8.0;  // about the sky's, W m^-2 sr^-1
        for (int j = 0; j < sky.resolution; ++j)
            for (int i = 0; i < sky.resolution; ++i) {
                if (!sky.in_disc(i, j)) continue;
                const double g = std::acos(std::clamp(fisheye::direction_from_pixel(i, j, 128).dot(sun), -1.0, 1.0));
                const float add = float(glow * median * std::exp(-g / (8 * kPiD / 180)));
                sky.set_pixel(i, j, sky.pixel(i, j) + Color(add, add, add));
            }
        return sky;
    };
    struct Case {
        double turbidity, glow;
    };
    for (const Case c : {Case{7, 0}, Case{9, 0}, Case{3, 6}}) {
        const SkyImage sky = sky_of(c.turbidity, c.glow);
        CloudMotion motion;
        motion.wind = Wind{270.0, 12.0, 1500.0};
        SkyImage last;
        net.rollout(sky, net.motion_flow(sky, motion, net.info().dt, sky.resolution), 10,
                    [&](int, const SkyImage& s) { last = s; });
        std::vector<double> ratio;
        for (int j = 0; j < sky.resolution; ++j)
            for (int i = 0; i < sky.resolution; ++i)
                if (sky.in_disc(i, j) && fisheye::direction_from_pixel(i, j, 128).dot(sun) < std::cos(3 * kPiD / 180))
                    ratio.push_back(luminance(last.pixel(i, j)) / luminance(sky.pixel(i, j)));
        std::sort(ratio.begin(), ratio.end());
        const double low = ratio[ratio.size() / 100], high = ratio[ratio.size() - 1 - ratio.size() / 100];
        std::printf("turbidity %g, glow %g: 1st-99th percentile of step 10 / start %.3f-%.3f\n", c.turbidity, c.glow,
                    low, high);
        // Before: 0.41-9.3 (turbidity 9), 0.85-7.9 (the added glow). Now 0.99-1.09 and 0.94-1.06.
        EXPECT_GT(low, 0.9) << "turbidity " << c.turbidity << ", glow " << c.glow;
        EXPECT_LT(high, 1.12) << "turbidity " << c.turbidity << ", glow " << c.glow;
    }
}

// Clouds a wind carries into the sun's glow hide it there, out to the glow's edge: composed over it
// additively beyond 30 degrees, they shone with it, and a hazy Mobotix photograph (11:59 CEST, its
// glow still half the sky's 30 degrees out) drew an orange ring 30-35 degrees around its sun within
// two steps, where the glow ends. Here a glow of 0.6 x the clear sky out to 35 degrees, opaque
// clouds beyond 40 carried across it: the clouds 31-34 degrees from the sun shine as those far from it.
TEST(AdvectResidual, CloudsCarriedIntoTheGlowHideIt) {
    AdvectResidualNetwork net = AdvectResidualNetwork::load(shipped());
    const int n = 128;
    const Vec3d sun = fisheye::direction_from_angles(25 * kPiD / 180, 1.0);
    ClearSkyParams p;
    p.sun_direction = sun;
    SkyImage sky = make_clear_sky(p, n);
    const float cloud = 30.0f;  // about 3 x the clear sky's median
    auto angle_to = [&](const Vec3d& a, const Vec3d& b) {
        return std::acos(std::clamp(a.dot(b), -1.0, 1.0)) * 180 / kPiD;
    };
    std::vector<Vec3d> blobs;
    for (double zenith = 20; zenith <= 75; zenith += 11)
        for (double azimuth = 0; azimuth < 360; azimuth += 24) {
            const Vec3d d = fisheye::direction_from_angles(zenith * kPiD / 180, azimuth * kPiD / 180);
            if (angle_to(d, sun) > 42) blobs.push_back(d);
        }
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            if (!sky.in_disc(i, j)) continue;
            const Vec3d d = fisheye::direction_from_pixel(i, j, n);
            const double a = angle_to(d, sun);
            if (a > 1.5 && a < 35) sky.set_pixel(i, j, sky.pixel(i, j) * 1.6f);
            for (const Vec3d& b : blobs)
                if (angle_to(d, b) < 5) sky.set_pixel(i, j, Color(cloud, cloud, cloud));
        }
    CloudMotion motion;
    motion.wind = Wind{270.0, 12.0, 1500.0};
    std::vector<SkyImage> steps;
    net.rollout(sky, net.motion_flow(sky, motion, net.info().dt, n), 4,
                [&](int, const SkyImage& s) { steps.push_back(s); });
    double band = 0, far = 0;
    int band_count = 0, far_count = 0;
    for (const SkyImage& s : steps)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                if (!s.in_disc(i, j) || luminance(s.pixel(i, j)) < 0.75 * cloud) continue;  // cloud
                const Vec3d d = fisheye::direction_from_pixel(i, j, n);
                const double a = angle_to(d, sun), zenith = std::acos(std::clamp(d.y(), -1.0, 1.0)) * 180 / kPiD;
                if (zenith > 70) continue;
                if (a > 31 && a < 34) band += luminance(s.pixel(i, j)), ++band_count;
                else if (a > 45) far += luminance(s.pixel(i, j)), ++far_count;
            }
    ASSERT_GT(band_count, 20);
    ASSERT_GT(far_count, 100);
    std::printf("cloud 31-34 degrees from the sun %.2f x the cloud beyond 45 (%d and %d pixels, steps 1-4)\n",
                (band / band_count) / (far / far_count), band_count, far_count);
    EXPECT_LT((band / band_count) / (far / far_count), 1.08);
}

// The glow measured around the sun leaves out the pixels an import filled, and keeps each ring's
// colour: a TSI's shadow band runs through the sun, and its fill (here magenta) set the innermost
// rings; capped channel by channel by them, an ARM photograph's glow came out magenta and left a
// pink ring 30-35 degrees around the sun once the clouds moved off it (`sky predict` of 15:40:30Z).
// Nor does a ring mostly hidden measure it: the few pixels it shows lie beside the band, in the
// glare along it (here white), and taken for every ring inside they made a pale disc with a hard
// edge 12 degrees around the sun (17:51Z).
TEST(AdvectResidual, TheSunsGlowIsMeasuredOnSeenSkyAndKeepsItsColour) {
    AdvectResidualNetwork net = AdvectResidualNetwork::load(shipped());
    const int n = 128;
    const Vec3d sun = fisheye::direction_from_angles((90 - 45) * kPiD / 180, 2.4);
    auto angle_at = [&](int i, int j) {
        return std::acos(std::clamp(fisheye::direction_from_pixel(i, j, n).dot(sun), -1.0, 1.0)) * 180 / kPiD;
    };
    for (const bool glare : {false, true}) {
        ClearSkyParams p;
        p.sun_direction = sun;
        SkyImage sky = make_clear_sky(p, n);
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i)
                if (sky.in_disc(i, j)) {  // a white glow, as a hazy sky's or a camera's
                    const float add = float(6 * 8.0 * std::exp(-angle_at(i, j) / 8));
                    sky.set_pixel(i, j, sky.pixel(i, j) + Color(add, add, add));
                }
        double sx, sy;
        fisheye::pixel_from_direction(sun, n, &sx, &sy);
        const double len = std::hypot(sx - n / 2.0, sy - n / 2.0), ux = (sx - n / 2.0) / len, uy = (sy - n / 2.0) / len;
        const cv::Mat cut = sun_cut_mask(n, sun);
        sky.filled.assign(size_t(n) * n, 0);
        std::vector<unsigned char> bright(size_t(n) * n, 0);
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const double x = i + 0.5 - n / 2.0, y = j + 0.5 - n / 2.0, across = std::abs(x * uy - y * ux);
                if (!sky.in_disc(i, j) || cut.at<uint8_t>(j, i)) continue;
                const float l = luminance(sky.pixel(i, j));
                if (across <= 5) {
                    sky.filled[size_t(j) * n + i] = 1;
                    sky.set_pixel(i, j, Color(2.0f * l, 0.4f * l, 2.0f * l));  // a band filled magenta
                } else if (glare && across <= 10 && angle_at(i, j) < 14) {
                    bright[size_t(j) * n + i] = 1;
                    sky.set_pixel(i, j, Color::Constant(3.0f * l));  // glare along the band, seen
                }
            }
        CloudMotion motion;
        motion.wind = Wind{270.0, 12.0, 1500.0};
        SkyImage last;
        net.rollout(sky, net.motion_flow(sky, motion, net.info().dt, n), 10, [&](int, const SkyImage& s) { last = s; });
        // The seen sky 5-35 degrees from the sun: its colour and brightness stay the start's.
        double rg = 0, bg = 0, l0 = 0, l = 0;
        int count = 0;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const double a = angle_at(i, j);
                if (!sky.in_disc(i, j) || sky.filled[size_t(j) * n + i] || bright[size_t(j) * n + i] || a < 5 || a > 35)
                    continue;
                const Color c0 = sky.pixel(i, j), c = last.pixel(i, j);
                rg += std::log(c[0] / c[1]) - std::log(c0[0] / c0[1]);
                bg += std::log(c[2] / c[1]) - std::log(c0[2] / c0[1]);
                l0 += luminance(c0), l += luminance(c), ++count;
            }
        rg /= count, bg /= count;
        std::printf(
            "%s: 5-35 degrees from the sun, step 10 against the start: log R/G %+.4f, log B/G %+.4f, "
            "luminance %.3f x\n",
            glare ? "band with glare beside it" : "band", rg, bg, l / l0);
        EXPECT_LT(std::abs(rg), 0.02) << (glare ? "with glare" : "");
        EXPECT_LT(std::abs(bg), 0.02) << (glare ? "with glare" : "");
        EXPECT_NEAR(l / l0, 1.0, 0.05) << (glare ? "with glare" : "");
    }
}

// A ring mostly hidden by filled pixels does not measure the glow: what it shows lies beside the
// hidden part (the glare along a TSI's band), and taken for every ring inside it a few bright
// pixels made a pale disc with a hard edge 12 degrees around the sun (ARM 17:51Z, 36 of 550 seen).
TEST(AdvectResidual, ARingMostlyHiddenDoesNotMeasureTheGlow) {
    const int n = 256;
    const UnitMapParams unit = AdvectResidualNetwork::load(shipped()).info().form.unit_map;
    const Vec3d sun = fisheye::direction_from_angles(40 * kPiD / 180, 1.0);
    const float base = 10.0f, glow = 2.0f;  // radiance of the background, and the glow over it
    cv::Mat background(n, n, CV_32FC3), start(n, n, CV_32FC3), filled(n, n, CV_8UC1, cv::Scalar(0));
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const Vec3d d = fisheye::direction_from_pixel(i, j, n);
            const double a = std::acos(std::clamp(d.dot(sun), -1.0, 1.0)) * 180 / kPiD;
            const float b = radiance_to_unit(base, unit);
            background.at<cv::Vec3f>(j, i) = cv::Vec3f(b, b, b);
            float s = radiance_to_unit(base + glow, unit);
            if (a < 12) {
                // Hidden but for a thin arc on one side (about 5 % of each ring), which is glare.
                const double side = std::atan2(d.cross(sun).dot(Vec3d::UnitY()), d.dot(Vec3d::UnitY()) - sun.y());
                if (std::abs(side) > 0.15) filled.at<uint8_t>(j, i) = 255;
                else s = radiance_to_unit(base + 10 * glow, unit);
            }
            start.at<cv::Vec3f>(j, i) = cv::Vec3f(s, s, s);
        }
    const std::vector<cv::Vec3f> excess = halo_excess(start, background, sun, unit, filled);
    ASSERT_FALSE(excess.empty());
    std::printf("glow measured at 2, 8, 20 degrees: %.2f %.2f %.2f (the seen sky's: %.1f)\n", excess[2][1],
                excess[8][1], excess[20][1], glow);
    for (const int r : {0, 2, 8, 11, 15, 20}) EXPECT_NEAR(excess[size_t(r)][1], glow, 0.1 * glow) << "ring " << r;
}

// Cloud all around the sun is not its glow: a glow rises towards the sun no faster than about the
// inverse square of the angle, so rings of cloud-white inside clear rings that show no glow measure
// little. A broken-cumulus photograph (ARM 17:19Z) whose seen pixels 12-17 degrees from the sun were
// all cloud measured 60 W m^-2 sr^-1 of glow out to 18 degrees and 2 beyond 24: a pale disc with a
// hard, coloured rim stayed around the sun as its clouds moved off. A real glare (a clipped plateau,
// then an inverse-square fall) is measured as it is.
TEST(AdvectResidual, CloudAroundTheSunIsNotMeasuredAsItsGlow) {
    const int n = 256;
    const UnitMapParams unit = AdvectResidualNetwork::load(shipped()).info().form.unit_map;
    const Vec3d sun = fisheye::direction_from_angles(30 * kPiD / 180, 1.0);
    const float base = 10.0f;
    for (const bool cloud : {true, false}) {
        // Cloud: 50 over the background within 18 degrees, a glow of 0.1 beyond. Glare: 40 out to
        // 4 degrees, then 40 (4 / a)^2.
        auto glow_at = [&](double a) {
            if (cloud) return a < 18 ? 50.0 : 0.1;
            return a < 4 ? 40.0 : 40.0 * (4 / a) * (4 / a);
        };
        cv::Mat background(n, n, CV_32FC3), start(n, n, CV_32FC3);
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const Vec3d d = fisheye::direction_from_pixel(i, j, n);
                const double a = std::acos(std::clamp(d.dot(sun), -1.0, 1.0)) * 180 / kPiD;
                const float b = radiance_to_unit(base, unit), s = radiance_to_unit(base + float(glow_at(a)), unit);
                background.at<cv::Vec3f>(j, i) = cv::Vec3f(b, b, b);
                start.at<cv::Vec3f>(j, i) = cv::Vec3f(s, s, s);
            }
        const std::vector<cv::Vec3f> excess = halo_excess(start, background, sun, unit, cv::Mat());
        ASSERT_FALSE(excess.empty());
        std::printf("%s: glow measured at 3, 8, 12, 16, 20 degrees: %.2f %.2f %.2f %.2f %.2f\n",
                    cloud ? "cloud within 18 degrees" : "glare", excess[3][1], excess[8][1], excess[12][1],
                    excess[16][1], excess[20][1]);
        for (const int r : {8, 10, 12, 14, 16, 17}) {
            if (cloud) EXPECT_LT(excess[size_t(r)][1], 5.0) << "ring " << r;  // 10 % of the cloud's
            else EXPECT_NEAR(excess[size_t(r)][1], glow_at(r + 0.5), 0.15 * glow_at(r + 0.5)) << "ring " << r;
        }
        if (!cloud) EXPECT_NEAR(excess[2][1], 40.0, 4.0);
    }
}

// A clear HDRI that does not record its sun (a downloaded one) moves as the same sky that does: its
// scale is measured against the clear-sky model of the sun its brightest pixels show. Put at a
// median of 20 instead, a sunset's sky (the sun 1.7 degrees up) was 8 x its model, read as cloud
// everywhere, and its glow was dragged across the sky (mean -6 %, fine detail +22 %).
TEST(AdvectResidual, AClearHdriWithoutItsSunMovesAsWithIt) {
    AdvectResidualNetwork net = AdvectResidualNetwork::load(shipped());
    for (const double elevation : {1.7, 30.0}) {
        ClearSkyParams p;
        p.sun_direction = fisheye::direction_from_angles((90 - elevation) * kPiD / 180, 4.2);
        const SkyImage with_sun = make_clear_sky(p, 128);
        SkyImage without = with_sun;
        without.sun_direction.reset();
        CloudMotion motion;
        motion.wind = Wind{};
        std::vector<SkyImage> a, b;
        roll(net, with_sun, motion, 20, [&](int, const SkyImage& s) { a.push_back(s); });
        const RolloutStats r = roll(net, without, motion, 20, [&](int, const SkyImage& s) { b.push_back(s); });
        ASSERT_EQ(a.size(), b.size());
        double worst = 0;
        for (size_t k = 0; k < a.size(); ++k) {
            double diff = 0, sum = 0;
            for (size_t q = 0; q < a[k].rgb.size(); ++q)
                diff += std::abs(a[k].rgb[q] - b[k].rgb[q]), sum += a[k].rgb[q];
            worst = std::max(worst, diff / sum);
        }
        std::printf("elevation %.1f: worst relative difference %.3f, mean %.3f..%.3f of the start\n", elevation, worst,
                    r.mean_min / r.mean0, r.mean_max / r.mean0);
        EXPECT_LT(worst, 0.03) << "elevation " << elevation;
        EXPECT_NEAR(r.mean_min / r.mean0, 1.0, 0.03) << "elevation " << elevation;
        EXPECT_LT(r.rim_change, 0.05) << "elevation " << elevation;
    }
}

// The pixels an import filled (SkyImage::filled: a TSI's shadow band, which runs through the sun)
// say nothing of the clouds: they take the opacity of the clouds around them. A smooth fill through
// the sun's glare, whiter and brighter than the sky, was judged cloud at the sun, and a sun the next
// photographs of the ARM day showed went out on the first step (`sky predict` from 17:28:30Z: mean
// luminance 44.2 -> 28.4). Here a clear sky with such a white band through its sun: the clouds the
// model sees at the sun (the opacity the sun's weight is judged by) are clear when the band is
// marked filled, and cloud when it is not.
TEST(AdvectResidual, AFilledBandThroughTheSunIsNotCloudOverIt) {
    ClearSkyParams p;
    p.sun_direction = fisheye::direction_from_angles(40 * kPiD / 180, 0.9);
    SkyImage sky = make_clear_sky(p, 128);
    const int n = sky.resolution;
    double sx, sy;
    fisheye::pixel_from_direction(p.sun_direction, n, &sx, &sy);
    const double len = std::hypot(sx - n / 2.0, sy - n / 2.0), ux = (sx - n / 2.0) / len, uy = (sy - n / 2.0) / len;
    const cv::Mat cut = sun_cut_mask(n, p.sun_direction);
    sky.filled.assign(size_t(n) * n, 0);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const double x = i + 0.5 - n / 2.0, y = j + 0.5 - n / 2.0;
            if (!sky.in_disc(i, j) || x * ux + y * uy < 0 || std::abs(x * uy - y * ux) > 4 || cut.at<uint8_t>(j, i))
                continue;
            sky.filled[size_t(j) * n + i] = 1;
            sky.set_pixel(i, j, Color::Constant(1.6f * luminance(sky.pixel(i, j))));  // a white fill
        }
    for (const bool marked : {true, false}) {
        auto start = std::make_shared<SkyImage>(sky);
        if (!marked) start->filled.clear();
        CloudMotion motion;
        motion.wind = Wind{};
        AdvectResidualStepModel model(AdvectResidualNetwork::load(shipped()), motion);
        model.step({start}, 30.0);
        const double t = sun_transmittance_of_opacity(model.input_cloud_opacity(), p.sun_direction);
        std::printf("band %s: transmittance of the clouds at the sun %.3f\n", marked ? "marked filled" : "unmarked", t);
        if (marked) EXPECT_GT(t, 0.95);
        else EXPECT_LT(t, 0.5) << "the white band no longer reads as cloud: the test shows nothing";
    }
}

// A grey overcast at 128 px, brighter towards its low sun (2-4 W m^-2 sr^-1 x scale).
SkyImage grey_overcast(float scale) {
    SkyImage grey(128);
    grey.sun_direction = fisheye::direction_from_angles(88 * kPiD / 180, 290 * kPiD / 180).cast<float>();
    for (int j = 0; j < 128; ++j)
        for (int i = 0; i < 128; ++i)
            if (grey.in_disc(i, j)) {
                const Vec3d w = fisheye::direction_from_pixel(i, j, 128);
                const float l = scale * float(2.0 + 2.0 * std::max(0.0, w.dot(grey.sun_direction->cast<double>())));
                for (int c = 0; c < 3; ++c) grey.rgb[(size_t(j) * 128 + i) * 3 + c] = l * (0.95f + 0.03f * c);
            }
    return grey;
}

// An overcast stays overcast under the default wind: a grey overcast at dusk (the sun 2 degrees up
// in the west-north-west, the grey brighter towards it) and, with the shared data, the ARM overcast
// dusk photograph. Its grey was added to the model's clear sky as broken cloud is, and carried from
// the bright west to the zenith it took the zenith's blue: blue bands grew through the overcast
// (cloud cover 1.00 -> 0.73 in 6 steps on the photograph).
TEST(AdvectResidual, AnOvercastStaysOvercastUnderTheWind) {
    AdvectResidualNetwork net = AdvectResidualNetwork::load(shipped());
    std::vector<std::pair<std::string, SkyImage>> starts;
    starts.emplace_back("grey overcast", grey_overcast(1.0f));
    if (test::shared_available())
        starts.emplace_back("ARM overcast dusk",
                            import_preset_photo(test::shared_path("skies/arm_tsi_sgp_20170524_overcast_dusk/images/"
                                                                  "tsi_sgpC1_20170524005000Z.jpg"),
                                                "arm-tsi", 128));
    for (auto& [name, sky] : starts) {
        CloudMotion motion;
        motion.wind = Wind{};  // the default: 12 m/s from 270 at 1500 m
        RolloutStats r = roll(net, sky, motion, 20);
        std::printf("%s: cover %.3f -> %.3f..%.3f, blue share %.3f -> at most %.3f, mean %.3f..%.3f of the start\n",
                    name.c_str(), r.cover0, r.cover_min, r.cover_max, r.blue0, r.blue_max, r.mean_min / r.mean0,
                    r.mean_max / r.mean0);
        ASSERT_GE(r.cover0, 0.95) << name << ": not an overcast start";
        EXPECT_GE(r.cover_min, 0.95) << name;
        EXPECT_LT(r.blue_max, r.blue0 + 0.02) << name;
        EXPECT_NEAR(r.mean_min / r.mean0, 1.0, 0.2) << name;
        EXPECT_NEAR(r.mean_max / r.mean0, 1.0, 0.2) << name;
    }
}

// Skies dimmer than any the network was trained on move as pure advection moves them: a clear sky
// at civil twilight (the sun 4.8 degrees down) and the grey overcast above at dusk brightness
// (x 1/300, 0.013 W m^-2 sr^-1). The network's corrections, added in the log map's units where
// such skies lie near 0, brightened the twilight sky 3.5 x in one step and the dusk overcast 4.7 x
// in ten (a night sky 40,000 x), with pure advection keeping both.
TEST(AdvectResidual, SkiesDimmerThanTheTrainingDaysMoveAsPureAdvection) {
    EXPECT_EQ(network_trust_of_brightness(0.05), 0.0);
    EXPECT_EQ(network_trust_of_brightness(0.1), 0.0);
    EXPECT_NEAR(network_trust_of_brightness(std::sqrt(0.1)), 0.5, 1e-12);
    EXPECT_EQ(network_trust_of_brightness(1.0), 1.0);
    EXPECT_EQ(network_trust_of_brightness(40.0), 1.0);
    AdvectResidualNetwork net = AdvectResidualNetwork::load(shipped());
    ClearSkyParams p;
    p.sun_direction = fisheye::direction_from_angles((90 + 4.8) * kPiD / 180, 300 * kPiD / 180);
    SkyImage twilight = make_clear_sky(p, 128, false);
    twilight.sun_direction = p.sun_direction.cast<float>();
    const SkyImage dusk = grey_overcast(1.0f / 300);
    for (const auto& [name, sky] : {std::pair<std::string, SkyImage>{"twilight", twilight}, {"dusk overcast", dusk}}) {
        CloudMotion motion;
        motion.wind = Wind{};
        const RolloutStats r = roll(net, sky, motion, 10);
        AdvectResidualNetwork advect = AdvectResidualNetwork::pure_advection(net.info().resolution, net.info().dt);
        const RolloutStats a = roll(advect, sky, motion, 10);
        std::printf("%s: mean %.4f, %.3f..%.3f of it over 10 steps (pure advection %.3f..%.3f)\n", name.c_str(),
                    r.mean0, r.mean_min / r.mean0, r.mean_max / r.mean0, a.mean_min / a.mean0, a.mean_max / a.mean0);
        EXPECT_TRUE(r.finite) << name;
        EXPECT_NEAR(r.mean_min / r.mean0, a.mean_min / a.mean0, 0.005) << name;
        EXPECT_NEAR(r.mean_max / r.mean0, a.mean_max / a.mean0, 0.005) << name;
        EXPECT_LT(r.mean_max / r.mean0, 1.05) << name;
    }
}

// Three hours of 30 s steps (issue 10's 360-step rollouts), at 128 px; one hour (120 steps) under
// DYNSKY_TEST_SMALL (the sanitizer run): the same bands, held over the first hour.
TEST(AdvectResidual, ThreeHourRolloutsFromEveryKindOfStartStayInBandAndKeepMoving) {
    AdvectResidualNetwork net = AdvectResidualNetwork::load(shipped());
    std::vector<std::pair<std::string, SkyImage>> starts;
    Image unused;
    starts.emplace_back("procedural", procedural(77, 250, 10, 128, 30, &unused));
    ClearSkyParams p;
    p.sun_direction = fisheye::direction_from_angles(0.7, 3.0);
    starts.emplace_back("clear", make_clear_sky(p, 128));
    if (test::shared_available())
        starts.emplace_back("photograph", import_preset_photo(test::shared_path("skies/arm_tsi_sgp_20170524/images/"
                                                                                "tsi_sgpC1_20170524175000Z.jpg"),
                                                              "arm-tsi", 128));
    const Wind wind{300, 9, 1500};
    for (auto& [name, sky] : starts) {
        CloudMotion motion;
        motion.wind = wind;
        SkyImage before_last, last;
        const int steps = test::run_size(360, 120);
        RolloutStats r = roll(net, sky, motion, steps, [&](int k, const SkyImage& s) {
            if (k == steps - 1) before_last = s;
            if (k == steps) last = s;
        });
        EXPECT_TRUE(r.finite) << name;
        EXPECT_GE(r.min, 0.0f) << name;
        EXPECT_LE(r.max, 1.0f) << name;
        // Issue 10's band: 20 %, the sun's pixels left out of the mean (a covered sun is lighting,
        // not drift). Measured at 128 px: procedural 0.95-1.01x, photograph 0.88-1.00x since the
        // recycled tile composes its clouds by their opacity (0.99-1.05x and 0.81-1.12x before;
        // 1.21x before the tile was scaled to the start's clouds around each pixel), clear 1.00x.
        std::printf("%s: mean %.3f..%.3f of the start (sun left out), detail >= %.2f of the start's\n", name.c_str(),
                    r.mean_min / r.mean0, r.mean_max / r.mean0, r.hf_min / r.hf0);
        const double band = 0.2;
        EXPECT_GT(r.mean_min, (1 - band) * r.mean0) << name;
        EXPECT_LT(r.mean_max, (1 + band) * r.mean0) << name;
        if (name == "clear") continue;
        EXPECT_GT(r.hf_min, 0.5 * r.hf0) << name;  // keeps at least half its fine detail
        // After three hours the clouds still move with the wind (recycled, not frozen or smeared).
        const cv::Mat produced = farneback_flow(to_network_form(before_last, net.info().form),
                                                to_network_form(last, net.info().form));
        const cv::Mat want = wind_flow(128, wind, net.info().dt);
        std::vector<double> angles, ratios;
        for (int j = 0; j < 128; ++j)
            for (int i = 0; i < 128; ++i) {
                const Vec2 uv = fisheye::pixel_center_uv(i, j, 128);
                if (uv.norm() > 0.6f) continue;
                const cv::Vec2f got = produced.at<cv::Vec2f>(j, i), w = want.at<cv::Vec2f>(j, i);
                angles.push_back(angle_deg(got, w));
                ratios.push_back(std::hypot(got[0], got[1]) / std::hypot(w[0], w[1]));
            }
        EXPECT_LT(median(angles), 20.0) << name;
        EXPECT_NEAR(median(ratios), 1.0, 0.3) << name;
    }
}

// A photograph under the default wind (12 m/s at 1500 m, no previous frame): within 10 minutes
// the whole view has been carried away and the sky is the recycled tile (motion/cloud_layer_paths.h).
// Its clouds must stay clouds: the spread of luminance over the sky (cloud against clear sky) and
// the mean stay near the start's. With the passes cross-faded as cloud
// signal scaled by the cloud around each place, the sky turned to a translucent grey haze with a
// circular seam, the mean at 0.70 of the start after 20 steps (docs/networks-advect-residual.md).
TEST(AdvectResidual, AFastWindOnAPhotographKeepsItsCloudsOpaque) {
    ASSERT_TRUE(test::shared_available());
    AdvectResidualNetwork net = AdvectResidualNetwork::load(shipped());
    const SkyImage sky = import_preset_photo(
        test::shared_path("skies/arm_tsi_sgp_20170524/images/tsi_sgpC1_20170524160000Z.jpg"), "arm-tsi", 256);
    auto spread_and_mean = [](const SkyImage& s) {
        double sum = 0, sum2 = 0;
        int count = 0;
        for (int j = 0; j < s.resolution; ++j)
            for (int i = 0; i < s.resolution; ++i) {
                if (!s.in_disc(i, j)) continue;
                const double l = luminance(s.pixel(i, j));
                sum += l, sum2 += l * l, ++count;
            }
        const double mean = sum / count;
        return std::make_pair(std::sqrt(std::max(0.0, sum2 / count - mean * mean)), mean);
    };
    const auto [spread0, mean0] = spread_and_mean(sky);
    CloudMotion motion;
    motion.wind = Wind{270, 12, 1500};
    double spread_min = 1e30, mean_min = 1e30, mean_max = 0;
    const RolloutStats r = roll(net, sky, motion, 40, [&](int k, const SkyImage& s) {
        if (k < 10) return;  // from 5 minutes on: the view has been carried away
        const auto [spread, mean] = spread_and_mean(s);
        spread_min = std::min(spread_min, spread / spread0);
        mean_min = std::min(mean_min, mean / mean0), mean_max = std::max(mean_max, mean / mean0);
    });
    std::printf("5-20 minutes: spread >= %.2f of the start's, mean %.2f..%.2f (whole sky %.2f..%.2f)\n", spread_min,
                mean_min, mean_max, r.mean_min / r.mean0, r.mean_max / r.mean0);
    // Measured at 256 px: spread >= 0.76, mean 0.83-1.01 of the start (issue 10's band: 20 %).
    EXPECT_TRUE(r.finite);
    EXPECT_GT(mean_min, 0.8);
    EXPECT_LT(mean_max, 1.2);
    EXPECT_GT(spread_min, 0.65);
}

// A sky of unknown scale (no sun: no time and place, e.g. an uncalibrated photograph or an HDRI of
// its own units) works at the networks' scale (model_scale) with its sun estimated from its
// brightest pixels: its rollout is the same whatever its units, keeps its mean and grows no cloud.
// The ARM photograph (calibrated, with its sun) at 1/50 and 1/5 of its radiance, its sun direction
// dropped. Before, a [0, 1]-scaled sky was nearly black in the networks' log map and composed over
// no background: the whole sky moved with the wind (a WSISEG photograph: mean 1.6x and cloud cover
// 0.28 -> 0.49 within 5 steps).
TEST(AdvectResidual, ASkyOfUnknownScaleMovesTheSameInAnyUnits) {
    ASSERT_TRUE(test::shared_available());
    AdvectResidualNetwork net = AdvectResidualNetwork::load(shipped());
    SkyImage sky = import_preset_photo(
        test::shared_path("skies/arm_tsi_sgp_20170524/images/tsi_sgpC1_20170524171600Z.jpg"), "arm-tsi", 128);
    sky.sun_direction.reset();
    CloudMotion motion;
    motion.wind = Wind{250, 10, 1500};
    const int steps = 30;
    std::vector<SkyImage> dim, bright;
    const RolloutStats r = roll(net, scaled_sky(sky, 1.0 / 50), motion, steps,
                                [&](int, const SkyImage& s) { dim.push_back(s); });
    roll(net, scaled_sky(sky, 1.0 / 5), motion, steps, [&](int, const SkyImage& s) { bright.push_back(s); });
    ASSERT_EQ(dim.size(), bright.size());
    double worst = 0;
    for (size_t k = 0; k < dim.size(); ++k) {
        double diff = 0, sum = 0;
        for (size_t p = 0; p < dim[k].rgb.size(); ++p)
            diff += std::abs(10.0 * dim[k].rgb[p] - bright[k].rgb[p]), sum += bright[k].rgb[p];
        worst = std::max(worst, diff / sum);
    }
    std::printf(
        "1/50 x 10 vs 1/5: worst relative difference %.2e; mean %.3f..%.3f of the start, cover %.3f -> %.3f at most\n",
        worst, r.mean_min / r.mean0, r.mean_max / r.mean0, r.cover0, r.cover_max);
    EXPECT_LT(worst, 1e-3);
    EXPECT_TRUE(r.finite);
    EXPECT_GT(r.mean_min, 0.8 * r.mean0);
    EXPECT_LT(r.mean_max, 1.2 * r.mean0);
    EXPECT_LT(r.cover_max, r.cover0 + 0.065);  // +0.049 (+0.083 at the sky's own scale)
    // Each step records the sun estimated on the start (a prediction continued from a step, a cloud
    // dimming its sun, looked for it again and lost it).
    const std::optional<Vec3d> found = sun_from_brightest_pixels(scaled_sky(sky, 1.0 / 5));
    ASSERT_TRUE(found);
    for (const SkyImage& s : {bright.front(), bright.back()}) {
        ASSERT_TRUE(s.sun_direction);
        EXPECT_LT((s.sun_direction->cast<double>() - *found).norm(), 1e-6);
    }
}

// --prev: the gap comes from the frames' clocks unless given; a "previous" frame from after the sky,
// or hours before it, is refused naming both files (its motion says nothing about this sky's).
TEST(AdvectResidual, APreviousFrameMustComeShortlyBeforeTheSky) {
    SkyImage sky(8), previous(8);
    sky.has_clock = previous.has_clock = true;
    sky.time_seconds = 1000, previous.time_seconds = 970;
    EXPECT_DOUBLE_EQ(previous_frame_gap(sky, previous, 0, "b.exr", "a.exr"), 30.0);
    EXPECT_DOUBLE_EQ(previous_frame_gap(sky, previous, 60, "b.exr", "a.exr"), 60.0);  // given wins
    previous.time_seconds = 1030;
    try {
        previous_frame_gap(sky, previous, 0, "b.exr", "a.exr");
        FAIL() << "a later 'previous' frame was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("a.exr"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("b.exr"), std::string::npos) << e.what();
    }
    previous.time_seconds = 1000;  // the sky itself given as its previous frame
    try {
        previous_frame_gap(sky, previous, 0, "b.exr", "b.exr");
        FAIL() << "a frame of the same time was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("at the same time as"), std::string::npos) << e.what();
    }
    previous.time_seconds = 1000 - 7200;
    EXPECT_THROW(previous_frame_gap(sky, previous, 0, "b.exr", "a.exr"), Error);
    // A sequence's first frame is at 0 on its clock: frames 0 and 1 of a 10 s sequence are 10 s apart
    // (taken as one medium step, 30 s, the clouds moved a third as fast).
    previous.time_seconds = 0, sky.time_seconds = 10;
    EXPECT_DOUBLE_EQ(previous_frame_gap(sky, previous, 0, "b.exr", "a.exr"), 10.0);
    previous.has_clock = false;  // no clock in one file, no recorded times: one medium step
    EXPECT_DOUBLE_EQ(previous_frame_gap(sky, previous, 0, "b.exr", "a.exr"), 0.0);
    EXPECT_THROW(previous_frame_gap(sky, previous, -5, "b.exr", "a.exr"), Error);
    // Two imported photographs (dynsky:time 0 on both): the times their import recorded, in any zone.
    // Taken as one 30 s step, a 60 s Mobotix pair moved the clouds twice as fast.
    sky.time_seconds = 0, previous.has_clock = true;
    previous.source = "photo:/x/2020-08-12_09_19.jpg (hdr: mean-luminance fallback) time=2020-08-12T09:19:00+02:00";
    sky.source = "photo:/x/2020-08-12_09_20.jpg (hdr: clear-sky pixels) time=2020-08-12T07:20:00Z";
    EXPECT_NEAR(previous_frame_gap(sky, previous, 0, "b.exr", "a.exr"), 60.0, 1e-3);
    EXPECT_THROW(previous_frame_gap(previous, sky, 0, "a.exr", "b.exr"), Error);  // the other way round
    sky.has_clock = false;  // a file without a clock: the recorded times still say
    EXPECT_NEAR(previous_frame_gap(sky, previous, 0, "b.exr", "a.exr"), 60.0, 1e-3);
    sky.source = "photo:/x/2020-08-12_09_20.jpg (hdr: clear-sky pixels)";  // no time recorded
    EXPECT_DOUBLE_EQ(previous_frame_gap(sky, previous, 0, "b.exr", "a.exr"), 0.0);
    sky.source = "photo:/x/y.jpg time=not-a-time";
    EXPECT_DOUBLE_EQ(previous_frame_gap(sky, previous, 0, "b.exr", "a.exr"), 0.0);
}

// The wind a measured flow gives leaves out the sun's aureole, which Farneback tracks as it moves
// with the sun: the clouds' own wind comes out however the glare around the sun moved.
TEST(AdvectResidual, TheWindFittedToAMeasuredFlowLeavesOutTheSunsAureole) {
    const int n = 64;
    Wind wind;
    wind.from_deg = 250, wind.speed_mps = 8;
    const cv::Mat clouds = wind_flow(n, wind, 30.0);
    const Vec3d sun = fisheye::direction_from_angles(0.5, 1.0);  // 29 degrees from the zenith
    MeasuredMotion m;
    m.smoothed = clouds.clone();
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            if (fisheye::direction_from_pixel(double(x), double(y), n).dot(sun) > std::cos(25.0 * kPiD / 180))
                m.smoothed.at<cv::Vec2f>(y, x) = cv::Vec2f(-3.0f, 2.0f);  // the glare's own motion
    auto error = [&](const CloudFlow& f) { return cv::norm(f.wind, clouds, cv::NORM_INF); };
    EXPECT_LT(error(CloudFlow::from_measured(m, 30.0, sun)), 0.02);
    EXPECT_GT(error(CloudFlow::from_measured(m, 30.0)), 0.1);  // with it, the wind goes astray
}

// A measured motion moves the clouds by its confirmed flow on the first step; after that only
// the departure from the fitted wind that the flow measured back agreed with is kept: where it did
// not agree, the clouds take the wind (Farneback's noise held for steps swirls big clouds).
TEST(AdvectResidual, AMeasuredFlowKeepsOnlyItsAgreedDepartureAfterTheFirstStep) {
    const int n = 64;
    const double c = (n - 1) / 2.0;
    MeasuredMotion m;
    m.smoothed = cv::Mat(n, n, CV_32FC2), m.confirmed = cv::Mat(n, n, CV_32FC2);
    m.agreement = cv::Mat(n, n, CV_32FC1);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            // A uniform wind plus a swirl, and a sharper detail on top of it.
            const cv::Vec2f swirl(float(-(j - c) / c), float((i - c) / c));
            m.smoothed.at<cv::Vec2f>(j, i) = cv::Vec2f(2.0f, 0.5f) + 0.6f * swirl;
            m.confirmed.at<cv::Vec2f>(j, i) = m.smoothed.at<cv::Vec2f>(j, i) + cv::Vec2f(i % 4 == 0 ? 0.5f : 0.0f, 0);
            m.agreement.at<float>(j, i) = i < n / 2 ? 0.0f : 1.0f;
        }
    const cv::Mat smoothed = m.smoothed.clone();
    const CloudFlow f = CloudFlow::from_measured(m, 30.0);
    // The caller's flow is left as it was (an expression assigned to a header of it was written into
    // it, and the checks below compared the result with itself).
    EXPECT_EQ(cv::norm(m.smoothed, smoothed, cv::NORM_INF), 0.0);
    EXPECT_LT(cv::norm(f.measured, m.confirmed, cv::NORM_INF), 1e-6);  // the first step: as confirmed
    const cv::Mat kept = f.measured - f.detail;
    double off_wind = 0, off_smoothed = 0, departure = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const cv::Vec2f k = kept.at<cv::Vec2f>(j, i);
            if (i < n / 2) off_wind = std::max(off_wind, double(cv::norm(k - f.wind.at<cv::Vec2f>(j, i))));
            else off_smoothed = std::max(off_smoothed, double(cv::norm(k - smoothed.at<cv::Vec2f>(j, i))));
            departure = std::max(departure,
                                 double(cv::norm(smoothed.at<cv::Vec2f>(j, i) - f.wind.at<cv::Vec2f>(j, i))));
        }
    EXPECT_GT(departure, 0.3);      // there is a departure to keep or drop
    EXPECT_LT(off_wind, 1e-5);      // not agreed: the wind
    EXPECT_LT(off_smoothed, 1e-5);  // agreed: the smoothed flow, departure and all
    // Without the agreement (a motion from elsewhere) the whole smoothed departure is kept.
    m.agreement = cv::Mat();
    const CloudFlow g = CloudFlow::from_measured(m, 30.0);
    EXPECT_LT(cv::norm(g.measured - g.detail, m.smoothed, cv::NORM_INF), 1e-5);
}

// The previous pair says how much of the network's correction this sky takes: the least-squares
// share of it that explains what the warp alone missed, in [0, 1]; a rollout takes that share on
// its first step (later steps take it whole).
TEST(AdvectResidual, APreviousPairSaysHowMuchOfTheCorrectionToTake) {
    AdvectResidualNetwork net = AdvectResidualNetwork::load(shipped());
    const int n = net.info().resolution;
    Image exact;
    const SkyImage sky = procedural(5, 250, 12, n, 30, &exact);
    cv::Mat previous = to_network_form(sky, net.info().form);
    fill_saturated_pixels(&previous);
    cv::Mat flow = wind_flow(n, Wind{250, 12, 1500}, 30);
    const cv::Mat warped = warp_in_disc(previous, flow), correction = net.step_network(previous, flow) - warped;
    ASSERT_GT(cv::norm(correction), 0.05);  // the network changes something here
    const cv::Mat seen = sky_disc_mask(n);
    for (double share : {0.0, 0.3, 0.7}) {
        const cv::Mat current = warped + correction * share;
        EXPECT_NEAR(net.correction_gain(previous, current, seen, flow), share, 1e-3) << share;
    }
    EXPECT_EQ(net.correction_gain(previous, warped - correction, seen, flow), 0.0);      // against it: none
    EXPECT_EQ(net.correction_gain(previous, warped + correction * 3, seen, flow), 1.0);  // at most all
    // Pixels not seen in both frames say nothing: a wrong current there changes nothing.
    cv::Mat half = seen.clone(), current = warped + correction * 0.3;
    half(cv::Rect(0, 0, n / 2, n)) = 0;
    current(cv::Rect(0, 0, n / 2, n)) = warped(cv::Rect(0, 0, n / 2, n)) - correction(cv::Rect(0, 0, n / 2, n));
    EXPECT_NEAR(net.correction_gain(previous, current, half, flow), 0.3, 1e-3);
    EXPECT_EQ(AdvectResidualNetwork::pure_advection().correction_gain(previous, current, seen, flow), 1.0);

    // A rollout's first step takes the share: none of it is pure advection's step.
    CloudFlow none = CloudFlow::constant(flow), all = none;
    none.correction_gain = 0.0;
    AdvectResidualNetwork advect = AdvectResidualNetwork::pure_advection(n);
    cv::Mat with_none, with_all, advected;
    net.rollout_network_form(previous, none, 1, [&](int, const cv::Mat& s) { with_none = s.clone(); });
    net.rollout_network_form(previous, all, 1, [&](int, const cv::Mat& s) { with_all = s.clone(); });
    advect.rollout_network_form(previous, all, 1, [&](int, const cv::Mat& s) { advected = s.clone(); });
    EXPECT_LT(cv::norm(with_none, advected, cv::NORM_INF), 1e-5);
    EXPECT_GT(cv::norm(with_all, advected, cv::NORM_INF), 0.01);
}

TEST(AdvectResidual, BadModelFoldersFailClearly) {
    const std::string dir = test::temp_dir("advect_bad");
    EXPECT_THROW(AdvectResidualNetwork::load(dir + "/missing"), Error);
    fs::create_directories(dir + "/m");
    std::ofstream(dir + "/m/model.json")
        << R"({"format": "dynsky-cloud-model", "version": 3, "kind": "advect-residual"})";
    try {
        AdvectResidualNetwork::load(dir + "/m");
        ADD_FAILURE() << "version 3 accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("version 3"), std::string::npos) << e.what();
    }
    std::ofstream(dir + "/m/model.json") << R"({"format": "dynsky-cloud-model", "version": 2, "kind": "advect-residual",
        "resolution": 64, "dt_s": 30})";
    try {
        AdvectResidualNetwork::load(dir + "/m");
        ADD_FAILURE() << "missing model.onnx accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("model.onnx"), std::string::npos) << e.what();
    }
    fs::remove_all(dir);
}

}  // namespace
}  // namespace dynsky
