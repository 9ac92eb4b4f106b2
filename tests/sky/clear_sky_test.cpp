#include "sky/clear_sky.h"

#include <gtest/gtest.h>

#include <cmath>

#include "sky/fisheye.h"
#include "sky/sun_position.h"
#include "util/error.h"

namespace dynsky {
namespace {

constexpr double kDeg = kPiD / 180.0;
constexpr double kLumensPerWatt = 683.0;  // luminance (cd m^-2) = 683 Y, Y in W m^-2 sr^-1

Vec3d sun_at(double elevation_deg, double azimuth_deg) {
    return fisheye::direction_from_angles((90 - elevation_deg) * kDeg, azimuth_deg * kDeg);
}

struct Integrals {
    Eigen::Array3d hemisphere = Eigen::Array3d::Zero();  // sum L * omega
    Eigen::Array3d horizontal = Eigen::Array3d::Zero();  // sum L * cos(theta) * omega
};
Integrals integrate(const SkyImage& sky) {
    Integrals out;
    const int n = sky.resolution;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            double omega = fisheye::pixel_solid_angle(i, j, n);
            if (omega <= 0) continue;
            Vec2 uv = fisheye::pixel_center_uv(i, j, n);
            double cos_theta = fisheye::direction_from_uv(double(uv.x()), double(uv.y())).y();
            out.hemisphere += sky.pixel(i, j).cast<double>() * omega;
            out.horizontal += sky.pixel(i, j).cast<double>() * omega * cos_theta;
        }
    return out;
}

double lum(const Eigen::Array3d& c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

// With the disc. (Without it the brightest sky is on the horizon below the sun: the model's
// circumsolar peak is broad, e.g. Y 24.7 at the sun vs 36 at the horizon for a sun at 35 deg.)
TEST(ClearSky, BrightestPixelIsTheSun) {
    const double positions[][2] = {{65, 30}, {35, 200}, {12, 100}, {82, 300}, {4, 45}, {50, 271}};
    for (int n : {256, 512}) {
        for (const auto& p : positions) {
            for (bool disc : {true}) {
                ClearSkyParams params;
                params.sun_direction = sun_at(p[0], p[1]);
                params.turbidity = 3;
                params.sun_disc = disc;
                SkyImage sky = make_clear_sky(params, n);
                int bi = -1, bj = -1;
                float best = -1;
                for (int j = 0; j < n; ++j)
                    for (int i = 0; i < n; ++i)
                        if (sky.in_disc(i, j) && luminance(sky.pixel(i, j)) > best)
                            best = luminance(sky.pixel(i, j)), bi = i, bj = j;
                double u, v;
                ASSERT_TRUE(fisheye::uv_from_direction(params.sun_direction, &u, &v));
                double si = (u + 1) / 2 * n - 0.5, sj = (v + 1) / 2 * n - 0.5;  // continuous pixel coordinates
                EXPECT_LE(std::abs(bi - si), 1.0) << "N " << n << " sun " << p[0] << "/" << p[1] << " disc " << disc;
                EXPECT_LE(std::abs(bj - sj), 1.0) << "N " << n << " sun " << p[0] << "/" << p[1] << " disc " << disc;
            }
        }
    }
}

// The splatted disc carries exactly the model's direct irradiance, at every resolution; also a sun
// whole above the horizon but within a rim pixel whose centre lies outside the disc (those hold no
// sky): 0.65 degrees up kept 10 % of its light at 64 px, 0.3 degrees none.
TEST(ClearSky, SunDiscConservesIrradiance) {
    struct Case {
        double elevation, azimuth;
        int n;
    };
    std::vector<Case> cases = {{40, 135, 64}, {40, 135, 256}, {40, 135, 512}};
    for (double elevation : {0.65, 0.3, 1.5})
        for (int n : {64, 128, 256}) cases.push_back({elevation, 300, n});
    for (const Case& c : cases) {
        ClearSkyParams params;
        params.sun_direction = sun_at(c.elevation, c.azimuth);
        SkyImage with_sun = make_clear_sky(params, c.n);
        params.sun_disc = false;
        SkyImage sky_only = make_clear_sky(params, c.n);
        Eigen::Array3d disc = integrate(with_sun).hemisphere - integrate(sky_only).hemisphere;
        Color expected = ClearSkyModel(params).model().solar_irradiance_rgb();
        for (int k = 0; k < 3; ++k)
            EXPECT_NEAR(disc[k], expected[k], 1e-3 * expected[k])
                << "elevation " << c.elevation << " N " << c.n << " channel " << k;
    }
}

// A disc several pixels wide (N of about 1400 and more) is limb-darkened smoothly: splatted, its
// pixels caught unequal numbers of ring samples and varied 37 % within 0.1 degree of the centre
// at 4096 px (a physical-units audit). It still carries the model's irradiance exactly, and a
// disc crossing the horizon keeps only what is above it.
TEST(ClearSky, AResolvedSunDiscIsSmoothAndConservesIrradiance) {
    for (int n : {2048, 4096}) {
        ClearSkyParams params;
        params.sun_direction = sun_at(29.6, 142.7);
        const ClearSkyModel model(params);
        Eigen::Array3d total = Eigen::Array3d::Zero();
        std::vector<double> centre;
        const Vec3d s = model.sun_direction();
        model.splat_sun_disc(n, [&](int i, int j, const Color& c) {
            total += (c.cast<double>() * fisheye::pixel_solid_angle(i, j, n)).array();
            const Vec3d w = fisheye::direction_from_pixel(i, j, n);
            if (std::atan2(w.cross(s).norm(), w.dot(s)) < 0.1 * kPiD / 180) centre.push_back(c.mean());
        });
        const Color expected = model.model().solar_irradiance_rgb();
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(total[k], expected[k], 1e-4 * expected[k]) << "N " << n;
        ASSERT_GE(centre.size(), 2u) << "N " << n;
        const auto [lo, hi] = std::minmax_element(centre.begin(), centre.end());
        EXPECT_LT(*hi / *lo - 1, 0.05) << "N " << n << ": the centre's pixels differ (limb darkening: 3 %)";
    }
    ClearSkyParams low;
    low.sun_direction = sun_at(0.0, 250);  // half the disc below the horizon
    const ClearSkyModel half(low);
    double got = 0;
    half.splat_sun_disc(4096, [&](int i, int j, const Color& c) {
        got += c.mean() * fisheye::pixel_solid_angle(i, j, 4096);
    });
    const double whole = half.model().solar_irradiance_rgb().mean();
    EXPECT_GT(got, 0.3 * whole);
    EXPECT_LT(got, 0.7 * whole);
}

// Orders of magnitude of a clear day with a high sun (turbidity 2.5): diffuse horizontal
// illuminance ~10-20 klux, direct normal illuminance ~80-110 klux (~900 W m^-2 broadband at a
// beam luminous efficacy of ~100 lm/W), sun luminance ~1.6e9 cd m^-2, zenith a few kcd m^-2.
TEST(ClearSky, PlausibleIlluminance) {
    ClearSkyParams params;
    params.sun_direction = sun_at(60, 180);
    params.turbidity = 2.5;
    params.sun_disc = false;
    SkyImage sky = make_clear_sky(params, 512);
    double diffuse_lux = kLumensPerWatt * lum(integrate(sky).horizontal);
    ClearSkyModel model(params);
    params.sun_disc = true;
    ClearSkyModel with_sun(params);
    double direct_normal_lux = kLumensPerWatt * luminance(with_sun.sun_irradiance());
    double sun_luminance = kLumensPerWatt * luminance(with_sun.model().solar_radiance_rgb(0.0));
    double zenith_luminance = kLumensPerWatt * luminance(model.sky_radiance(Vec3d(0, 1, 0)));
    std::printf(
        "sun at 60 deg, T 2.5: diffuse horizontal %.0f lux, direct normal %.0f lux (~%.0f W/m^2 at 100 lm/W), "
        "global horizontal %.0f lux, sun centre %.3g cd/m^2, zenith %.0f cd/m^2\n",
        diffuse_lux, direct_normal_lux, direct_normal_lux / 100, diffuse_lux + direct_normal_lux * std::sin(60 * kDeg),
        sun_luminance, zenith_luminance);
    EXPECT_GT(diffuse_lux, 8e3);
    EXPECT_LT(diffuse_lux, 30e3);
    EXPECT_GT(direct_normal_lux, 70e3);
    EXPECT_LT(direct_normal_lux, 120e3);
    EXPECT_GT(sun_luminance, 0.8e9);
    EXPECT_LT(sun_luminance, 2.5e9);
    EXPECT_GT(zenith_luminance, 1e3);
    EXPECT_LT(zenith_luminance, 1.5e4);
}

TEST(ClearSky, ImageHoldsTheModelAtPixelCentres) {
    ClearSkyParams params;
    params.sun_direction = sun_at(25, 250);
    params.turbidity = 4.2;
    params.ground_albedo = 0.6;
    params.sun_disc = false;
    const int n = 128;
    SkyImage sky = make_clear_sky(params, n);
    ASSERT_TRUE(sky.sun_direction.has_value());
    EXPECT_NEAR((sky.sun_direction->cast<double>() - params.sun_direction).norm(), 0.0, 1e-6);
    EXPECT_NE(sky.source.find("hosek-wilkie"), std::string::npos);
    // Reference: the model evaluated straight from (theta, gamma).
    HosekWilkieSky hw(4.2, 0.6, 25 * kDeg);
    for (int j = 0; j < n; j += 7)
        for (int i = 0; i < n; i += 5) {
            Vec2 uv = fisheye::pixel_center_uv(i, j, n);
            if (uv.squaredNorm() > 1) {
                EXPECT_EQ(sky.pixel(i, j).matrix().norm(), 0.0f);
                continue;
            }
            Vec3d w = fisheye::direction_from_uv(double(uv.x()), double(uv.y()));
            double theta = std::acos(w.y()), gamma = std::acos(std::clamp(w.dot(params.sun_direction), -1.0, 1.0));
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(sky.pixel(i, j)[c], std::max(0.0, hw.sky_radiance(c, theta, gamma)),
                            2e-5 * std::abs(hw.sky_radiance(c, theta, gamma)) + 1e-6);
            Color one = clear_sky_radiance(params, w);
            EXPECT_NEAR(one[1], sky.pixel(i, j)[1], 1e-5 * one[1]);
        }
}

TEST(ClearSky, SymmetricAboutTheSunsVertical) {
    // Sun due north: the image must be mirror-symmetric in u (east <-> west).
    ClearSkyParams params;
    params.sun_direction = sun_at(30, 0);
    const int n = 96;
    SkyImage sky = make_clear_sky(params, n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n / 2; ++i)
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(sky.pixel(i, j)[c], sky.pixel(n - 1 - i, j)[c], 1e-4 * std::abs(sky.pixel(i, j)[c]) + 1e-6);
}

TEST(ClearSky, PointLookupIncludesTheSunDisc) {
    ClearSkyParams params;
    params.sun_direction = sun_at(45, 90);
    Color at_sun = clear_sky_radiance(params, params.sun_direction);
    Color beside = clear_sky_radiance(params, sun_at(45, 90.6));  // 0.42 deg of azimuth = 0.3 deg on the sky
    EXPECT_GT(luminance(at_sun), 1e5f * luminance(beside));
    ClearSkyModel model(params);
    EXPECT_EQ(luminance(model.sun_radiance(sun_at(45, 90.6))), 0.0f);
    EXPECT_EQ(luminance(clear_sky_radiance(params, Vec3d(0, -1, 0))), 0.0f);  // below the horizon: no sky
}

TEST(ClearSky, SunBelowHorizonIsClampedWithAWarning) {
    ClearSkyParams params;
    params.sun_direction = sun_at(-3, 250);
    testing::internal::CaptureStderr();
    SkyImage low = make_clear_sky(params, 64);
    std::string err = testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("below the horizon"), std::string::npos) << err;
    // The sky with the sun on the horizon (the disc, 3 deg down, is hidden) dimmed for twilight.
    ClearSkyParams horizon = params;
    horizon.sun_direction = Vec3d(params.sun_direction.x(), 0.0, params.sun_direction.z()).normalized();
    horizon.sun_disc = false;
    SkyImage ref = make_clear_sky(horizon, 64);
    const float dim = float(twilight_factor(3.0));
    for (size_t k = 0; k < low.rgb.size(); ++k)
        EXPECT_NEAR(low.rgb[k], dim * ref.rgb[k], 1e-5 * std::abs(dim * ref.rgb[k]) + 1e-9);
    EXPECT_LT(low.sun_direction->y(), 0.0f);  // the true sun is recorded
    EXPECT_NO_THROW(validate_sky(low, "low"));
}

// Through twilight the sky darkens as a clear evening does (horizontal illuminance, US Naval
// Observatory's table: sunset ~10^3 lx, civil dusk (6 deg) a few lx, nautical (12 deg) ~10^-2, night
// ~10^-3), continuously: it stayed at the sunset's 2400 lx all night.
TEST(ClearSky, TwilightDarkensToANightSky) {
    auto illuminance = [](double elevation_deg) {
        ClearSkyParams p;
        p.sun_direction = sun_at(elevation_deg, 250);
        const SkyImage s = make_clear_sky(p, 64, false);
        double e = 0;
        for (int j = 0; j < 64; ++j)
            for (int i = 0; i < 64; ++i)
                if (const double omega = fisheye::pixel_solid_angle(i, j, 64); omega > 0)
                    e += luminance(s.pixel(i, j)) * omega * fisheye::direction_from_pixel(i, j, 64).y();
        return 683 * e;
    };
    const double sunset = illuminance(-0.3);
    EXPECT_GT(sunset, 300);
    EXPECT_NEAR(illuminance(-0.31) / sunset, 1.0, 0.01);  // no jump
    EXPECT_GT(illuminance(-6), 0.5);
    EXPECT_LT(illuminance(-6), 20);
    EXPECT_GT(illuminance(-12), 1e-3);
    EXPECT_LT(illuminance(-12), 0.1);
    EXPECT_LT(illuminance(-40), 1e-2);
    EXPECT_EQ(illuminance(-40), illuminance(-18));
    EXPECT_DOUBLE_EQ(twilight_factor(0), 1.0);
}

TEST(ClearSky, RejectsBadParameters) {
    ClearSkyParams params;
    params.sun_direction = sun_at(45, 0);
    params.turbidity = 0.9;
    EXPECT_THROW(make_clear_sky(params, 64), Error);
    params.turbidity = 3;
    params.ground_albedo = 1.5;
    EXPECT_THROW(make_clear_sky(params, 64), Error);
    params.ground_albedo = 0.3;
    params.sun_direction = Vec3d::Zero();
    EXPECT_THROW(make_clear_sky(params, 64), Error);
    params.sun_direction = Vec3d(0, NAN, 0);
    EXPECT_THROW(make_clear_sky(params, 64), Error);
    params.sun_direction = sun_at(45, 0);
    EXPECT_THROW(make_clear_sky(params, 0), Error);
}

TEST(ClearSky, FromTheSunPositionOfADate) {
    // Noon at the June solstice in Paris: a high southern sun; the image's sun direction is the
    // sun position's direction.
    SunPosition sun = compute_sun_position(parse_utc_time("2026-06-21T11:50:00Z"), GeoLocation{48.8566, 2.3522, 35});
    ClearSkyParams params;
    params.sun_direction = sun.direction();
    SkyImage sky = make_clear_sky(params, 64);
    EXPECT_NEAR(sky.sun_direction->y(), std::sin(sun.elevation_deg() * kDeg), 1e-6);
    EXPECT_GT(sky.sun_direction->z(), 0.3f);  // south is +Z
    EXPECT_LT(std::abs(sky.sun_direction->x()), 0.05f);
    EXPECT_NO_THROW(validate_sky(sky, "paris"));
}

}  // namespace
}  // namespace dynsky
