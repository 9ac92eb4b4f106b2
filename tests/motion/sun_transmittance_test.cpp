// The sun dimmed by passing clouds (motion/sun_patch.h estimate_sun_transmittance): on a procedural
// sky whose cloud crosses the sun (ground truth: the procedural sky itself) and on the ARM TSI day
// against the imager's own cloud masks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <vector>
#include <sstream>

#include "motion/advect_residual.h"
#include "motion/flow.h"
#include "motion/network_form.h"
#include "motion/network_step_model.h"
#include "motion/photo_sequence.h"
#include "motion/sky_timeline.h"
#include "motion/sun_patch.h"
#include "sky/clear_sky.h"
#include "sky/fisheye.h"
#include "sky/hdr_recovery.h"
#include "sky/preset_import.h"
#include "sky/procedural_clouds.h"
#include "sky/sun_position.h"
#include "tests/sky/frozen_cumulus.h"
#include "tests/test_support.h"

namespace dynsky {
namespace {

namespace fs = std::filesystem;


TEST(SunTransmittance, ClearSkyLetsTheSunThrough) {
    ClearSkyParams p;
    p.sun_direction = fisheye::direction_from_angles(0.8, 2.0);
    SkyImage clear = make_clear_sky(p, 256);
    remove_sun(&clear);  // as the timeline and the networks estimate it: with the sun cut out
    EXPECT_GT(estimate_sun_transmittance(clear, p.sun_direction), 0.95);
    // A uniform grey overcast around the sun: none.
    SkyImage grey(256);
    for (int j = 0; j < 256; ++j)
        for (int i = 0; i < 256; ++i) grey.set_pixel(i, j, Color(300, 300, 300));
    EXPECT_LT(estimate_sun_transmittance(grey, p.sun_direction), 0.05);
}

// Frozen cumulus under a steady wind (12 m/s from 250 degrees), the first seed whose sun starts
// clear and is covered within `duration` seconds (looked at every dt); nullopt when none is.
std::optional<ProceduralSkyParams> cloud_crossing_the_sun(double duration, double dt) {
    for (uint64_t seed = 1; seed < 200; ++seed) {
        const ProceduralSkyParams p = test::frozen_cumulus(seed);
        if (procedural_sun_transmittance(p, 0) < 0.95) continue;
        for (double t = dt; t <= duration; t += dt)
            if (procedural_sun_transmittance(p, t) < 0.1) return p;
    }
    return std::nullopt;
}

// What the moving sky cannot judge around the sun is the same part of the sky at any resolution:
// every pixel within kSunUnseenDeg of the sun (the cut shrinks from 5.6 to 1.35 degrees between 128
// and 1024 px), the cut included, and nothing beyond the cut's reach or the disc's.
TEST(SunTransmittance, UnseenSkyAroundTheSunIsTheSameAtAnyResolution) {
    const Vec3d sun = fisheye::direction_from_angles(0.8, 1.2);
    for (int n : {64, 128, 512, 1024}) {
        const cv::Mat unseen = sun_unseen_mask(n, sun), cut = sun_cut_mask(n, sun);
        EXPECT_EQ(cv::countNonZero(cut & ~unseen), 0) << n;
        double farthest = 0, nearest_out = 180;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                if (fisheye::pixel_center_uv(i, j, n).squaredNorm() > 1) {
                    EXPECT_EQ(unseen.at<uint8_t>(j, i), 0) << n << ": off the disc";
                    continue;
                }
                const double a = std::acos(std::clamp(fisheye::direction_from_pixel(i, j, n).dot(sun), -1.0, 1.0)) *
                                 180 / kPiD;
                if (unseen.at<uint8_t>(j, i)) farthest = std::max(farthest, cut.at<uint8_t>(j, i) ? 0.0 : a);
                else nearest_out = std::min(nearest_out, a);
            }
        EXPECT_GE(nearest_out, kSunUnseenDeg) << n << ": a pixel this close to the sun was left judged";
        EXPECT_LE(farthest, kSunUnseenDeg) << n;
    }
    EXPECT_EQ(cv::countNonZero(sun_unseen_mask(128, Vec3d(0, -1, 0))), 0);  // the sun below the horizon
}

// The cumulus above moved by pure advection along its wind: the moved sky shows the cloud reaching
// the sun, and the sun put back must follow the procedural sky's own.
TEST(SunTransmittance, CloudCrossingTheSunDimsItAsTheProceduralSkyDoes) {
    const double duration = 120, dt = 10;
    const std::optional<ProceduralSkyParams> crossing = cloud_crossing_the_sun(duration, dt);
    ASSERT_TRUE(crossing);
    const ProceduralSkyParams& p = *crossing;
    const int n = 128;
    ProceduralSky truth(p);
    SkyImage input = truth.render(0, n);
    CloudMotion motion;
    motion.wind = Wind{p.layers[0].wind_from_deg, p.layers[0].wind_speed_mps, p.layers[0].altitude_m};
    SkyTimeline timeline(input, make_network_step_model("advect", motion), dt);
    // The sun's share of the input's illuminance (what a cloud over it can take away).
    SkyImage cut = input;
    remove_sun(&cut);
    const double sun_lx = horizontal_illuminance(input) - horizontal_illuminance(cut);
    // When the cloud's edge reaches the sun (the truth's transmittance first below one half).
    double t_cover = -1;
    for (double t = 0; t <= duration + 1e-9 && t_cover < 0; t += 5)
        if (truth.sun_transmittance(t) < 0.5) t_cover = t;
    double worst = 0, worst_undimmed = 0, worst_edge = 0, sum = 0;
    int frames = 0;
    for (double t = 0; t <= duration + 1e-9; t += 5) {
        SkyImage frame = timeline.sky_at(t);
        double want = horizontal_illuminance(truth.render(t, n)), got = horizontal_illuminance(frame);
        if (t >= t_cover - 10 - 1e-9 && t <= t_cover + 1e-9)
            worst_edge = std::max(worst_edge, std::abs(got / want - 1));
        double undimmed = got + (1 - timeline.last_sun_weight()) * sun_lx;  // the sun put back as it was
        worst = std::max(worst, std::abs(got / want - 1));
        worst_undimmed = std::max(worst_undimmed, std::abs(undimmed / want - 1));
        sum += std::abs(got / want - 1), ++frames;
        std::printf("t %5.1f s  truth %7.0f lx (sun T %.2f)  timeline %7.0f lx (sun weight %.2f)  undimmed %7.0f lx\n",
                    t, want, truth.sun_transmittance(t), got, timeline.last_sun_weight(), undimmed);
    }
    std::printf(
        "seed %llu: largest error %.1f %% (mean %.1f %%), in the 10 s up to the edge covering the sun (t = %.0f s) "
        "%.1f %%; with the sun put back undimmed %.1f %%\n",
        (unsigned long long)p.seed, 100 * worst, 100 * sum / frames, t_cover, 100 * worst_edge, 100 * worst_undimmed);
    // Follows the truth: every frame within 15 %, mean within 4 %, from 10 s before the cloud's edge
    // covers the sun to the frame it does within 15 %. (Composed additively over the background,
    // the moved sky was 14-18 % over the truth once covered, 18.4 % at worst; judged by the moved
    // sky's look alone, the sun shone on at half strength the frame the cloud covered it.)
    EXPECT_LT(worst_edge, 0.15);
    EXPECT_LT(sum / frames, 0.04);
    EXPECT_LT(worst, 0.15);
    EXPECT_GT(worst_undimmed, 0.5) << "the cloud over the sun must matter, or the test says nothing";
}

// A grey cloud in front of the aureole: on seed 27 of the sky above the sun sits at a cumulus's edge
// and is covered 5 s later. Within 10 degrees of the sun the cloud is 0.78 as bright as the white
// aureole and 1.12-1.2 as red/blue, inside the look rule's thresholds: read clear, the cloud was
// carried over the sun as clear sky and the sun shone on at 2.8x the truth's illuminance for 35 s
// (mean 48 % at 128 px, 59 % at 512). Near the sun the rule now tightens to what the sky's own clear
// pixels allow. At 256 px (128 under DYNSKY_TEST_SMALL), every 5 s over the first 30 s.
TEST(SunTransmittance, AGreyCloudBesideTheSunCoversItWhenItArrives) {
    const double dt = 10;
    ProceduralSkyParams p = *cloud_crossing_the_sun(120, dt);
    p.seed = 27;
    ASSERT_GT(procedural_sun_transmittance(p, 0), 0.95);
    ASSERT_LT(procedural_sun_transmittance(p, 10), 0.1);
    const int n = test::run_size(256, 128);
    ProceduralSky truth(p);
    CloudMotion motion;
    motion.wind = Wind{p.layers[0].wind_from_deg, p.layers[0].wind_speed_mps, p.layers[0].altitude_m};
    SkyTimeline timeline(truth.render(0, n), make_network_step_model("advect", motion), dt);
    double sum = 0;
    int frames = 0;
    for (double t = 0; t <= 30 + 1e-9; t += 5) {
        const double want = horizontal_illuminance(truth.render(t, n));
        const double got = horizontal_illuminance(timeline.sky_at(t));
        std::printf("t %4.1f s  truth %7.0f lx  timeline %7.0f lx  (sun weight %.2f)\n", t, want, got,
                    timeline.last_sun_weight());
        sum += std::abs(got / want - 1), ++frames;
    }
    std::printf("mean error %.1f %%\n", 100 * sum / frames);
    EXPECT_LT(sum / frames, 0.15);
}

// The first `count` seeds of the sky above whose sun starts clear and is covered within
// `duration` s (chosen by that rule alone, not by how they fare).
std::vector<ProceduralSkyParams> clouds_crossing_the_sun(int count, double duration, double dt) {
    std::vector<ProceduralSkyParams> out;
    ProceduralSkyParams p = *cloud_crossing_the_sun(duration, dt);
    for (uint64_t seed = 1; seed < 500 && int(out.size()) < count; ++seed) {
        p.seed = seed;
        if (procedural_sun_transmittance(p, 0) < 0.95) continue;
        for (double t = dt; t <= duration; t += dt)
            if (procedural_sun_transmittance(p, t) < 0.1) {
                out.push_back(p);
                break;
            }
    }
    return out;
}

// The same over several seeds, among them clouds already at the sun's edge in the input (covered
// within 5-25 s), which the look near the sun calls clear. bench/sun_seeds measures more.
TEST(SunTransmittance, CloudsCrossingTheSunOnSeveralSeeds) {
    const double duration = 120, dt = 10;
    // 8 seeds (3-12), 4 under DYNSKY_TEST_SMALL.
    const std::vector<ProceduralSkyParams> seeds = clouds_crossing_the_sun(test::run_size(8, 4), duration, dt);
    ASSERT_EQ(int(seeds.size()), test::run_size(8, 4));
    const int n = 128;
    double sum = 0;
    int frames = 0;
    std::vector<double> worst;
    for (const ProceduralSkyParams& p : seeds) {
        ProceduralSky truth(p);
        CloudMotion motion;
        motion.wind = Wind{p.layers[0].wind_from_deg, p.layers[0].wind_speed_mps, p.layers[0].altitude_m};
        SkyTimeline timeline(truth.render(0, n), make_network_step_model("advect", motion), dt);
        double w = 0, s = 0;
        int f = 0;
        for (double t = 0; t <= duration + 1e-9; t += 5) {
            const double e =
                std::abs(horizontal_illuminance(timeline.sky_at(t)) / horizontal_illuminance(truth.render(t, n)) - 1);
            w = std::max(w, e), s += e, ++f;
        }
        std::printf("seed %llu: largest error %.1f %%, mean %.1f %%\n", (unsigned long long)p.seed, 100 * w,
                    100 * s / f);
        worst.push_back(w), sum += s, frames += f;
    }
    std::sort(worst.begin(), worst.end());
    const double median_worst = worst[worst.size() / 2];
    std::printf("mean frame error %.1f %%, median of the seeds' largest %.1f %%\n", 100 * sum / frames,
                100 * median_worst);
    // Measured 10.4 % and 83 % (4 seeds: 9.2 %, 63 %) against the truth's sun dimmed by the cloud
    // on its line of sight. Against the truth before it, whose sun the cloud at each pixel's centre
    // dimmed (early or late by 5 s at an edge): 8.6 % and 60 % (4 seeds: 6.8 %, 60 %); with the look
    // rule not tightened near the sun and the sun's weight relative to the start's cover: 10.4 % and
    // 60 % (4 seeds: 9.8 %, 59 %); with the sun's cut counted as clear sky (before that): 12.5 % and
    // 127 % (4 seeds: 14.9 %, 127 %). Some seeds still miss by 50-190 % in a few frames
    // (docs/animation.md).
    EXPECT_LT(sum / frames, 0.115);
    EXPECT_LT(median_worst, 1.0);
}

// `sky predict` (AdvectResidualNetwork::rollout: no timeline, the sun cut where the sky clips) dims
// the sun by the same rule as the timeline (sun_weight_reference), on the same seeds at the steps.
TEST(SunTransmittance, PredictedStepsDimTheSunAsTheTimelineDoes) {
    const double duration = 120, dt = 10;
    const std::vector<ProceduralSkyParams> seeds = clouds_crossing_the_sun(test::run_size(8, 4), duration, dt);
    const int n = 128;
    AdvectResidualNetwork advect = AdvectResidualNetwork::pure_advection();
    double sum = 0;
    int frames = 0;
    for (const ProceduralSkyParams& p : seeds) {
        ProceduralSky truth(p);
        const Wind wind{p.layers[0].wind_from_deg, p.layers[0].wind_speed_mps, p.layers[0].altitude_m};
        double s = 0;
        int f = 0;
        advect.rollout(truth.render(0, n), CloudFlow::from_wind(wind_flow(n, wind, dt)), int(duration / dt),
                       [&](int k, const SkyImage& sky) {
                           s += std::abs(horizontal_illuminance(sky) / horizontal_illuminance(truth.render(k * dt, n)) -
                                         1);
                           ++f;
                       });
        std::printf("seed %llu: mean error %.1f %%\n", (unsigned long long)p.seed, 100 * s / f);
        sum += s, frames += f;
    }
    std::printf("mean step error %.1f %%\n", 100 * sum / frames);
    // Measured 11.5 % (4 seeds: 9.4 %; the timeline, every 5 s: 10.4 %) against the truth's sun
    // dimmed on its line of sight. Against the truth dimmed at pixel centres: 9.7 % (4 seeds: 6.8 %);
    // 11.1 % (4 seeds: 8.1 %) with the sun's weight relative to the start's cover at the sun alone,
    // as `sky predict` had it.
    EXPECT_LT(sum / frames, test::run_size(0.125, 0.105));
}

// A sun seen through an even overcast (a grey sky, its sun one bright pixel): the look around it
// and the opacity the model carries both read cloud at the start and nothing thickens it, so a
// sky that does not change keeps its sun. It went out on the first step (0 / 0.05), 33 x darker,
// for a sun bright (elevation 60) or dim (a tenth as bright), in the timeline and in `sky predict`;
// with the sun's direction recorded or found from the brightest pixel.
TEST(SunTransmittance, ASunSeenThroughAnOvercastIsKeptWhileNothingChanges) {
    const int n = 64;
    const Vec3d sun = fisheye::direction_from_angles(30.0 * kPiD / 180.0, 10.0 * kPiD / 180.0);
    for (const double sun_radiance : {5e4, 5e3})
        for (const bool recorded : {true, false}) {
            SkyImage grey(n);
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i)
                    if (fisheye::pixel_center_uv(i, j, n).squaredNorm() <= 1.0)
                        for (int c = 0; c < 3; ++c) grey.rgb[(size_t(j) * n + i) * 3 + c] = 1.0f;
            double x, y;
            fisheye::pixel_from_direction(sun, n, &x, &y);
            for (int c = 0; c < 3; ++c) grey.rgb[(size_t(y) * n + size_t(x)) * 3 + c] = float(sun_radiance);
            if (recorded) grey.sun_direction = sun.cast<float>();
            const double start = horizontal_illuminance(grey);
            const std::string what = std::to_string(sun_radiance) + (recorded ? ", recorded" : ", found");
            if (recorded) {
                CloudMotion still;
                still.wind = Wind{270, 0, 1500};
                SkyTimeline timeline(grey, make_network_step_model("advect", still), 10);
                for (double t : {5.0, 10.0, 25.0})
                    // The dim sun (under half the clear one's) comes back as the clear sun's disc at its
                    // share: its irradiance, spread a little otherwise (2.7 %).
                    EXPECT_NEAR(horizontal_illuminance(timeline.sky_at(t)) / start, 1.0, 0.03) << what << " t " << t;
            }
            AdvectResidualNetwork advect = AdvectResidualNetwork::pure_advection();
            advect.rollout(grey, CloudFlow::from_wind(wind_flow(n, Wind{270, 0, 1500}, 30)), 3,
                           [&](int k, const SkyImage& sky) {
                               EXPECT_NEAR(horizontal_illuminance(sky) / start, 1.0, 0.01) << what << " step " << k;
                           });
        }
}

// With no wind nothing moves, so a sun that starts whole keeps its radiance however near a cloud
// is: with one within 3 degrees (read as covering it) the sun went to half on the first step in
// `sky predict` (procedural seeds: 0.50, 0.93, 0.78 of it) and in the timeline.
TEST(SunTransmittance, NothingMovesWithoutWindSoTheSunKeepsItsRadiance) {
    const int n = 128;
    const Wind still_air{270, 0, 1500};
    int near_cloud = 0, tried = 0;
    for (uint64_t seed = 1; seed <= 24 && tried < test::run_size(8, 3); ++seed) {
        const ProceduralSkyParams p = test::frozen_cumulus(seed);
        ProceduralSky truth(p);
        if (truth.sun_transmittance(0) < 0.95) continue;
        ++tried;
        const SkyImage start = truth.render(0, n);
        const double e0 = horizontal_illuminance(start);
        CloudMotion still;
        still.wind = still_air;
        SkyTimeline timeline(start, make_network_step_model("advect", still), 30);
        for (double t : {10.0, 30.0, 90.0})
            EXPECT_NEAR(horizontal_illuminance(timeline.sky_at(t)) / e0, 1.0, 0.01) << "seed " << seed << ", t " << t;
        const cv::Mat o = timeline.model().input_cloud_opacity();
        ASSERT_FALSE(o.empty());
        if (sun_transmittance_of_opacity(o, p.clear_sky.sun_direction) < 0.8) ++near_cloud;
        AdvectResidualNetwork advect = AdvectResidualNetwork::pure_advection();
        advect.rollout(start, CloudFlow::from_wind(wind_flow(n, still_air, 30)), 3, [&](int k, const SkyImage& s) {
            EXPECT_NEAR(horizontal_illuminance(s) / e0, 1.0, 0.01) << "seed " << seed << ", step " << k;
        });
    }
    EXPECT_GE(near_cloud, 1) << "no start with a cloud beside its sun: the test shows nothing";
}

// A clear photograph keeps its sun: the ARM clear morning (the sun 17 degrees up, the glare
// between it and the horizon brighter than the clear-sky model). Its calibration fitted the sky's
// brightness to the model, so the opacity near the sun was judged 1.4 x tighter in brightness than
// the rule and read that glare as cloud over a whole sun: the sun went out for good with the
// measured motion (mean luminance 22.8 -> 8.6) and for three steps under the wind.
TEST(SunTransmittance, AClearPhotographKeepsItsSun) {
    DYNSKY_REQUIRE_SHARED();
    const std::string dir = "skies/arm_tsi_sgp_20170524_clear_morning/images/";
    const SkyImage previous = import_preset_photo(test::shared_path(dir + "tsi_sgpC1_20170524124930Z.jpg"), "arm-tsi",
                                                  256);
    const SkyImage sky = import_preset_photo(test::shared_path(dir + "tsi_sgpC1_20170524125000Z.jpg"), "arm-tsi", 256);
    ASSERT_TRUE(sky.sun_direction);
    EXPECT_EQ(clear_sky_turbidity(sky, sky.sun_direction->cast<double>()), 3.0);  // a photograph: the default
    const double start = horizontal_illuminance(sky);
    AdvectResidualNetwork advect = AdvectResidualNetwork::pure_advection();
    for (const bool measured : {true, false}) {
        CloudMotion motion;
        if (measured) motion.previous = std::make_shared<const SkyImage>(previous), motion.previous_dt = 30;
        else motion.wind = Wind{};
        advect.rollout(sky, advect.motion_flow(sky, motion, 30, sky.resolution), 4, [&](int k, const SkyImage& s) {
            EXPECT_NEAR(horizontal_illuminance(s) / start, 1.0, 0.05)
                << (measured ? "measured motion" : "wind") << ", step " << k;
        });
    }
}

// A clear sky at sunrise keeps its sun in `sky predict` and in the timeline. At turbidity 3 it is
// red enough all over for the networks' cloud rule to call it overcast, but its sun shows whole
// (the overcast rule put it out on the first step: 2.58 -> 0.01); at turbidity 2 its aureole,
// against the background's turbidity 3, read as cloud over the sun (out for 11-14 minutes): the
// background is a clear sky's own turbidity (clear_sky_turbidity).
TEST(SunTransmittance, AClearSkyAtSunriseKeepsItsSun) {
    for (const auto& [time, turbidity] : {std::pair<const char*, double>{"2026-06-21T04:10:00Z", 3.0},
                                          std::pair<const char*, double>{"2026-06-21T04:20:00Z", 2.0}}) {
        ClearSkyParams p;  // Paris on 21 June: the sun 1.3 and 2.7 degrees up in the north-east
        p.sun_direction = compute_sun_position(parse_utc_time(time), GeoLocation{48.8566, 2.3522, 0}).direction();
        p.turbidity = turbidity;
        const SkyImage sky = make_clear_sky(p, 256);
        EXPECT_DOUBLE_EQ(clear_sky_turbidity(sky, p.sun_direction), turbidity) << time;
        const double start = horizontal_illuminance(sky);
        AdvectResidualNetwork advect = AdvectResidualNetwork::pure_advection();
        CloudMotion motion;
        motion.wind = Wind{};
        advect.rollout(sky, advect.motion_flow(sky, motion, 30, sky.resolution), 3, [&](int k, const SkyImage& s) {
            EXPECT_NEAR(horizontal_illuminance(s) / start, 1.0, 0.03) << time << ", sky predict, step " << k;
        });
        SkyTimeline timeline(sky, make_network_step_model("advect", motion), 30);
        for (double t : {15.0, 30.0, 60.0})
            EXPECT_NEAR(horizontal_illuminance(timeline.sky_at(t)) / start, 1.0, 0.03) << time << ", timeline, t " << t;
    }
}

TEST(SunTransmittance, RelativeTransmittanceIsContinuousAndKeepsAnOpaqueStart) {
    EXPECT_DOUBLE_EQ(relative_transmittance(0.25, 0.5), 0.5);
    EXPECT_DOUBLE_EQ(relative_transmittance(1.0, 0.5), 1.0);  // never brighter than it was
    EXPECT_DOUBLE_EQ(relative_transmittance(0.0, 0.0), 1.0);  // an opaque start: nothing to thicken
    EXPECT_NEAR(relative_transmittance(0.0, 0.0499999), 0.0, 1e-5);
    EXPECT_NEAR(relative_transmittance(0.0, 0.025), 0.5, 1e-12);
    EXPECT_NEAR(relative_transmittance(0.02, 0.05), 0.4, 1e-12);
}

// A sun partly seen through the cloud around it: under an overcast (its disc at least
// kOvercastCloudShare cloud) a thin cloud it shines through, kept while nothing thickens it; under
// broken cloud it is at a cloud's edge, and once the clouds have moved a sun's diameter the cover
// moved over it decides (procedural seed 8: half out for the whole minute, the truth's in within
// 10 s).
TEST(SunTransmittance, ASunHalfSeenAtABrokenCloudsEdgeGoesInWhenTheCloudComes) {
    // moved T, start T, start look, input sun share, travel, cloud share
    EXPECT_DOUBLE_EQ(opacity_sun_weight(0.0, 0.0, 0.0, 0.3, 1.0, 0.9), 1.0);      // overcast: kept
    EXPECT_DOUBLE_EQ(opacity_sun_weight(0.0, 0.0, 0.0, 0.3, 1.0, 0.5), 0.0);      // broken: gone in
    EXPECT_DOUBLE_EQ(opacity_sun_weight(0.0, 0.0, 0.0, 0.3, 0.0, 0.5), 1.0);      // nothing moved yet
    EXPECT_DOUBLE_EQ(opacity_sun_weight(0.6, 0.0, 0.0, 0.3, 1.0, 0.5), 1.0);      // clearer than the start
    EXPECT_NEAR(opacity_sun_weight(0.15, 0.0, 0.0, 0.3, 0.5, 0.5), 0.75, 1e-12);  // halfway: 1/2 + 1/2 x 1/2
    cv::Mat half = cv::Mat::zeros(64, 64, CV_32FC1);
    half.rowRange(0, 32).setTo(1.0f);
    EXPECT_NEAR(cloud_share(half), 0.5, 0.02);
    EXPECT_DOUBLE_EQ(cloud_share(cv::Mat::ones(64, 64, CV_32FC1)), 1.0);
    EXPECT_DOUBLE_EQ(cloud_share(cv::Mat::zeros(64, 64, CV_32FC1)), 0.0);
}

// The cumulus above on seed 1, whose sun starts covered and comes out at 25 s: the input's sun is
// the dim one behind the cloud, so once the cloud moves off the clear sun must come back (it stayed
// at 0.35 of the truth's illuminance when only the input's own sun was put back).
TEST(SunTransmittance, SunComingOutOfACloudShinesAsTheClearSun) {
    const ProceduralSkyParams p = test::frozen_cumulus(1);
    ProceduralSky truth(p);
    ASSERT_LT(truth.sun_transmittance(0), 0.1);
    ASSERT_GT(truth.sun_transmittance(40), 0.95);
    const int n = 128;
    CloudMotion motion;
    motion.wind = Wind{p.layers[0].wind_from_deg, p.layers[0].wind_speed_mps, p.layers[0].altitude_m};
    SkyTimeline timeline(truth.render(0, n), make_network_step_model("advect", motion), 10);
    for (double t = 0; t <= 60 + 1e-9; t += 5) {
        const SkyImage moved = timeline.sky_at(t);
        if (t < 30) continue;  // the cloud's edge at the sun
        const double ratio = horizontal_illuminance(moved) / horizontal_illuminance(truth.render(t, n));
        EXPECT_NEAR(ratio, 1.0, 0.15) << "t " << t << " s";
    }
}

// A stored timeline keeps the cloud opacity the model measured (the sun's weight comes from it):
// the skies of the loaded timeline are those of the one that computed them, the sun dimmed alike.
TEST(SunTransmittance, StoredTimelineDimsTheSunAsTheComputedOne) {
    const double dt = 10;
    const std::optional<ProceduralSkyParams> crossing = cloud_crossing_the_sun(120, dt);
    ASSERT_TRUE(crossing);
    ProceduralSky truth(*crossing);
    const SkyImage input = truth.render(0, 64);
    CloudMotion motion;
    const CloudLayer& layer = crossing->layers[0];
    motion.wind = Wind{layer.wind_from_deg, layer.wind_speed_mps, layer.altitude_m};
    const std::string dir = ::testing::TempDir() + "/dynsky_stored_sun_timeline";
    fs::remove_all(dir);
    SkyTimeline computed(input, make_network_step_model("advect", motion), dt);
    computed.save(dir, 12, "settings");
    SkyTimeline loaded = SkyTimeline::load(dir);
    double least = 1;
    for (double t : {0.0, 45.0, 85.0, 90.0, 95.0, 100.0, 105.0, 120.0}) {
        SkyImage a = computed.sky_at(t), b = loaded.sky_at(t);
        EXPECT_TRUE(a.rgb == b.rgb) << "t = " << t;
        EXPECT_EQ(computed.last_sun_weight(), loaded.last_sun_weight()) << "t = " << t;
        least = std::min(least, computed.last_sun_weight());
    }
    EXPECT_LT(least, 0.1) << "the cloud must cover the sun, or the test says nothing";
    fs::remove_all(dir);
}

// The imager's own mask (indexed PNG read as colours: white opaque, grey thin, blue clear) says
// whether the sun is covered: the cloud share (thin or opaque) of a ring 6-15 degrees around the
// computed sun above one half. Nearer the sun the imager marks the glare on its mirror as cloud
// (seen on clear frames), so the ring starts beyond it.
bool imager_says_covered(const std::string& mask_png, const PhotoGeometry& g, const Vec3d& sun, int* labelled) {
    cv::Mat m = cv::imread(mask_png, cv::IMREAD_COLOR);
    if (m.empty()) return false;
    double cloud = 0;
    int count = 0;
    for (int y = 0; y < m.rows; ++y)
        for (int x = 0; x < m.cols; ++x) {
            Vec3d w;
            if (!g.unproject(x, y, &w)) continue;
            double a = std::acos(std::clamp(w.normalized().dot(sun), -1.0, 1.0)) * 180 / kPiD;
            if (a < 6 || a > 15) continue;
            cv::Vec3b c = m.at<cv::Vec3b>(y, x);  // BGR
            if (c[0] > 240 && c[1] > 240 && c[2] > 240) cloud += 1, ++count;
            else if (std::abs(c[0] - 192) < 8 && std::abs(c[1] - 192) < 8 && std::abs(c[2] - 192) < 8)
                cloud += 1, ++count;
            else if (c[0] > 240 && c[1] < 16 && c[2] < 16) ++count;
        }
    *labelled = count;
    return count > 0 && cloud / count > 0.5;
}

// Imported as users import (no mask files beside the photos: issue 11's case; the imager's masks
// serve only as the truth), scored by balanced accuracy too: 60 of the 75 frames are covered, so
// always answering "covered" scores 80 % agreement but a balanced accuracy of 50 %. The thresholds
// were chosen on these frames (docs/animation.md): an in-sample figure.
TEST(SunTransmittance, AgreesWithTheImagersMasksOnTheArmDay) {
    const fs::path folder = fs::path(default_shared_dir()) / "skies" / "arm_tsi_sgp_20170524";
    if (!fs::exists(folder / "frames.csv")) GTEST_SKIP() << folder << " is absent";
    PhotoSequence seq = photo_sequence_from_folder(folder.string(), "arm-tsi");
    int agree = 0, total = 0, covered = 0, covered_right = 0, clear_right = 0;
    // Every 4th frame; every 8th under DYNSKY_TEST_SMALL (the sanitizer run), half the imports.
    const size_t every = test::run_size<size_t>(4, 8);
    for (size_t k = 0; k < seq.photos.size(); k += every) {
        const std::string& photo = seq.photos[k];
        std::string stamp = fs::path(photo).stem().string().substr(std::string("tsi_sgpC1_").size());
        fs::path mask = folder / "tsi_cloudmask" / ("tsicldmask_sgpC1_" + stamp + ".png");
        if (!fs::exists(mask)) continue;
        PresetImportPlan plan = plan_preset_import("arm-tsi", photo, 128, "", /*look_for_mask=*/false);
        ImportedPhoto imported = import_photo(photo, plan.params);
        HdrCalibrationReport report;
        SkyImage sky = recover_hdr(imported, hdr_calibration_params(plan), &report);
        int labelled = 0;
        bool truth_covered = imager_says_covered(mask.string(), imported.geometry, report.computed_sun, &labelled);
        if (labelled < 50) continue;
        double t = estimate_sun_transmittance(sky, report.computed_sun);
        bool estimated_covered = t < 0.5;
        agree += estimated_covered == truth_covered, ++total, covered += truth_covered;
        (truth_covered ? covered_right : clear_right) += estimated_covered == truth_covered;
    }
    ASSERT_GT(total, int(160 / every));
    ASSERT_GE(covered, 5) << "both answers must occur, or the test says nothing";
    ASSERT_GE(total - covered, 5) << "both answers must occur, or the test says nothing";
    const double balanced = 0.5 * (double(covered_right) / covered + double(clear_right) / (total - covered));
    std::printf(
        "direct-sun visibility agrees with the imager's masks in %d of %d frames (%.1f %%; %d covered: %d "
        "right; %d clear: %d right; balanced accuracy %.1f %%)\n",
        agree, total, 100.0 * agree / total, covered, covered_right, total - covered, clear_right, 100.0 * balanced);
    EXPECT_GE(double(agree) / total, 0.85);
    EXPECT_GE(balanced, 0.85);
}

}  // namespace
}  // namespace dynsky
