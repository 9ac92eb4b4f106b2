#include "renderer/sky_sampler.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "renderer/builtin_scene.h"
#include "renderer/env_light.h"
#include "renderer/integrator.h"
#include "renderer/sampling.h"
#include "sky/clear_sky.h"
#include "sky/fisheye.h"
#include "tests/renderer/chi_square.h"
#include "tests/test_support.h"
#include "util/color.h"
#include "util/error.h"

namespace dynsky {
namespace {

std::vector<std::string> all_sampler_names() {
    std::vector<std::string> names = sky_sampler_base_names();
    for (const std::string& n : sky_sampler_base_names())
        if (n != "uniform" && n != "cosine") names.push_back(n + "+mis");
    return names;
}

std::shared_ptr<SkyImage> gradient_sky(int n) {
    auto sky = std::make_shared<SkyImage>(n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            Vec2 uv = fisheye::pixel_center_uv(i, j, n);
            if (uv.squaredNorm() > 1) continue;
            Vec3 w = fisheye::direction_from_uv(uv);
            sky->set_pixel(i, j, Color(0.3f, 0.5f, 1.0f) * (0.3f + w.y()));
        }
    return sky;
}

// A sun of the given angular radius and radiance (relative to a sky of about 0.5) splatted into
// the pixel of its centre when it is smaller than a pixel.
std::shared_ptr<SkyImage> sun_sky(int n, const Vec3& sun, float radius_rad, float radiance, bool give_direction) {
    auto sky = gradient_sky(n);
    Vec2 uv;
    fisheye::uv_from_direction(sun, &uv);
    int ci = std::clamp(int((uv.x() + 1) / 2 * n), 0, n - 1), cj = std::clamp(int((uv.y() + 1) / 2 * n), 0, n - 1);
    double sun_sr = 2 * kPiD * (1 - std::cos(radius_rad));
    double pixel_sr = fisheye::pixel_solid_angle(ci, cj, n);
    if (sun_sr < pixel_sr) {
        sky->set_pixel(ci, cj, Color::Constant(float(radiance * sun_sr / pixel_sr)));
    } else {
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                Vec2 c = fisheye::pixel_center_uv(i, j, n);
                if (c.squaredNorm() <= 1 && fisheye::direction_from_uv(c).dot(sun) >= std::cos(radius_rad))
                    sky->set_pixel(i, j, Color::Constant(radiance));
            }
    }
    if (give_direction) sky->sun_direction = sun;
    return sky;
}

// The Mobotix all-sky photograph (sRGB-decoded, cropped to its image circle), if ../shared exists.
std::shared_ptr<SkyImage> photo_sky(int n) {
    cv::Mat img = cv::imread(test::shared_path("skies/mobotix_sophia_20200812_morning/images/2020-08-12_10_00.jpg"),
                             cv::IMREAD_COLOR);
    if (img.empty()) return nullptr;
    int side = std::min(img.rows, 940);
    cv::Mat small;
    cv::resize(img(cv::Rect((img.cols - side) / 2, (img.rows - side) / 2, side, side)), small, cv::Size(n, n), 0, 0,
               cv::INTER_AREA);
    auto sky = std::make_shared<SkyImage>(n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            cv::Vec3b c = small.at<cv::Vec3b>(j, i);
            sky->set_pixel(i, j,
                           Color(srgb_to_linear(c[2] / 255.f), srgb_to_linear(c[1] / 255.f),
                                 srgb_to_linear(c[0] / 255.f)));
        }
    clear_outside_disc(sky.get());
    return sky;
}

struct NamedSky {
    std::string name;
    std::shared_ptr<SkyImage> sky;
};

// The failure cases of the issue, at 64 x 64 (small enough to test every sampler on each).
std::vector<NamedSky> failure_skies() {
    const int n = 64;
    std::vector<NamedSky> skies;
    Vec3 sun = fisheye::direction_from_angles(0.7, 2.0).cast<float>();
    skies.push_back({"subtexel_sun", sun_sky(n, sun, 0.0046f, 1e5f, false)});
    skies.push_back({"sun_1e6", sun_sky(n, sun, 0.03f, 1e6f, true)});
    skies.push_back({"horizon_sun",
                     sun_sky(n, fisheye::direction_from_angles(1.53, 1.0).cast<float>(), 0.03f, 1e4f, true)});
    auto single = std::make_shared<SkyImage>(n);
    single->set_pixel(20, 41, Color(3, 2, 1));
    skies.push_back({"single_pixel", single});
    auto bad = gradient_sky(n);
    bad->set_pixel(30, 30, Color(std::numeric_limits<float>::quiet_NaN(), 1, 1));
    bad->set_pixel(31, 30, Color(std::numeric_limits<float>::infinity(), 1, 1));
    bad->set_pixel(32, 30, Color(-5, 1, 1));
    skies.push_back({"nan_inf_negative", bad});
    // The rim: only pixels whose centre is within a pixel of the horizon are lit.
    auto rim = std::make_shared<SkyImage>(n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            float r = fisheye::pixel_center_uv(i, j, n).norm();
            if (r <= 1 && r > 1 - 2.0f / n) rim->set_pixel(i, j, Color(1, 1, 1));
        }
    skies.push_back({"horizon_rim", rim});
    return skies;
}

// Integral of the light's pdf over pixel (i, j) (p_w J over uv) with s x s points; *jumps tells
// whether the pdf jumps inside it (the disc's rim, the sun cone's edge).
double pixel_mass(const EnvLight& light, int i, int j, int n, int s, bool* jumps) {
    const double cell = 2.0 / (double(n) * s);
    double sum = 0, lo = 1e30, hi = 0;
    for (int b = 0; b < s; ++b)
        for (int a = 0; a < s; ++a) {
            Vec2 uv(float(-1 + (i * s + a + 0.5) * cell), float(-1 + (j * s + b + 0.5) * cell));
            double p = 0;
            if (uv.squaredNorm() <= 1)
                p = double(light.pdf(fisheye::direction_from_uv(uv))) * EnvLight::jacobian_from_r2(uv.squaredNorm());
            sum += p * cell * cell;
            lo = std::min(lo, p), hi = std::max(hi, p);
        }
    if (jumps) *jumps = hi > 1.5 * lo || (i == 0 || j == 0 || i == n - 1 || j == n - 1);
    return sum;
}

// Histogram of light samples in uv blocks plus a "no sample" bin, against expected counts from
// integrating the light's own pdf: 8 x 8 points per pixel, 64 x 64 in and beside pixels where the
// pdf jumps (an edge can clip a neighbour's corner between the coarse points).
void check_chi_square(const EnvLight& light, int block, int samples, const std::string& what) {
    const int n = light.sky().resolution, bins = n / block;
    std::vector<double> observed(size_t(bins * bins + 1), 0), expected(size_t(bins * bins + 1), 0);
    std::vector<double> coarse(size_t(n) * n);
    std::vector<char> jumps(size_t(n) * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            bool jump;
            coarse[size_t(j) * n + i] = pixel_mass(light, i, j, n, 8, &jump);
            jumps[size_t(j) * n + i] = jump;
        }
    double mass = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            bool near_jump = false;
            for (int b = std::max(0, j - 1); b <= std::min(n - 1, j + 1); ++b)
                for (int a = std::max(0, i - 1); a <= std::min(n - 1, i + 1); ++a)
                    near_jump |= jumps[size_t(b) * n + a] != 0;
            double p = near_jump ? pixel_mass(light, i, j, n, 64, nullptr) : coarse[size_t(j) * n + i];
            expected[size_t((j / block) * bins + i / block)] += samples * p;
            mass += p;
        }
    expected[size_t(bins * bins)] = samples * std::max(0.0, 1 - mass);
    Rng rng(7, 3);
    for (int k = 0; k < samples; ++k) {
        EnvLightSample ls;
        float uc = rng.uniform();
        Vec2 u = rng.uniform2();
        if (!light.sample(uc, u, &ls) || ls.wi.y() < 0) {
            observed[size_t(bins * bins)] += 1;
            continue;
        }
        ASSERT_EQ(ls.pdf, light.pdf(ls.wi)) << what;
        ASSERT_TRUE(std::isfinite(ls.radiance.sum())) << what;
        ASSERT_TRUE((ls.radiance == light.radiance(ls.wi)).all()) << what;
        Vec2 uv;
        fisheye::uv_from_direction(ls.wi, &uv);
        int i = std::clamp(int((uv.x() + 1) / 2 * n), 0, n - 1), j = std::clamp(int((uv.y() + 1) / 2 * n), 0, n - 1);
        observed[size_t((j / block) * bins + i / block)] += 1;
    }
    // The quadrature misses about 0.1% of a cone barely wider than a pixel, which would dominate
    // the "no sample" bin: test the rejection rate by itself (within 0.5%), and the shape of the
    // accepted samples by chi-square, expected counts scaled to the accepted total.
    double rejected = observed.back();
    EXPECT_NEAR(rejected / samples, std::max(0.0, 1 - mass), 5e-3) << what;
    observed.pop_back(), expected.pop_back();
    double accepted_expected = 0;
    for (double e : expected) accepted_expected += e;
    if (!(accepted_expected > 0)) return;
    for (double& e : expected) e *= (samples - rejected) / accepted_expected;
    auto r = test::chi_square_test(observed, expected);
    EXPECT_GT(r.p_value, 1e-4) << what << ": " << r.summary();
}

TEST(SkySampler, NamesRoundTripAndBadNamesAreRejected) {
    for (const std::string& name : all_sampler_names()) EXPECT_EQ(sky_sampler_name(parse_sky_sampler(name)), name);
    EXPECT_THROW(parse_sky_sampler("sun+uniform"), Error);
    EXPECT_THROW(parse_sky_sampler("walker"), Error);
}

TEST(SkySampler, EverySamplerMatchesItsPdfOnARealSkyChiSquare) {
    DYNSKY_REQUIRE_SHARED();
    auto sky = photo_sky(64);
    ASSERT_TRUE(sky);
    for (const std::string& name : all_sampler_names()) {
        EnvLight light(sky, 0.0f, parse_sky_sampler(name));
        check_chi_square(light, 4, 200000, name);
    }
}

TEST(SkySampler, EverySamplerMatchesItsPdfOnTheFailureSkiesChiSquare) {
    for (const NamedSky& s : failure_skies())
        for (const std::string& name : all_sampler_names()) {
            EnvLight light(s.sky, 0.0f, parse_sky_sampler(name));
            check_chi_square(light, 8, 100000, s.name + " / " + name);
        }
}

TEST(SkySampler, PdfsIntegrateToOne) {
    auto sky = sun_sky(128, fisheye::direction_from_angles(0.5, 1.0).cast<float>(), 0.02f, 1e4f, true);
    for (const std::string& name : all_sampler_names()) {
        EnvLight light(sky, 0.0f, parse_sky_sampler(name));
        // Over the upper hemisphere by uv quadrature (p_w J du dv); the light's sky part is 1.
        const int m = 1024;
        double sum = 0;
        for (int j = 0; j < m; ++j)
            for (int i = 0; i < m; ++i) {
                Vec2 uv(-1 + (i + 0.5f) * 2.0f / m, -1 + (j + 0.5f) * 2.0f / m);
                if (uv.squaredNorm() > 1) continue;
                sum += double(light.pdf(fisheye::direction_from_uv(uv))) *
                       EnvLight::jacobian_from_r2(uv.squaredNorm()) * 4.0 / (double(m) * m);
            }
        // Pixel-based samplers lose the part of rim pixels beyond the horizon (< 1% at 128 px).
        EXPECT_NEAR(sum, 1.0, 0.01) << name;
    }
}

TEST(SkySampler, SunSplitFindsTheSunWithAndWithoutItsDirection) {
    Vec3 sun = fisheye::direction_from_angles(0.8, 3.0).cast<float>();
    for (bool given : {true, false}) {
        auto sky = sun_sky(256, sun, 0.0047f, 1e6f, given);
        EnvLight light(sky, 0.0f, parse_sky_sampler("sun+alias"));
        EXPECT_GT(light.sampler().sun_probability(), 0.9f) << given;  // a 1e6 sun holds nearly all power
        EXPECT_GT(light.pdf(sun), 100.0f);
    }
    EnvLight overcast(gradient_sky(128), 0.0f, parse_sky_sampler("sun+alias"));
    EXPECT_EQ(overcast.sampler().sun_probability(), 0.0f);
}

TEST(SkySampler, AllBlackSkyGivesNoNaNs) {
    auto black = std::make_shared<SkyImage>(32);
    for (const std::string& name : all_sampler_names()) {
        EnvLight light(black, 0.3f, parse_sky_sampler(name));
        Rng rng(1, 1);
        for (int k = 0; k < 1000; ++k) {
            EnvLightSample s;
            if (light.sample(rng.uniform(), rng.uniform2(), &s)) {
                EXPECT_TRUE(std::isfinite(s.pdf)) << name;
                EXPECT_EQ(s.radiance.sum(), 0.0f) << name;
            }
        }
        EXPECT_TRUE(std::isfinite(light.pdf(Vec3(0, 1, 0)))) << name;
    }
}

TEST(SkySampler, NaNInfAndNegativePixelsAreTreatedAsBlack) {
    auto sky = gradient_sky(32);
    sky->set_pixel(10, 10, Color(std::numeric_limits<float>::quiet_NaN(), 1, 1));
    sky->set_pixel(11, 10, Color(1, std::numeric_limits<float>::infinity(), 1));
    sky->set_pixel(12, 10, Color(1, 1, -3));
    for (const std::string& name : all_sampler_names()) {
        EnvLight light(sky, 0.3f, parse_sky_sampler(name));
        EXPECT_EQ(light.bad_pixel_count(), 3u);
        EXPECT_TRUE(std::isfinite(light.sky_irradiance().sum()));
        for (int i = 10; i <= 12; ++i) {
            Vec3 w = fisheye::direction_from_uv(fisheye::pixel_center_uv(i, 10, 32));
            EXPECT_TRUE(std::isfinite(light.radiance(w).sum())) << name;
            EXPECT_GE(light.radiance(w).minCoeff(), 0.0f) << name;
            EXPECT_TRUE(std::isfinite(light.pdf(w))) << name;
        }
    }
}

TEST(SkySampler, MovingBrightnessIsRebuiltNeverStale) {
    Vec3 a = fisheye::direction_from_angles(0.4, 1.0).cast<float>(),
         b = fisheye::direction_from_angles(1.1, 4.0).cast<float>();
    auto sky_a = sun_sky(64, a, 0.05f, 1e3f, false), sky_b = sun_sky(64, b, 0.05f, 1e3f, false);
    for (const std::string& name : all_sampler_names()) {
        if (name == "uniform" || name == "cosine") continue;
        EnvLight light(sky_a, 0.0f, parse_sky_sampler(name));
        EXPECT_GT(light.pdf(a), 10 * light.pdf(b)) << name;
        light.set_sky(sky_b);
        EXPECT_GT(light.pdf(b), 10 * light.pdf(a)) << name;
    }
}

// Every sampler's estimate of the horizontal irradiance (light sampling only, no MIS: the "+mis"
// variants are excluded) agrees with the pixel sum within 4 standard errors.
TEST(SkySampler, EstimatesOfIrradianceAgreeWithThePixelSum) {
    auto sky = sun_sky(128, fisheye::direction_from_angles(0.6, 2.5).cast<float>(), 0.02f, 300.0f, true);
    double exact = 0;
    for (int j = 0; j < 128; ++j)
        for (int i = 0; i < 128; ++i) {
            Vec2 c = fisheye::pixel_center_uv(i, j, 128);
            if (c.squaredNorm() > 1) continue;
            exact += luminance(sky->pixel(i, j)) * fisheye::direction_from_uv(c).y() *
                     fisheye::pixel_solid_angle(i, j, 128);
        }
    for (const std::string& name : sky_sampler_base_names()) {
        EnvLight light(sky, 0.0f, parse_sky_sampler(name));
        Rng rng(11, 2);
        const int m = 400000;
        double sum = 0, sum2 = 0;
        for (int k = 0; k < m; ++k) {
            EnvLightSample s;
            double v = 0;
            if (light.sample(rng.uniform(), rng.uniform2(), &s) && s.wi.y() > 0)
                v = luminance(s.radiance) * s.wi.y() / s.pdf;
            sum += v, sum2 += v * v;
        }
        double mean = sum / m, se = std::sqrt(std::max(0.0, sum2 / m - mean * mean) / m);
        // The rim pixels' parts beyond the horizon are not sampled by the pixel-based samplers but
        // count in the pixel sum: allow that (grazing, cos ~ 0) difference of 0.2%.
        EXPECT_NEAR(mean, exact, 4 * se + 2e-3 * exact) << name;
    }
}

// All samplers, under MIS in the path tracer, converge to the same image: every pixel mean
// within 5 standard errors of the CDF's, on a small plaza render.
TEST(SkySampler, AllSamplersConvergeToTheSameImage) {
    Scene scene = make_builtin_scene();
    Accel accel(scene);
    auto sky = sun_sky(128, fisheye::direction_from_angles(0.7, 2.0).cast<float>(), 0.02f, 500.0f, true);
    RenderSettings rs;
    rs.width = 16, rs.height = 12, rs.spp = 64, rs.quiet = true, rs.compute_variance = true, rs.max_depth = 3;
    Camera cam = frame_bounds_camera(scene.world_bounds(), 4.0f / 3);
    EnvLight ref_light(sky, 0.3f, parse_sky_sampler("cdf"));
    RenderResult ref = PathIntegrator(accel, ref_light, rs).render(cam);
    for (const std::string name :
         {"uniform", "cosine", "alias+mis", "mip+mis", "sun+alias+mis", "sun+mip", "sun+cdf+mis"}) {
        EnvLight light(sky, 0.3f, parse_sky_sampler(name));
        RenderSettings s2 = rs;
        s2.seed = 99;
        RenderResult r = PathIntegrator(accel, light, s2).render(cam);
        int outliers = 0, total = 0;
        for (size_t k = 0; k < r.color.pixels.size(); ++k) {
            double d = r.color.pixels[k] - ref.color.pixels[k];
            double se = std::sqrt(double(r.variance.pixels[k]) + ref.variance.pixels[k]);
            outliers += std::abs(d) > 5 * se + 1e-6;
            ++total;
        }
        EXPECT_LE(outliers, total / 100 + 1) << name;
    }
}

}  // namespace
}  // namespace dynsky
