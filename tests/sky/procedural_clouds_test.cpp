#include "sky/procedural_clouds.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <opencv2/imgproc.hpp>

#include "sky/clear_sky.h"
#include "sky/fisheye.h"
#include "tests/sky/frozen_cumulus.h"
#include "tests/test_support.h"
#include "util/error.h"

namespace dynsky {
namespace {

ProceduralSkyParams base_params(uint64_t seed = 7, double coverage = 0.5) {
    ProceduralSkyParams p;
    p.seed = seed;
    p.coverage = coverage;
    p.clear_sky.sun_direction = fisheye::direction_from_angles(50.0 * kPiD / 180.0, 200.0 * kPiD / 180.0);
    return p;
}

cv::Mat luminance_mat(const SkyImage& sky) {
    cv::Mat m(sky.resolution, sky.resolution, CV_32F);
    for (int y = 0; y < sky.resolution; ++y)
        for (int x = 0; x < sky.resolution; ++x) m.at<float>(y, x) = luminance(sky.pixel(x, y));
    return m;
}

double cloud_fraction(const Image& flow, double min_opacity = 0.5) {
    int cloudy = 0, sky = 0;
    for (int y = 0; y < flow.height; ++y)
        for (int x = 0; x < flow.width; ++x) {
            if (fisheye::pixel_center_uv(x, y, flow.width).squaredNorm() > 1.0f) continue;
            ++sky;
            cloudy += flow.at(x, y, 2) > min_opacity;
        }
    return double(cloudy) / sky;
}

// The paper's use of a flow field: warp frame t along it and compare with frame t + dt.
// Returns {MSE of the warped frame, MSE of the unwarped frame} against frame t + dt, in luminance,
// over cloud pixels inside the disc.
std::pair<double, double> warp_errors(uint64_t seed) {
    ProceduralSkyParams p = base_params(seed, 0.5);
    p.clear_sky.sun_disc = false;  // a disc warped into cloud pixels would swamp the comparison
    p.layers[0].wind_speed_mps = 15.0;
    p.layers[0].wind_from_deg = 300.0;
    const int n = 128;
    const double dt = 20.0, t = 100.0;
    ProceduralSky sky(p);
    Image flow, next_flow;
    SkyImage a = sky.render(t, n, &flow, dt);
    SkyImage b = sky.render(t + dt, n, &next_flow, dt);

    // Backward map from the forward flow: the cloud at y came from about y - flow(y).
    cv::Mat map_x(n, n, CV_32F), map_y(n, n, CV_32F);
    double max_displacement = 0;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            map_x.at<float>(y, x) = x - flow.at(x, y, 0);
            map_y.at<float>(y, x) = y - flow.at(x, y, 1);
            max_displacement = std::max(max_displacement,
                                        std::hypot(double(flow.at(x, y, 0)), double(flow.at(x, y, 1))));
        }
    EXPECT_GT(max_displacement, 3.0) << "the test needs visible motion";
    cv::Mat la = luminance_mat(a), lb = luminance_mat(b), warped;
    cv::remap(la, warped, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);

    double err_warped = 0, err_still = 0;
    int count = 0;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            Vec2 uv = fisheye::pixel_center_uv(x, y, n);
            if (uv.norm() > 0.85f) continue;  // keep the warp's source inside the disc
            if (flow.at(x, y, 2) < 0.05f && next_flow.at(x, y, 2) < 0.05f) continue;  // cloud pixels only
            double target = lb.at<float>(y, x);
            err_warped += std::pow(warped.at<float>(y, x) - target, 2);
            err_still += std::pow(la.at<float>(y, x) - target, 2);
            ++count;
        }
    EXPECT_GT(count, 500);
    return {err_warped / count, err_still / count};
}

TEST(ProceduralClouds, WarpingByGroundTruthFlowPredictsNextFrame) {
    for (uint64_t seed : {11, 12, 13}) {
        auto [err_warped, err_still] = warp_errors(seed);
        EXPECT_LT(err_warped * 2.0, err_still)
            << "seed " << seed << ": warped MSE " << err_warped << ", unwarped " << err_still;
    }
}

TEST(ProceduralClouds, SameSeedGivesBitwiseIdenticalFramesOnAnyThreadCount) {
    ProceduralSkyParams p = base_params(3, 0.45);
    p.layers.push_back(cirrus_layer());
    Image flow_many, flow_one;
    SkyImage many = render_procedural_sky(p, 42.0, 96, &flow_many, 5.0);
    SkyImage one;
    {
        tbb::global_control serial(tbb::global_control::max_allowed_parallelism, 1);
        one = render_procedural_sky(p, 42.0, 96, &flow_one, 5.0);
    }
    EXPECT_TRUE(many.rgb == one.rgb);
    EXPECT_TRUE(flow_many.pixels == flow_one.pixels);

    SkyImage other = render_procedural_sky(base_params(4, 0.45), 42.0, 96);
    SkyImage same_seed_single = render_procedural_sky(base_params(3, 0.45), 42.0, 96);
    EXPECT_FALSE(other.rgb == same_seed_single.rgb) << "different seeds must give different skies";
    // Seeds far apart (the 64-bit range, not only the low byte) differ too.
    EXPECT_FALSE(render_procedural_sky(base_params(3 + (1ull << 40), 0.45), 42.0, 96).rgb == same_seed_single.rgb);
}

// A pixel's opacity is the mean over its footprint: at the resolutions animate uses (1024 px)
// the field passes from clear to opaque within a metre or two, and opacity taken at the pixel's
// centre gave the clouds stair-stepped edges. The opacity of a 256 px sky near its zenith (where
// its footprint gets the window, as a 1024 px one does out to 70 degrees) against the mean of
// 4 x 4 pixels of the same sky at 1024 px, on the pixels where that mean is between 0.05 and
// 0.95 (edges): taken at the centres they were off by 0.17 on average, now 0.11.
TEST(ProceduralClouds, EdgeOpacityIsThePixelsMean) {
    ProceduralSkyParams p = base_params(11, 0.5);
    ProceduralSky sky(p);
    const int n = 256, f = 4;
    Image coarse, fine;
    sky.render(0.0, n, &coarse, 10.0);
    sky.render(0.0, n * f, &fine, 10.0);
    double error = 0;
    long edges = 0;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            if (fisheye::pixel_center_uv(x, y, n).norm() > 0.4) continue;  // near the zenith
            double mean = 0;
            for (int j = 0; j < f; ++j)
                for (int i = 0; i < f; ++i) mean += fine.at(x * f + i, y * f + j, 2);
            mean /= f * f;
            if (mean < 0.05 || mean > 0.95) continue;
            error += std::abs(coarse.at(x, y, 2) - mean), ++edges;
        }
    ASSERT_GT(edges, 200);
    error /= edges;
    std::printf("edge pixels %ld: mean |opacity - 4x4 mean at 4x the resolution| %.3f\n", edges, error);
    EXPECT_LT(error, 0.13);
}

TEST(ProceduralClouds, CoverageZeroIsExactlyTheClearSky) {
    ProceduralSkyParams p = base_params(5, 0.0);
    p.layers.push_back(cirrus_layer());
    SkyImage sky = render_procedural_sky(p, 10.0, 64);
    SkyImage clear = make_clear_sky(p.clear_sky, 64);
    EXPECT_TRUE(sky.rgb == clear.rgb);
    EXPECT_DOUBLE_EQ(procedural_sun_transmittance(p, 10.0), 1.0);
}

TEST(ProceduralClouds, CoverageIncreasesCloudFractionMonotonically) {
    double previous = -1.0;
    Image flow;
    for (double c : {0.05, 0.2, 0.4, 0.6, 0.8, 1.0}) {
        render_procedural_sky(base_params(9, c), 0.0, 64, &flow, 1.0);
        double fraction = cloud_fraction(flow);
        EXPECT_GT(fraction, previous) << "coverage " << c;
        previous = fraction;
    }
    EXPECT_GT(cloud_fraction(flow, 0.0), 0.99) << "full coverage is overcast";
}

TEST(ProceduralClouds, CoverageIsTheFractionOfTheLayerWithCloud) {
    // Points spread over a square of the layer 100 km (cumulus) or 300 km (cirrus, whose
    // streaks come in patches about 20 km wide) across.
    for (double c : {0.1, 0.25, 0.6, 0.9}) {
        ProceduralSkyParams p = base_params(17, c);
        p.layers.push_back(cirrus_layer());
        ProceduralSky sky(p);
        for (size_t layer = 0; layer < 2; ++layer) {
            int cloudy = 0;
            const int n = 100;
            const double spacing = layer == 0 ? 1000.0 : 3000.0;
            for (int a = 0; a < n; ++a)
                for (int b = 0; b < n; ++b)
                    cloudy += sky.layer_density(layer, (a - n / 2) * spacing + 0.37, (b - n / 2) * spacing + 0.61,
                                                30.0) > 0.0;
            EXPECT_NEAR(double(cloudy) / (n * n), c, 0.04) << "coverage " << c << ", layer " << layer;
        }
    }
}

TEST(ProceduralClouds, FlowAtZenithMatchesGeometryAndHorizonIsSlower) {
    ProceduralSkyParams p = base_params(1, 0.5);
    CloudLayer& l = p.layers[0];
    l.wind_speed_mps = 10.0;
    l.wind_from_deg = 270.0;  // from the west: clouds drift east, which is image left
    const int n = 128;
    const double dt = 30.0;
    Image flow;
    render_procedural_sky(p, 0.0, n, &flow, dt);
    // The four pixels around the zenith: displacement angle atan(w dt / h), pi / N radians per pixel.
    double expected = std::atan(l.wind_speed_mps * dt / l.altitude_m) / (kPiD / n);
    for (int y : {n / 2 - 1, n / 2})
        for (int x : {n / 2 - 1, n / 2}) {
            EXPECT_NEAR(flow.at(x, y, 0), -expected, 0.05 * expected);
            EXPECT_NEAR(flow.at(x, y, 1), 0.0, 0.05 * expected);
        }
    // Towards the horizon (east and north of the zenith) the same wind moves clouds fewer pixels.
    double zenith = std::hypot(flow.at(n / 2, n / 2, 0), flow.at(n / 2, n / 2, 1));
    for (auto [x, y] : {std::pair{10, n / 2}, std::pair{n / 2, 10}, std::pair{n - 11, n / 2}}) {
        double speed = std::hypot(flow.at(x, y, 0), flow.at(x, y, 1));
        EXPECT_LT(speed, 0.5 * zenith) << "pixel " << x << "," << y;
        EXPECT_GT(speed, 0.0);
    }
    // Nothing moves outside the disc.
    EXPECT_EQ(flow.at(0, 0, 0), 0.0f);
    EXPECT_EQ(flow.at(0, 0, 2), 0.0f);
}

TEST(ProceduralClouds, FrozenShapesWithoutWindDoNotChange) {
    ProceduralSkyParams p = base_params(2, 0.5);
    p.layers[0].wind_speed_mps = 0.0;
    p.layers[0].evolution_time_s = 0.0;
    ProceduralSky sky(p);
    EXPECT_TRUE(sky.render(0.0, 48).rgb == sky.render(500.0, 48).rgb);
    p.layers[0].evolution_time_s = 600.0;  // now the shapes evolve
    ProceduralSky evolving(p);
    EXPECT_FALSE(evolving.render(0.0, 48).rgb == evolving.render(500.0, 48).rgb);
}

std::shared_ptr<Image> full_mask() {
    auto mask = std::make_shared<Image>(8, 8, 1);
    std::fill(mask->pixels.begin(), mask->pixels.end(), 1.0f);
    return mask;
}

TEST(ProceduralClouds, SunIsDimmedWhenACloudCoversIt) {
    ProceduralSkyParams p = base_params(1, 0.5);
    p.clear_sky.sun_direction = fisheye::direction_from_angles(20.0 * kPiD / 180.0, 100.0 * kPiD / 180.0);
    p.layers[0].mask = full_mask();  // a cloud over the whole middle of the sky
    p.layers[0].mask_detail = 0.0;
    const int n = 128;
    SkyImage cloudy = render_procedural_sky(p, 0.0, n);
    SkyImage clear = make_clear_sky(p.clear_sky, n);
    double u, v;
    ASSERT_TRUE(fisheye::uv_from_direction(p.clear_sky.sun_direction.normalized(), &u, &v));
    int i = int((u + 1) * 0.5 * n), j = int((v + 1) * 0.5 * n);
    float clear_sun = luminance(clear.pixel(i, j)), cloudy_sun = luminance(cloudy.pixel(i, j));
    EXPECT_GT(clear_sun, 1e4f) << "the clear sky's sun disc should be in this pixel";
    EXPECT_LT(cloudy_sun, 1e-2f * clear_sun);
    // What is left is the cloud's own light: no brighter than the cloud a few pixels away.
    EXPECT_LT(cloudy_sun, 2.0f * luminance(cloudy.pixel(i + 4, j)));
    EXPECT_LT(procedural_sun_transmittance(p, 0.0), 1e-3);

    // Without the cloud, the sun shines through.
    p.layers[0].mask.reset();
    p.coverage = 0.0;
    EXPECT_DOUBLE_EQ(procedural_sun_transmittance(p, 0.0), 1.0);
}

// The disc is half a degree wide and a 128 px pixel 1.4 degrees: the disc's light in the image is
// dimmed by the cloud on the sun's own line of sight (sun_transmittance), not by the cloud at the
// centre of each pixel it falls in. Taken at the centres, a cumulus edge dimmed the sun 5 s before it
// reached it (seed 7 below, at 10 s: 38 % of the truth's illuminance), and a wisp over a centre a
// degree away blinked it out for one frame (bench/sun_seeds).
TEST(ProceduralClouds, SunDiscIsDimmedByTheCloudOnTheSunsLineOfSight) {
    const ProceduralSkyParams p = test::frozen_cumulus(7);
    ProceduralSkyParams no_disc = p;
    no_disc.clear_sky.sun_disc = false;
    for (int n : {64, 128, 256}) {
        ProceduralSky with(p), without(no_disc);
        const double clear_disc = horizontal_illuminance(make_clear_sky(p.clear_sky, n)) -
                                  horizontal_illuminance(make_clear_sky(no_disc.clear_sky, n));
        ASSERT_GT(clear_disc, 1e4);
        int covered = 0, clear = 0;
        for (double t = 0; t <= 120; t += 2) {
            const double transmittance = with.sun_transmittance(t);
            const double disc = horizontal_illuminance(with.render(t, n)) -
                                horizontal_illuminance(without.render(t, n));
            EXPECT_NEAR(disc, transmittance * clear_disc, 0.01 * clear_disc) << n << " px, t " << t << " s";
            covered += transmittance<0.05, clear += transmittance> 0.95;
        }
        // The cloud's edge crosses the sun within the run, or the test says nothing.
        EXPECT_GT(covered, 3);
        EXPECT_GT(clear, 3);
    }
}

TEST(ProceduralClouds, MaskCloudsAppearWhereTheMaskSaysAndDriftWithTheWind) {
    // A square in the mask's upper-left quadrant: north-east of the zenith, as seen from below.
    auto mask = std::make_shared<Image>(64, 64, 1);
    for (int y = 8; y < 28; ++y)
        for (int x = 8; x < 28; ++x) mask->at(x, y, 0) = 1.0f;
    ProceduralSkyParams p = base_params(1, 0.5);
    CloudLayer& l = p.layers[0];
    l.mask = mask;
    l.mask_detail = 0.0;
    l.wind_speed_mps = 10.0;
    l.wind_from_deg = 270.0;
    const int n = 128;
    const double half = l.altitude_m * std::tan(60.0 * kPiD / 180.0);  // default extent / 2
    for (double t : {0.0, 120.0}) {
        Image flow;
        render_procedural_sky(p, t, n, &flow, 1.0);
        int inside = 0, outside = 0, checked_in = 0, checked_out = 0;
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                Vec2 uv = fisheye::pixel_center_uv(x, y, n);
                if (uv.squaredNorm() > 1.0f) continue;
                Vec3d d = fisheye::direction_from_uv(uv.x(), uv.y());
                Vec3d q = d * (l.altitude_m / d.y());
                q.x() -= 10.0 * t;  // material coordinates: the wind blows east (+x)
                double mx = (-q.x() / half + 1.0) * 32.0, my = (q.z() / half + 1.0) * 32.0;
                bool in_square = mx > 9 && mx < 27 && my > 9 && my < 27;
                bool far_from_square = mx < 6 || mx > 30 || my < 6 || my > 30;
                if (in_square) ++checked_in, inside += flow.at(x, y, 2) > 0.9f;
                if (far_from_square) ++checked_out, outside += flow.at(x, y, 2) > 0.0f;
            }
        ASSERT_GT(checked_in, 20) << "t = " << t;
        EXPECT_EQ(inside, checked_in) << "t = " << t;
        EXPECT_EQ(outside, 0) << "t = " << t;
    }
}

TEST(ProceduralClouds, LoadsGreyAndAlphaMasks) {
    std::string dir = test::temp_dir("procedural_mask");
    Image grey(4, 2, 3);
    grey.at(1, 0, 0) = grey.at(1, 0, 1) = grey.at(1, 0, 2) = 1.0f;
    write_image(dir + "/grey.png", grey);
    Image m = load_cloud_mask(dir + "/grey.png");
    EXPECT_EQ(m.channels, 1);
    EXPECT_FLOAT_EQ(m.at(1, 0, 0), 1.0f);
    EXPECT_FLOAT_EQ(m.at(0, 0, 0), 0.0f);
    Image rgba(4, 2, 4);
    rgba.at(2, 1, 3) = 0.5f;  // density from alpha, whatever the colour
    write_image(dir + "/alpha.exr", rgba);
    Image a = load_cloud_mask(dir + "/alpha.exr");
    EXPECT_FLOAT_EQ(a.at(2, 1, 0), 0.5f);
    EXPECT_FLOAT_EQ(a.at(1, 0, 0), 0.0f);
    Image opaque(4, 2, 4);  // RGBA saved by a paint program: alpha 1 everywhere, grey is the density
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 4; ++x) opaque.at(x, y, 3) = 1.0f;
    opaque.at(3, 1, 0) = opaque.at(3, 1, 1) = opaque.at(3, 1, 2) = 0.75f;
    write_image(dir + "/opaque.exr", opaque);
    Image o = load_cloud_mask(dir + "/opaque.exr");
    EXPECT_FLOAT_EQ(o.at(3, 1, 0), 0.75f);
    EXPECT_FLOAT_EQ(o.at(0, 0, 0), 0.0f);
}

template <typename F>
std::string error_of(F&& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

TEST(ProceduralClouds, BadInputGivesClearErrors) {
    ProceduralSkyParams p = base_params();
    p.coverage = 1.5;
    EXPECT_NE(error_of([&] { render_procedural_sky(p, 0.0, 32); }).find("coverage"), std::string::npos);
    p.coverage = -0.1;
    EXPECT_NE(error_of([&] { ProceduralSky s(p); }).find("coverage"), std::string::npos);
    p = base_params();
    Image flow;
    EXPECT_NE(error_of([&] { render_procedural_sky(p, 0.0, 32, &flow, -1.0); }).find("dt"), std::string::npos);
    EXPECT_NE(error_of([&] { render_procedural_sky(p, 0.0, 32, &flow, 0.0); }).find("dt"), std::string::npos);
    p.layers[0].altitude_m = -5.0;
    EXPECT_NE(error_of([&] { ProceduralSky s(p); }).find("altitude"), std::string::npos);
    std::string missing = "/nonexistent/clouds.png";
    std::string message = error_of([&] { load_cloud_mask(missing); });
    EXPECT_NE(message.find(missing), std::string::npos) << message;
    EXPECT_NE(message.find("no such file"), std::string::npos) << message;
}

}  // namespace
}  // namespace dynsky
