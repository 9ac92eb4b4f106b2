#include "sky/latlong.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>

#include "sky/clear_sky.h"
#include "sky/fisheye.h"
#include "tests/test_support.h"
#include "util/error.h"
#include "util/image.h"

namespace dynsky {
namespace {

constexpr double kDeg = kPiD / 180.0;

// A smooth, asymmetric, coloured sky as a function of direction.
Color synthetic(const Vec3d& w) {
    return Color(float(1.0 + 0.5 * w.x() + 0.3 * w.z() + w.y() * w.y()), float(2.0 - 0.4 * w.z() + 0.2 * w.x() * w.y()),
                 float(0.5 + std::exp(-2.0 * (1 - w.y()))));
}
// Its integral over the upper hemisphere: odd terms in x and z vanish; int y^2 = 2 pi / 3;
// int exp(-2 (1 - y)) = 2 pi (1 - e^-2) / 2.
Eigen::Array3d synthetic_integral() {
    return Eigen::Array3d(2 * kPiD + 2 * kPiD / 3, 4 * kPiD, 0.5 * 2 * kPiD + kPiD * (1 - std::exp(-2.0)));
}

SkyImage sky_from_function(int n, Color (*f)(const Vec3d&)) {
    SkyImage sky(n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            Vec2 uv = fisheye::pixel_center_uv(i, j, n);
            if (uv.squaredNorm() <= 1)
                sky.set_pixel(i, j, f(fisheye::direction_from_uv(double(uv.x()), double(uv.y()))));
        }
    return sky;
}

Eigen::Array3d fisheye_integral(const SkyImage& sky) {
    Eigen::Array3d sum = Eigen::Array3d::Zero();
    for (int j = 0; j < sky.resolution; ++j)
        for (int i = 0; i < sky.resolution; ++i)
            sum += sky.pixel(i, j).cast<double>() * fisheye::pixel_solid_angle(i, j, sky.resolution);
    return sum;
}

Eigen::Array3d latlong_upper_integral(const Image& ll) {
    Eigen::Array3d sum = Eigen::Array3d::Zero();
    for (int r = 0; r < ll.height / 2; ++r) {
        double omega = latlong_pixel_solid_angle(r, ll.width, ll.height);
        for (int c = 0; c < ll.width; ++c)
            for (int k = 0; k < 3; ++k) sum[k] += ll.at(c, r, k) * omega;
    }
    return sum;
}

TEST(LatLong, LayoutMatchesBlender) {
    // Named directions: top row zenith, centre column east, u = 0.25 north, 0.75 south, 0 west.
    EXPECT_NEAR((latlong_direction(0.3, 0.0) - Vec3d(0, 1, 0)).norm(), 0.0, 1e-12);
    EXPECT_NEAR((latlong_direction(0.5, 0.5) - Vec3d(1, 0, 0)).norm(), 0.0, 1e-12);    // east +X
    EXPECT_NEAR((latlong_direction(0.25, 0.5) - Vec3d(0, 0, -1)).norm(), 0.0, 1e-12);  // north -Z
    EXPECT_NEAR((latlong_direction(0.75, 0.5) - Vec3d(0, 0, 1)).norm(), 0.0, 1e-12);   // south +Z
    EXPECT_NEAR((latlong_direction(0.0, 0.5) - Vec3d(-1, 0, 0)).norm(), 0.0, 1e-12);   // west -X
    // Cycles' direction_to_equirectangular: u = 0.5 - atan2(y, x) / 2 pi, v = 1 - acos(z) / pi
    // (v up), in Blender's frame after glTF import: (x, y, z)_blender = (x, -z, y)_gltf.
    std::mt19937 rng(3);
    std::normal_distribution<double> g;
    for (int k = 0; k < 1000; ++k) {
        Vec3d w = Vec3d(g(rng), g(rng), g(rng)).normalized();
        double bx = w.x(), by = -w.z(), bz = w.y();
        double bu = 0.5 - std::atan2(by, bx) / (2 * kPiD), bv = 1 - std::acos(bz) / kPiD;
        double u, v;
        latlong_uv(w, &u, &v);
        double du = std::remainder(u - bu, 1.0);
        EXPECT_NEAR(du, 0.0, 1e-9);
        EXPECT_NEAR(v, 1 - bv, 1e-9);
        EXPECT_NEAR((latlong_direction(u, v) - w).norm(), 0.0, 1e-9);
    }
}

TEST(LatLong, PixelSolidAnglesCoverTheSphere) {
    for (int w : {4, 64, 1000}) {
        double sum = 0;
        for (int r = 0; r < w / 2; ++r) sum += w * latlong_pixel_solid_angle(r, w, w / 2);
        EXPECT_NEAR(sum, 4 * kPiD, 1e-9);
    }
}

// Fisheye made from a function, then lat-long: every pixel and every lookup is the function
// within interpolation error; the upper hemisphere's integral is kept.
TEST(LatLong, RoundTripsASyntheticSky) {
    const int n = 256;
    SkyImage sky = sky_from_function(n, synthetic);
    Image ll = sky_to_latlong(sky, 512, Color(0.1f, 0.2f, 0.3f));
    ASSERT_EQ(ll.width, 512);
    ASSERT_EQ(ll.height, 256);
    double worst = 0, worst_rim = 0;
    for (int r = 0; r < ll.height / 2; ++r)
        for (int c = 0; c < ll.width; ++c) {
            Vec3d w = latlong_direction((c + 0.5) / ll.width, (r + 0.5) / ll.height);
            Color f = synthetic(w);
            for (int k = 0; k < 3; ++k) {
                double rel = std::abs(ll.at(c, r, k) - f[k]) / f[k];
                (r >= ll.height / 2 - 2 ? worst_rim : worst) = std::max(r >= ll.height / 2 - 2 ? worst_rim : worst,
                                                                        rel);
            }
        }
    // Bilinear of a smooth function over pixels pi/256 wide: ~1e-4; the two rows at the horizon
    // average over the fisheye's rim, where the disc's edge pixels stand in for the outside.
    EXPECT_LT(worst, 2e-3);
    EXPECT_LT(worst_rim, 5e-3);
    // Lower half: the ground colour.
    for (int r = ll.height / 2; r < ll.height; r += 17)
        for (int c = 0; c < ll.width; c += 13) EXPECT_FLOAT_EQ(ll.at(c, r, 2), 0.3f);
    // Lookups at arbitrary directions above the horizon.
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> U(0, 1);
    for (int k = 0; k < 2000; ++k) {
        double theta = std::acos(U(rng) * 0.98 + 0.02), phi = 2 * kPiD * U(rng);
        Vec3d w = fisheye::direction_from_angles(theta, phi);
        Color got = sample_latlong(ll, w), f = synthetic(w);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], f[c], 3e-3 * f[c]) << theta / kDeg << " " << phi / kDeg;
    }
    // Integrals: analytic, fisheye, lat-long.
    Eigen::Array3d exact = synthetic_integral(), fish = fisheye_integral(sky), lat = latlong_upper_integral(ll);
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(fish[c], exact[c], 2e-3 * exact[c]);
        EXPECT_NEAR(lat[c], fish[c], 2e-3 * fish[c]);
    }
    std::printf("hemisphere integral (G): exact %.5f, fisheye %.5f, lat-long %.5f; worst pixel error %.2g (rim %.2g)\n",
                exact[1], fish[1], lat[1], worst, worst_rim);
}

// A clear sky with its sun (one fisheye pixel of ~1e6): neither missed nor doubled, whether the
// lat-long is coarser, equal or finer than the fisheye.
TEST(LatLong, KeepsTheSunsEnergy) {
    ClearSkyParams params;
    params.sun_direction = fisheye::direction_from_angles(50 * kDeg, 120 * kDeg);
    SkyImage sky = make_clear_sky(params, 256);
    Eigen::Array3d fish = fisheye_integral(sky);
    for (int width : {256, 512, 1024}) {
        Image ll = sky_to_latlong(sky, width);
        Eigen::Array3d lat = latlong_upper_integral(ll);
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(lat[c], fish[c], 0.005 * fish[c]) << "width " << width << " channel " << c;
        std::printf("sky with sun, N 256 -> lat-long %d: integral ratio %.5f (G)\n", width, lat[1] / fish[1]);
        // The brightest lat-long pixel is the sun's.
        int bc = 0, br = 0;
        for (int r = 0; r < ll.height; ++r)
            for (int c = 0; c < ll.width; ++c)
                if (ll.at(c, r, 1) > ll.at(bc, br, 1)) bc = c, br = r;
        double u, v;
        latlong_uv(params.sun_direction, &u, &v);
        EXPECT_LE(std::abs(bc - (u * width - 0.5)), 1.5) << width;
        EXPECT_LE(std::abs(br - (v * width / 2 - 0.5)), 1.5) << width;
    }
}

// The inverse conversion (downloaded HDRIs): a lat-long of a known function back to a fisheye
// matches the function pixel by pixel, keeps the integral of a sky with a sun, and puts the lower
// half, seen from above, in the ground fisheye.
TEST(LatLong, ConvertsBackToTheFisheyeAndTheGround) {
    const int n = 128;
    Image ll(512, 256, 3);
    for (int r = 0; r < ll.height; ++r)
        for (int c = 0; c < ll.width; ++c) {
            Vec3d w = latlong_direction((c + 0.5) / ll.width, (r + 0.5) / ll.height);
            // Below the horizon: a function of the mirrored direction, so the ground fisheye must
            // show it as the sky fisheye shows `synthetic`, scaled by 0.25.
            Color col = w.y() >= 0 ? synthetic(w) : Color(0.25f * synthetic(Vec3d(w.x(), -w.y(), w.z())));
            for (int k = 0; k < 3; ++k) ll.at(c, r, k) = col[k];
        }
    SkyImage sky = latlong_to_fisheye(ll, n), ground = latlong_to_fisheye(ll, n, true);
    SkyImage truth = sky_from_function(n, synthetic);
    double worst = 0, worst_ground = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            Vec2 uv = fisheye::pixel_center_uv(i, j, n);
            if (uv.squaredNorm() > 0.95 * 0.95) continue;  // the horizon rows mix both halves
            for (int k = 0; k < 3; ++k) {
                worst = std::max(worst, double(std::abs(sky.pixel(i, j)[k] - truth.pixel(i, j)[k])));
                worst_ground = std::max(worst_ground,
                                        double(std::abs(ground.pixel(i, j)[k] - 0.25f * truth.pixel(i, j)[k])));
            }
        }
    EXPECT_LT(worst, 0.01);  // values 0.5 .. 3
    EXPECT_LT(worst_ground, 0.0025);
    Eigen::Array3d integral = fisheye_integral(sky), expected = synthetic_integral();
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(integral[k], expected[k], 0.005 * expected[k]);

    // A clear sky with its sun: fisheye -> lat-long -> fisheye keeps the sky's integral.
    ClearSkyParams params;
    params.sun_direction = fisheye::direction_from_angles(50 * kDeg, 120 * kDeg);
    SkyImage clear = make_clear_sky(params, 256);
    SkyImage back = latlong_to_fisheye(sky_to_latlong(clear, 1024), 256);
    Eigen::Array3d a = fisheye_integral(clear), b = fisheye_integral(back);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(b[k], a[k], 0.01 * a[k]);
    std::printf("clear sky N 256 -> lat-long 1024 -> N 256: integral ratio %.5f (G)\n", b[1] / a[1]);

    EXPECT_THROW(latlong_to_fisheye(Image(30, 20, 3), 64), Error);
    Image bad(8, 4, 3);
    bad.at(1, 1, 0) = -1;
    EXPECT_THROW(latlong_environment(bad, "bad.exr"), Error);
    // A huge ground is refused as a huge sky is, named by the file's own pixel (the ground half
    // lights the scene from below: 1e30 there rendered as 1e30).
    for (int y : {1, 3}) {
        Image huge(16, 8, 3);
        std::fill(huge.pixels.begin(), huge.pixels.end(), 1.0f);
        huge.at(5, 2 * y, 1) = 1e30f;
        try {
            latlong_environment(huge, "huge.exr");
            ADD_FAILURE() << "1e30 at row " << 2 * y << " was accepted";
        } catch (const Error& e) {
            const std::string m = e.what();
            EXPECT_NE(m.find("huge.exr"), std::string::npos) << m;
            EXPECT_NE(m.find("pixel (5, " + std::to_string(2 * y) + ")"), std::string::npos) << m;
            EXPECT_NE(m.find(y == 1 ? "sky (upper half)" : "ground (lower half)"), std::string::npos) << m;
        }
    }
}

// A downloaded HDRI's sun keeps its energy in the fisheye it becomes, at the resolution the renderer
// takes (as tall as the file): point samples of the few-pixel sun, 2 x 2 per fisheye pixel, missed
// or doubled up to 1 % of a sunny sky's irradiance (the render of a white plane 45.25 for 45.67).
TEST(LatLong, AnHdrisSunKeepsItsEnergyInTheFisheye) {
    for (const double zenith : {10.0, 50.0, 80.0})
        for (const int width : {512, 1024}) {
            ClearSkyParams params;
            params.sun_direction = fisheye::direction_from_angles(zenith * kDeg, 37 * kDeg);
            const Image ll = sky_to_latlong(make_clear_sky(params, 512), width);
            const Eigen::Array3d expected = latlong_upper_integral(ll);
            const Eigen::Array3d got = fisheye_integral(latlong_to_fisheye(ll, width / 2));
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(got[c] / expected[c], 1.0, 0.002) << "zenith " << zenith << ", width " << width;
        }
}

// A lat-long file's colour is its R, G and B by name, as a fisheye sky's is: a Blender render's
// layers (Denoising.Depth first) were read by position, the depth as red (25 for 0.5), and X Y Z
// passed as R G B; and a file stored turned (Orientation 4: bottom-up, a "+Y" .hdr) is read the
// right way up (its sky and ground were swapped).
TEST(LatLong, FilesAreReadByChannelNameAndOrientation) {
    const std::string dir = test::temp_dir("latlong_channels");
    Image layered(16, 8, 5);
    layered.channel_names = {"Denoising.Depth", "Denoising.Albedo.G", "Image.R", "Image.G", "Image.B"};
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 16; ++x) {
            const float v[5] = {50, 0.8f, 1, 2, 3};
            for (int c = 0; c < 5; ++c) layered.at(x, y, c) = v[c] * (y < 4 ? 1.0f : 0.25f);
        }
    write_image(dir + "/layered.exr", layered);
    std::shared_ptr<SkyImage> ground;
    SkyImage sky = load_sky_or_latlong(dir + "/layered.exr", &ground);
    const Color zenith = sky.pixel(sky.resolution / 2, sky.resolution / 2);
    EXPECT_NEAR(zenith[0], 1.0f, 1e-4f);
    EXPECT_NEAR(zenith[1], 2.0f, 1e-4f);
    EXPECT_NEAR(zenith[2], 3.0f, 1e-4f);
    EXPECT_NEAR(ground->pixel(ground->resolution / 2, ground->resolution / 2)[2], 0.75f, 1e-4f);

    Image xyz = layered;
    xyz.channels = 3, xyz.pixels.resize(16 * 8 * 3), xyz.channel_names = {"X", "Y", "Z"};
    write_image(dir + "/xyz.exr", xyz);
    try {
        load_sky_or_latlong(dir + "/xyz.exr", &ground);
        ADD_FAILURE() << "X Y Z read as colour";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("has no R channel (its channels: X, Y, Z)"), std::string::npos)
            << e.what();
    }

    Image turned(16, 8, 3);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 16; ++x)
            for (int c = 0; c < 3; ++c) turned.at(x, y, c) = y < 4 ? 0.5f : 2.0f;  // stored bottom-up: sky 2
    turned.metadata.numbers["Orientation"] = 4;
    write_image(dir + "/turned.exr", turned);
    sky = load_sky_or_latlong(dir + "/turned.exr", &ground);
    EXPECT_NEAR(sky.pixel(sky.resolution / 2, sky.resolution / 2)[0], 2.0f, 1e-4f);
    EXPECT_NEAR(ground->pixel(ground->resolution / 2, ground->resolution / 2)[0], 0.5f, 1e-4f);
}

// --sky-res with a sky file: the file is taken at N (a fisheye resampled, a lat-long converted at
// N), each keeping its hemisphere's integral; unasked, a lat-long converts at its height, at most the
// limit a moving sky sets (an 8192 x 4096 HDRI made a 4096 px moving sky: 4 GB per step).
TEST(LatLong, SkyFilesAreTakenAtTheResolutionAsked) {
    const std::string dir = test::temp_dir("latlong_asked");
    const SkyImage fine = sky_from_function(128, synthetic);
    write_image(dir + "/ll.exr", sky_to_latlong(fine, 256, Color(0.1f, 0.2f, 0.3f)));  // 256 x 128
    save_sky(dir + "/fish.exr", fine);
    const Eigen::Array3d exact = synthetic_integral();
    std::shared_ptr<SkyImage> ground;
    struct Case {
        std::string file;
        int asked, limit, want;
    };
    for (const Case& c : {Case{"ll", 0, 0, 128}, Case{"ll", 0, 64, 64}, Case{"ll", 0, 512, 128}, Case{"ll", 48, 64, 48},
                          Case{"fish", 0, 64, 128}, Case{"fish", 48, 0, 48}, Case{"fish", 200, 0, 200}}) {
        const SkyImage sky = load_sky_or_latlong(dir + "/" + c.file + ".exr", &ground, {c.asked, c.limit});
        EXPECT_EQ(sky.resolution, c.want) << c.file << " asked " << c.asked << " limit " << c.limit;
        EXPECT_EQ(bool(ground), c.file == "ll");
        if (ground) {
            EXPECT_EQ(ground->resolution, c.want) << "the ground is taken at the sky's size";
        }
        const Eigen::Array3d got = fisheye_integral(sky);
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[k], exact[k], 1.5e-2 * exact[k]) << c.file << " at " << c.want;
    }
    EXPECT_THROW(load_sky_or_latlong(dir + "/fish.exr", &ground, {4}), Error);  // under the 16 px floor
    std::filesystem::remove_all(dir);
}

// --sky-turn: a clear sky with its sun at azimuth 100 degrees, turned by 45 (a fisheye, through a
// lat-long) or taken from a lat-long turned by 45 (its columns rolled: 64 of 512), is the clear sky of
// a sun at 145: the sun where that one's is, with its energy, the rest within a few per cent, its recorded
// sun turned; a fisheye's filled mask turns with it.
TEST(LatLong, ASkyTurnedAboutTheZenithIsTheSkyOfTheTurnedSun) {
    const std::string dir = test::temp_dir("latlong_turned");
    ClearSkyParams params;
    params.sun_direction = fisheye::direction_from_angles(40 * kDeg, 100 * kDeg);
    SkyImage start = make_clear_sky(params, 128);
    start.filled.assign(size_t(128) * 128, 0);
    for (int j = 10; j < 30; ++j) start.filled[size_t(j) * 128 + 64] = 1;  // a line north of the zenith
    params.sun_direction = fisheye::direction_from_angles(40 * kDeg, 145 * kDeg);
    const SkyImage want = make_clear_sky(params, 128);
    save_sky(dir + "/fish.exr", start);
    write_image(dir + "/ll.exr", sky_to_latlong(start, 512));
    std::shared_ptr<SkyImage> ground;
    const SkyImage direct = turned_about_zenith(start, 45);
    for (const SkyImage& got : {direct, load_sky_or_latlong(dir + "/fish.exr", &ground, {0, 0, 45}),
                                load_sky_or_latlong(dir + "/ll.exr", &ground, {128, 0, 45})}) {
        ASSERT_TRUE(got.sun_direction);
        EXPECT_LT((got.sun_direction->cast<double>() - want.sun_direction->cast<double>()).norm(), 1e-5);
        const Eigen::Array3d a = fisheye_integral(got), b = fisheye_integral(want);
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[k], b[k], 0.01 * b[k]) << "channel " << k;
        int bi = 0, bj = 0, wi = 0, wj = 0;
        std::vector<double> rel;
        for (int j = 0; j < 128; ++j)
            for (int i = 0; i < 128; ++i) {
                if (got.pixel(i, j)[1] > got.pixel(bi, bj)[1]) bi = i, bj = j;
                if (want.pixel(i, j)[1] > want.pixel(wi, wj)[1]) wi = i, wj = j;
                if (!want.in_disc(i, j) || std::hypot(i - 63.5, j - 63.5) > 60) continue;
                rel.push_back(std::abs(got.pixel(i, j)[1] / want.pixel(i, j)[1] - 1));
            }
        EXPECT_LE(std::abs(bi - wi) + std::abs(bj - wj), 2) << "the sun at (" << bi << ", " << bj << ")";
        std::sort(rel.begin(), rel.end());
        EXPECT_LT(rel[rel.size() / 2], 0.01) << "median pixel";
        EXPECT_LT(rel[rel.size() * 95 / 100], 0.05) << "95th percentile pixel (the sun's neighbours apart)";
    }
    // The filled line north of the zenith (azimuth 0) now lies at azimuth 45: north-east, towards the
    // upper left of the image (east is left).
    ASSERT_EQ(direct.filled.size(), size_t(128) * 128);
    int filled = 0, upper_left = 0;
    for (int j = 0; j < 128; ++j)
        for (int i = 0; i < 128; ++i)
            if (direct.is_filled(i, j)) ++filled, upper_left += i < 64 && j < 64;
    EXPECT_GT(filled, 10);
    EXPECT_EQ(upper_left, filled);
    // An exact roll of a lat-long: a quarter turn moves a column W / 4 to the right.
    Image ll(16, 8, 3);
    ll.at(3, 2, 0) = 7;
    EXPECT_EQ(turn_latlong(&ll, 90), 90);
    EXPECT_EQ(ll.at(7, 2, 0), 7.0f);
    EXPECT_EQ(turn_latlong(&ll, -450), -450);  // -360 - 90: back
    EXPECT_EQ(ll.at(3, 2, 0), 7.0f);
    // To whole columns (22.5 degrees here), said, so the sun turns as far as the pixels; less than half
    // a column, or a whole turn, is none (and a fisheye is then not sent through a lat-long's blur).
    EXPECT_EQ(turn_latlong(&ll, 100), 90);
    EXPECT_EQ(turn_latlong(&ll, 10), 0);
    EXPECT_EQ(turned_about_zenith(start, 360).rgb, start.rgb);
    // A quarter turn is exact: the pixels permuted (the sun's peak kept, not halved by a round trip),
    // the line north of the zenith now east of it (left), the sun at azimuth 190.
    const SkyImage quarter = turned_about_zenith(start, 90);
    std::vector<float> a = start.rgb, b = quarter.rgb;
    std::sort(a.begin(), a.end()), std::sort(b.begin(), b.end());
    EXPECT_EQ(a, b);
    int left = 0, filled_quarter = 0;
    for (int j = 0; j < 128; ++j)
        for (int i = 0; i < 128; ++i)
            if (quarter.is_filled(i, j)) ++filled_quarter, left += i < 64 && j >= 63 && j <= 64;
    EXPECT_EQ(filled_quarter, 20);
    EXPECT_EQ(left, 20);
    params.sun_direction = fisheye::direction_from_angles(40 * kDeg, 190 * kDeg);
    EXPECT_LT((quarter.sun_direction->cast<double>() - params.sun_direction).norm(), 1e-6);
    EXPECT_EQ(turned_about_zenith(start, -270).rgb, quarter.rgb);
    EXPECT_EQ(turned_about_zenith(start, 0.1).rgb, start.rgb);
    // A bad pixel is named where the file has it, not where the turn put it.
    Image bad(16, 8, 3);
    bad.at(3, 2, 1) = std::nanf("");
    write_image(dir + "/bad.exr", bad);
    try {
        load_sky_or_latlong(dir + "/bad.exr", &ground, {0, 0, 90});
        ADD_FAILURE() << "a NaN pixel was taken";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("pixel (3, 2)"), std::string::npos) << e.what();
    }
    std::filesystem::remove_all(dir);
}

// The sky fisheye reads only the upper half's rows, the ground only the lower half's: a bright
// ground (snow, 20 x the sky) leaked into the sky's horizon ring through the filter.
TEST(LatLong, EachHalfIsReadWithoutTheOthersRows) {
    Image ll(64, 32, 3);
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 64; ++x)
            for (int c = 0; c < 3; ++c) ll.at(x, y, c) = y < 16 ? 1.0f : 20.0f;
    const SkyImage sky = latlong_to_fisheye(ll, 64), ground = latlong_to_fisheye(ll, 64, true);
    float sky_max = 0, ground_min = 1e9f;
    for (int j = 0; j < 64; ++j)
        for (int i = 0; i < 64; ++i)
            if (sky.in_disc(i, j)) {
                sky_max = std::max(sky_max, sky.pixel(i, j).maxCoeff());
                ground_min = std::min(ground_min, ground.pixel(i, j).minCoeff());
            }
    EXPECT_NEAR(sky_max, 1.0f, 1e-5f);
    EXPECT_NEAR(ground_min, 20.0f, 1e-4f);
}

TEST(LatLong, CarriesMetadataAndRejectsBadWidths) {
    SkyImage sky = sky_from_function(32, synthetic);
    sky.time_seconds = 12.5;
    sky.sun_direction = Vec3(0, 1, 0);
    sky.source = "test";
    Image ll = sky_to_latlong(sky, 64);
    EXPECT_DOUBLE_EQ(ll.metadata.numbers.at("dynsky:time"), 12.5);
    EXPECT_DOUBLE_EQ(ll.metadata.numbers.at("dynsky:sun_y"), 1.0);
    EXPECT_EQ(ll.metadata.strings.at("dynsky:source"), "test");
    EXPECT_THROW(sky_to_latlong(sky, 63), Error);
    EXPECT_THROW(sky_to_latlong(sky, 2), Error);
}

TEST(LatLong, SampleSkyIsBilinearInsideTheDisc) {
    SkyImage sky = sky_from_function(64, synthetic);
    // At a pixel centre the lookup returns that pixel.
    for (int j = 10; j < 54; j += 7)
        for (int i = 10; i < 54; i += 5) {
            Vec2 uv = fisheye::pixel_center_uv(i, j, 64);
            if (uv.squaredNorm() > 0.9) continue;
            Color got = sample_sky(sky, fisheye::direction_from_uv(double(uv.x()), double(uv.y())));
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], sky.pixel(i, j)[c], 1e-5);
        }
    EXPECT_EQ(sample_sky(sky, Vec3d(0, -1, 0)).matrix().norm(), 0.0f);
    // On the horizon itself the rim pixels stand in: finite and close to the function.
    Color rim = sample_sky(sky, Vec3d(1, 0, 0));
    EXPECT_NEAR(rim[1], synthetic(Vec3d(1, 0, 0))[1], 0.05);
}

// What `sky predict`, `animate` and `compare` say when they move a lat-long: its size, and how to
// choose another only when --sky-res did not.
TEST(LatLong, MovingNoteSaysTheSizeAndHowToChooseAnother) {
    EXPECT_EQ(moving_latlong_note("hdri.exr", 2048, false),
              "dynsky: note: hdri.exr is a lat-long sky: its upper half moves, as a 2048 x 2048 fisheye (--sky-res: "
              "another size)");
    EXPECT_EQ(moving_latlong_note("hdri.exr", 512, true),
              "dynsky: note: hdri.exr is a lat-long sky: its upper half moves, as a 512 x 512 fisheye");
}

}  // namespace
}  // namespace dynsky
