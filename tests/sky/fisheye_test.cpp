#include "sky/fisheye.h"

#include <gtest/gtest.h>

#include <random>

namespace dynsky {
namespace {

TEST(Fisheye, RoundTripDirectionUvDirection) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> U(-1, 1);
    for (int k = 0; k < 100000; ++k) {
        double u = U(rng), v = U(rng);
        if (u * u + v * v > 1) continue;
        Vec3d w = fisheye::direction_from_uv(u, v);
        EXPECT_NEAR(w.norm(), 1.0, 1e-12);
        double u2, v2;
        ASSERT_TRUE(fisheye::uv_from_direction(w, &u2, &v2));
        EXPECT_NEAR(u, u2, 1e-9);
        EXPECT_NEAR(v, v2, 1e-9);
    }
}

TEST(Fisheye, OrientationFollowsConventions) {
    // Zenith at the centre.
    Vec3d zenith = fisheye::direction_from_uv(0.0, 0.0);
    EXPECT_NEAR(zenith.y(), 1.0, 1e-12);
    // North (-Z) horizon at the top (v = -1), east (+X) at the left (u = -1).
    Vec3d north = fisheye::direction_from_uv(0.0, -1.0);
    EXPECT_NEAR(north.z(), -1.0, 1e-9);
    Vec3d east = fisheye::direction_from_uv(-1.0, 0.0);
    EXPECT_NEAR(east.x(), 1.0, 1e-9);
    EXPECT_NEAR(fisheye::azimuth(east), kPiD / 2, 1e-9);
    EXPECT_NEAR(fisheye::azimuth(north), 0.0, 1e-9);
    // Equidistant: r = 0.5 is 45 degrees from the zenith.
    Vec3d w = fisheye::direction_from_uv(0.5, 0.0);
    EXPECT_NEAR(fisheye::zenith_angle(w), kPiD / 4, 1e-12);
    // Below the horizon has no uv.
    double u, v;
    EXPECT_FALSE(fisheye::uv_from_direction(Vec3d(0, -0.1, 1).normalized(), &u, &v));
}

TEST(Fisheye, AnglesRoundTrip) {
    for (double theta = 0.05; theta < kPiD / 2; theta += 0.1)
        for (double phi = 0.0; phi < 2 * kPiD; phi += 0.3) {
            Vec3d w = fisheye::direction_from_angles(theta, phi);
            EXPECT_NEAR(fisheye::zenith_angle(w), theta, 1e-9);
            EXPECT_NEAR(fisheye::azimuth(w), phi, 1e-9);
            double u, v;
            ASSERT_TRUE(fisheye::uv_from_direction(w, &u, &v));
            double r = 2 * theta / kPiD;
            EXPECT_NEAR(u, -r * std::sin(phi), 1e-9);
            EXPECT_NEAR(v, -r * std::cos(phi), 1e-9);
        }
}

TEST(Fisheye, PixelSolidAnglesSumToTwoPi) {
    const int n = 512;
    double total = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) total += fisheye::pixel_solid_angle(i, j, n);
    EXPECT_NEAR(total, 2 * kPiD, 1e-3);
    // Zenith pixel: pi^2 / N^2.
    EXPECT_NEAR(fisheye::pixel_solid_angle(n / 2, n / 2, n), kPiD * kPiD / (n * n), 1e-4 * kPiD * kPiD / (n * n));
}

TEST(Fisheye, DensityConversionIntegratesToOne) {
    // A uniform density over the disc in uv (1/pi) becomes a solid-angle density that
    // integrates to 1 over the hemisphere.
    const int n = 1024;
    double total = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            double dw = fisheye::pixel_solid_angle(i, j, n);
            if (dw == 0) continue;
            Vec2 uv = fisheye::pixel_center_uv(i, j, n);
            double theta = uv.norm() * kPiD / 2;
            total += fisheye::pdf_solid_angle_from_uv(1.0 / kPiD, theta) * dw;
        }
    EXPECT_NEAR(total, 1.0, 2e-3);
}

}  // namespace
}  // namespace dynsky
