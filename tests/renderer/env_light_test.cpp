#include "renderer/env_light.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "renderer/sampling.h"
#include "sky/fisheye.h"
#include "tests/renderer/chi_square.h"
#include "tests/test_support.h"
#include "util/color.h"

namespace dynsky {
namespace {

// A real sky: the Mobotix all-sky photograph's image circle (about 940 px across, centred),
// cropped square, resized and sRGB-decoded. Not an exact lens mapping, but real radiance structure.
std::shared_ptr<SkyImage> real_photo_sky(int n) {
    std::string path = test::shared_path("skies/mobotix_sophia_20200812_morning/images/2020-08-12_10_00.jpg");
    cv::Mat img = cv::imread(path, cv::IMREAD_COLOR);
    if (img.empty()) return nullptr;
    int side = std::min(img.rows, 940);
    cv::Rect roi((img.cols - side) / 2, (img.rows - side) / 2, side, side);
    cv::Mat small;
    cv::resize(img(roi), small, cv::Size(n, n), 0, 0, cv::INTER_AREA);
    auto sky = std::make_shared<SkyImage>(n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            cv::Vec3b bgr = small.at<cv::Vec3b>(j, i);
            sky->set_pixel(i, j,
                           Color(srgb_to_linear(bgr[2] / 255.f), srgb_to_linear(bgr[1] / 255.f),
                                 srgb_to_linear(bgr[0] / 255.f)));
        }
    clear_outside_disc(sky.get());
    return sky;
}

// Blue-ish sky with a sun of the true angular size (0.533 deg) at a given direction.
std::shared_ptr<SkyImage> tiny_sun_sky(int n, const Vec3d& sun, double sun_radiance) {
    auto sky = std::make_shared<SkyImage>(n);
    double cos_radius = std::cos(0.2665 * kPiD / 180);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            Vec2 uv = fisheye::pixel_center_uv(i, j, n);
            if (uv.squaredNorm() > 1) continue;
            Vec3d w = fisheye::direction_from_uv(uv.x(), uv.y());
            Color c = Color(0.3f, 0.5f, 1.0f) * float(0.5 + 0.5 * w.y());
            sky->set_pixel(i, j, c);
        }
    // The sun covers about 1.5 pixels at 512: put its radiance into the pixel holding its centre.
    double u, v;
    fisheye::uv_from_direction(sun, &u, &v);
    int i = int((u + 1) / 2 * n), j = int((v + 1) / 2 * n);
    double pixel_sr = fisheye::pixel_solid_angle(i, j, n);
    double sun_sr = 2 * kPiD * (1 - cos_radius);
    sky->set_pixel(i, j, Color::Constant(float(sun_radiance * sun_sr / pixel_sr)));
    sky->sun_direction = sun.cast<float>();
    return sky;
}

// Fraction of pixel (i, j)'s area inside the unit disc.
double inside_fraction(int i, int j, int n) {
    Vec2 c = fisheye::pixel_center_uv(i, j, n);
    double half = 1.0 / n;
    double far = std::hypot(std::abs(c.x()) + half, std::abs(c.y()) + half);
    if (far <= 1) return 1;
    const int s = 32;
    int inside = 0;
    for (int a = 0; a < s; ++a)
        for (int b = 0; b < s; ++b) {
            double u = c.x() - half + 2 * half * (a + 0.5) / s, v = c.y() - half + 2 * half * (b + 0.5) / s;
            inside += u * u + v * v <= 1;
        }
    return double(inside) / (s * s);
}

// Histogram of light samples in uv blocks of `block` pixels, plus ground and rejected bins,
// against expected counts computed exactly from the distribution.
void check_sampler_chi_square(const EnvLight& light, int block, int samples) {
    const int n = light.sky().resolution, bins = n / block;
    std::vector<double> observed(bins * bins + 2, 0), expected(bins * bins + 2, 0);
    const Distribution2D& d = light.distribution();
    double ps = light.sky_probability();
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            double p = ps * d.cell_pdf(i, j) / (double(n) * n);
            if (p == 0) continue;
            double f = inside_fraction(i, j, n);
            expected[(j / block) * bins + i / block] += samples * p * f;
            expected[bins * bins + 1] += samples * p * (1 - f);
        }
    expected[bins * bins] = samples * (1 - ps);
    Rng rng(5, 9);
    for (int k = 0; k < samples; ++k) {
        EnvLightSample s;
        float uc = rng.uniform();
        Vec2 u = rng.uniform2();
        if (!light.sample(uc, u, &s)) {
            observed[bins * bins + 1] += 1;
            continue;
        }
        ASSERT_NEAR(s.wi.norm(), 1.0f, 1e-4f);
        ASSERT_GT(s.pdf, 0.0f);
        // The pdf a sample reports is the pdf the light reports for that direction.
        ASSERT_NEAR(s.pdf, light.pdf(s.wi), 2e-3f * s.pdf);
        if (s.wi.y() < 0) {
            observed[bins * bins] += 1;
            continue;
        }
        Vec2 uv;
        ASSERT_TRUE(fisheye::uv_from_direction(s.wi, &uv));
        int i = std::clamp(int((uv.x() + 1) / 2 * n), 0, n - 1), j = std::clamp(int((uv.y() + 1) / 2 * n), 0, n - 1);
        observed[(j / block) * bins + i / block] += 1;
    }
    auto r = test::chi_square_test(observed, expected);
    EXPECT_GT(r.p_value, 1e-3) << r.summary();
}

// The light's pdf integrated over the sphere on m x m stratified uniform directions
// (E[pdf / (1 / 4pi)] = 1 for a normalised density).
double pdf_integral_over_sphere(const EnvLight& light, int m) {
    double sum = 0;
    for (int a = 0; a < m; ++a)
        for (int b = 0; b < m; ++b) {
            double z = 1 - 2 * (a + 0.5) / m, phi = 2 * kPiD * (b + 0.5) / m, r = std::sqrt(1 - z * z);
            sum += light.pdf(Vec3(float(r * std::cos(phi)), float(z), float(r * std::sin(phi)))) * 4 * kPiD;
        }
    return sum / (double(m) * m);
}

TEST(EnvLight, SamplerMatchesItsDensityOnARealSkyChiSquare) {
    DYNSKY_REQUIRE_SHARED();
    auto sky = real_photo_sky(128);
    ASSERT_TRUE(sky);
    EnvLight light(sky, 0.3f, parse_sky_sampler("cdf"));  // expected counts come from its 2D CDF
    check_sampler_chi_square(light, 4, 500000);
}

TEST(EnvLight, SamplerMatchesItsDensityOnATinySunSkyChiSquare) {
    auto sky = tiny_sun_sky(512, fisheye::direction_from_angles(0.9, 2.2), 1.6e5);
    EnvLight light(sky, 0.2f, parse_sky_sampler("cdf"));
    check_sampler_chi_square(light, 16, 500000);
}

TEST(EnvLight, PdfIntegratesToOneOverTheSphere) {
    auto sky = tiny_sun_sky(128, fisheye::direction_from_angles(0.5, 1.0), 1e3);
    EnvLight light(sky, 0.3f);
    EXPECT_NEAR(pdf_integral_over_sphere(light, 1000), 1.0, 1e-2);
}

TEST(EnvLight, EstimatedIntegralOfRadianceMatchesPixelSum) {
    DYNSKY_REQUIRE_SHARED();
    auto sky = real_photo_sky(96);
    ASSERT_TRUE(sky);
    EnvLight light(sky, 0.0f);  // black ground: all samples on the sky
    double exact = 0;
    for (int j = 0; j < 96; ++j)
        for (int i = 0; i < 96; ++i)
            if (sky->in_disc(i, j)) exact += luminance(sky->pixel(i, j)) * fisheye::pixel_solid_angle(i, j, 96);
    Rng rng(2, 3);
    const int n = 200000;
    double sum = 0, sum2 = 0;
    for (int k = 0; k < n; ++k) {
        EnvLightSample s;
        double v = 0;
        if (light.sample(rng.uniform(), rng.uniform2(), &s)) v = luminance(s.radiance) / s.pdf;
        sum += v, sum2 += v * v;
    }
    double mean = sum / n, se = std::sqrt((sum2 / n - mean * mean) / n);
    // The continuous estimator sees sin(theta)/theta varying inside each pixel; the pixel sum uses
    // the centre, so allow that quadrature difference (1e-3) beside the Monte Carlo error.
    EXPECT_NEAR(mean, exact, 4 * se + 1e-3 * exact) << "se " << se;
}

// A lat-long's ground (a fisheye of the lower hemisphere, mirrored) is importance sampled: light
// samples below the horizon report the pdf that pdf() gives, the radiance that radiance() gives,
// the pdf integrates to 1, E[L / p] is the exact integral, and a bright patch on the ground gets
// most of the ground's samples.
TEST(EnvLight, GroundImageIsImportanceSampled) {
    const int n = 64;
    auto sky = tiny_sun_sky(n, fisheye::direction_from_angles(0.5, 1.0), 1e3);
    auto ground = std::make_shared<SkyImage>(n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            if (ground->in_disc(i, j)) ground->set_pixel(i, j, Color(0.1f, 0.1f, 0.1f));
    for (int j = 40; j < 46; ++j)  // a bright patch off the nadir
        for (int i = 20; i < 26; ++i) ground->set_pixel(i, j, Color(50, 40, 30));
    for (const char* method : {"cdf+mis", "cdf", "alias"}) {
        SCOPED_TRACE(method);
        EnvLight light(sky, 0.3f, parse_sky_sampler(method));
        light.set_ground_image(ground);
        double exact = 0, patch_solid_angle = 0;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                double a = fisheye::pixel_solid_angle(i, j, n);
                if (sky->in_disc(i, j)) exact += luminance(sky->pixel(i, j)) * a;
                if (ground->in_disc(i, j)) exact += luminance(ground->pixel(i, j)) * a;
                if (i >= 20 && i < 26 && j >= 40 && j < 46) patch_solid_angle += a;
            }
        Rng rng(5, 7);
        const int m = 200000;
        double sum = 0, sum2 = 0;
        int below = 0, in_patch = 0;
        for (int k = 0; k < m; ++k) {
            EnvLightSample s;
            double v = 0;
            if (light.sample(rng.uniform(), rng.uniform2(), &s)) {
                v = luminance(s.radiance) / s.pdf;
                if (s.wi.y() < 0) {
                    ++below;
                    ASSERT_EQ(s.pdf, light.pdf(s.wi));
                    ASSERT_TRUE((s.radiance == light.radiance(s.wi)).all());
                    in_patch += luminance(s.radiance) > 10;
                }
            }
            sum += v, sum2 += v * v;
        }
        double mean = sum / m, se = std::sqrt(std::max(0.0, sum2 / m - mean * mean) / m);
        // Light samples alone are unbiased without MIS compensation (with it, BSDF sampling covers
        // the rest). The parts of rim pixels below the horizon (0.3 % here) are left to BSDF
        // sampling, as the sky's are.
        if (std::string(method).find("mis") == std::string::npos) {
            EXPECT_NEAR(mean, exact, 4 * se + 5e-3 * exact);
        }
        ASSERT_GT(below, 1000);
        // Uniform sampling would put patch_solid_angle / 2 pi of them there (about 1.3 %).
        EXPECT_LT(patch_solid_angle / (2 * kPiD), 0.02);
        EXPECT_GT(double(in_patch) / below, 0.5);
        EXPECT_NEAR(pdf_integral_over_sphere(light, 600), 1.0, 2e-2);
    }
}

TEST(EnvLight, UniformSkyLightsAWhiteGroundToTheSameRadiance) {
    auto sky = std::make_shared<SkyImage>(256);
    for (int j = 0; j < 256; ++j)
        for (int i = 0; i < 256; ++i)
            if (sky->in_disc(i, j)) sky->set_pixel(i, j, Color::Ones());
    EnvLight light(sky, 1.0f);
    // E = integral of L cos over the hemisphere = pi, so a white Lambertian ground reflects L = 1.
    EXPECT_NEAR(light.sky_irradiance()[0], kPi, 3e-3f * kPi);
    EXPECT_NEAR(light.ground_radiance()[1], 1.0f, 3e-3f);
    EXPECT_NEAR(light.sky_probability(), 0.5f, 3e-3f);
    EXPECT_EQ(light.radiance(Vec3(0, -1, 0))[0], light.ground_radiance()[0]);
    // Near the rim (above the horizon) the lookup stays on the sky, never black.
    Vec3 grazing = Vec3(1, 1e-4f, 0).normalized();
    EXPECT_EQ(light.radiance(grazing)[2], 1.0f);
}

TEST(EnvLight, RebuildFollowsTheNewSky) {
    auto a = tiny_sun_sky(64, fisheye::direction_from_angles(0.3, 0.5), 1e5);
    auto b = tiny_sun_sky(64, fisheye::direction_from_angles(1.2, 4.0), 1e5);
    EnvLight light(a, 0.0f);
    light.set_sky(b);
    // Most samples now land near b's sun, none near a's.
    Rng rng(4, 4);
    int near_b = 0, near_a = 0;
    for (int k = 0; k < 2000; ++k) {
        EnvLightSample s;
        if (!light.sample(rng.uniform(), rng.uniform2(), &s)) continue;
        // Within 11 degrees: the sun split samples a cone with a margin around the sun's pixels.
        near_b += s.wi.dot(b->sun_direction.value()) > 0.98f;
        near_a += s.wi.dot(a->sun_direction.value()) > 0.999f;
    }
    EXPECT_GT(near_b, 1000);  // the sun holds most of the power; the dim sky the rest
    EXPECT_EQ(near_a, 0);
}

// The build time (recorded per frame by animate and render) is measured: zero before any sky,
// positive and finite after a build.
TEST(EnvLight, BuildTimeIsMeasured) {
    EnvLight light(0.3f);
    EXPECT_EQ(light.last_build_seconds(), 0.0);
    light.set_sky(tiny_sun_sky(64, fisheye::direction_from_angles(0.3, 0.5), 1e5));
    EXPECT_GT(light.last_build_seconds(), 0.0);
    EXPECT_TRUE(std::isfinite(light.last_build_seconds()));
}

// The per-frame pass has a fast path for clean rows and a checked one for rows holding NaN,
// infinite, negative (or -0) values: a sky with such rows must light exactly like the same sky
// with those channels set to 0, at sizes with and without a SIMD tail.
TEST(EnvLight, RowsWithBadPixelsMatchTheCleanedSky) {
    for (int n : {64, 37}) {
        auto bad = std::make_shared<SkyImage>(n);
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i)
                if (bad->in_disc(i, j)) bad->set_pixel(i, j, Color(0.2f + 0.01f * i, 0.5f, 0.3f + 0.02f * j));
        auto clean = std::make_shared<SkyImage>(*bad);
        const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
        bad->set_pixel(n / 2, 5, Color(nan, 1, 1));
        bad->set_pixel(n / 2, 9, Color(1, -inf, 1));
        bad->set_pixel(n / 2 + 1, 12, Color(1, 1, -2));
        bad->set_pixel(0, 0, Color(inf, 0, 0));  // outside the disc: still counted, still harmless
        // Each bad channel reads as 0; the pixel's other channels stay.
        clean->set_pixel(n / 2, 5, Color(0, 1, 1)), clean->set_pixel(n / 2, 9, Color(1, 0, 1));
        clean->set_pixel(n / 2 + 1, 12, Color(1, 1, 0)), clean->set_pixel(0, 0, Color::Zero());
        bad->set_pixel(n / 2, 20, Color(-0.0f, 0.5f, 0.5f));  // -0 is zero: not bad, but takes the checked path
        clean->set_pixel(n / 2, 20, Color(0.0f, 0.5f, 0.5f));
        for (const char* sampler : {"cdf+mis", "alias", "mip+mis"}) {
            EnvLight a(bad, 0.3f, parse_sky_sampler(sampler)), b(clean, 0.3f, parse_sky_sampler(sampler));
            EXPECT_EQ(a.bad_pixel_count(), 4u) << n << " " << sampler;
            EXPECT_EQ(b.bad_pixel_count(), 0u);
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(a.sky_irradiance()[c], b.sky_irradiance()[c], 1e-5f * b.sky_irradiance()[c]) << n;
            EXPECT_NEAR(a.sky_probability(), b.sky_probability(), 1e-6f);
            Rng rng(3, 7);
            for (int k = 0; k < 200; ++k) {
                Vec3 w = sample_uniform_hemisphere(rng.uniform2());
                w = Vec3(w.x(), w.z(), w.y());
                // Sums run in another order; compensation (+mis) magnifies that near its threshold.
                EXPECT_NEAR(a.pdf(w), b.pdf(w), 2e-4f * b.pdf(w) + 1e-6f) << n << " " << sampler;
            }
        }
    }
}

// Irradiance from the pass (fixed-point solid angles, float sums) against a direct double sum of
// L cos(theta) over each pixel's exact solid angle.
TEST(EnvLight, IrradianceMatchesADirectSum) {
    for (int n : {256, 61}) {
        auto sky = std::make_shared<SkyImage>(n);
        double direct[3] = {0, 0, 0};
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                if (!sky->in_disc(i, j)) continue;
                Vec3 d = fisheye::direction_from_uv(fisheye::pixel_center_uv(i, j, n));
                Color c(1 + d.x(), 2 + d.z(), 0.5f + 3 * d.y() * d.y());
                sky->set_pixel(i, j, c);
                // dw = J du dv with J from the closed form at the pixel centre (du = 2/n)
                double r = fisheye::pixel_center_uv(i, j, n).norm(), theta = r * kPiD / 2;
                double jac = r > 0 ? (kPiD * kPiD / 4) * std::sin(theta) / theta : kPiD * kPiD / 4;
                for (int k = 0; k < 3; ++k) direct[k] += c[k] * std::cos(theta) * jac * (4.0 / (double(n) * n));
            }
        EnvLight light(sky, 0.3f);
        for (int k = 0; k < 3; ++k)
            EXPECT_NEAR(light.sky_irradiance()[k], direct[k], 2e-4 * direct[k]) << n << " " << k;
    }
}

TEST(EnvLight, JacobianPolynomialMatchesClosedForm) {
    for (double r = 0; r <= 1.0; r += 0.01) {
        double theta = r * kPiD / 2;
        EXPECT_NEAR(EnvLight::jacobian_from_r2(float(r * r)), fisheye::solid_angle_jacobian(theta), 2e-6);
        EXPECT_NEAR(EnvLight::cos_theta_from_r2(float(r * r)), std::cos(theta), 2e-6);
    }
}

}  // namespace
}  // namespace dynsky
