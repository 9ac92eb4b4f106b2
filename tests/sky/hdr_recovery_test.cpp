#include "sky/hdr_recovery.h"

#include <gtest/gtest.h>

#include <cmath>

#include "sky/clear_sky.h"
#include "sky/fisheye.h"
#include "tests/test_support.h"
#include "util/color.h"
#include "util/error.h"

namespace dynsky {
namespace {

TEST(UnitMap, HdrToUnitToHdrRoundTripsFromDarkSkyToTheSun) {
    UnitMapParams p;
    float previous = -1;
    for (double x = 1e-4; x <= 5e6; x *= 1.37) {
        float y = radiance_to_unit(float(x), p);
        EXPECT_GE(y, 0.0f);
        EXPECT_LE(y, 1.0f);
        EXPECT_GT(y, previous);  // strictly increasing: nothing merges
        previous = y;
        double back = unit_to_radiance(y, p);
        EXPECT_NEAR(back / x, 1.0, 2e-5) << x;
    }
    EXPECT_EQ(radiance_to_unit(0.0f, p), 0.0f);
    EXPECT_NEAR(radiance_to_unit(float(p.max_radiance), p), 1.0f, 1e-6);
    EXPECT_EQ(radiance_to_unit(float(10 * p.max_radiance), p), 1.0f);  // clamped above the range
}

TEST(UnitMap, UnitToHdrToUnitIsExact) {
    UnitMapParams p{0.5, 3e6};
    for (int k = 0; k <= 1000; ++k) {
        float y = k / 1000.0f;
        EXPECT_NEAR(radiance_to_unit(unit_to_radiance(y, p), p), y, 2e-6f) << y;
    }
}

TEST(UnitMap, WholeImagesRoundTripAndCarryTheirParameters) {
    ClearSkyParams cp;
    cp.sun_direction = fisheye::direction_from_angles(40 * kPiD / 180, 2.0);
    SkyImage sky = make_clear_sky(cp, 64);
    sky.set_pixel(30, 20, Color(3.1e6f, 2.6e6f, 2.0e6f));  // a disc-centre radiance, as at 2048 px
    UnitMapParams p;
    Image unit = hdr_to_unit(sky, p);
    SkyImage back = unit_to_hdr(unit, p);
    double max_sun = 0;
    for (size_t i = 0; i < sky.rgb.size(); ++i) {
        max_sun = std::max(max_sun, double(sky.rgb[i]));
        EXPECT_NEAR(back.rgb[i], sky.rgb[i], 2e-5 * sky.rgb[i] + 1e-7);
    }
    EXPECT_GT(max_sun, 1e5);  // the sun was in the range tested
    ASSERT_TRUE(back.sun_direction.has_value());
    UnitMapParams other{2.0, 1e7};
    EXPECT_THROW(unit_to_hdr(unit, other), Error);
    EXPECT_THROW(validate_unit_map(UnitMapParams{0.0, 1.0}), Error);
}

// An 8-bit photo of a known clear sky: model radiance / k0, clipped and sRGB-encoded, as a camera
// with exposure 1/k0 would record it (the canonical layout, so the import is the identity).
struct SyntheticClearPhoto {
    Image photo;
    SkyImage truth;
    HdrCalibrationParams params;
    double k0 = 40.0;
};

SyntheticClearPhoto clear_photo(int n) {
    SyntheticClearPhoto s;
    s.params.time = parse_utc_time("2017-05-24T16:00:00Z");
    s.params.location = {36.605, -97.485, 318};
    ClearSkyParams cp;
    cp.sun_direction = compute_sun_position(s.params.time, s.params.location).direction();
    s.truth = make_clear_sky(cp, n);
    s.photo = Image(n, n, 3);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            for (int k = 0; k < 3; ++k) {
                float v = std::min(1.0f, float(s.truth.pixel(i, j)[k] / s.k0));
                s.photo.at(i, j, k) = std::round(linear_to_srgb(v) * 255.0f) / 255.0f;
            }
    return s;
}

ImportedPhoto import_canonical(const Image& photo, int n) {
    PhotoImportParams p;
    p.resolution = n;
    p.circle = SkyCircle{n / 2.0 - 0.5, n / 2.0 - 0.5, n / 2.0};
    p.encoding = "srgb";
    return import_photo_image(photo, "synthetic.png", p);
}

TEST(HdrRecovery, CalibratesAClearSkyPhotoToTheModelAndRestoresTheSun) {
    const int n = 256;
    SyntheticClearPhoto s = clear_photo(n);
    ImportedPhoto imp = import_canonical(s.photo, n);
    HdrCalibrationReport rep;
    SkyImage hdr = recover_hdr(imp, s.params, &rep);
    EXPECT_EQ(rep.method, "clear-sky pixels");
    EXPECT_NEAR(rep.scale / s.k0, 1.0, 0.05);
    EXPECT_GT(rep.clear_fraction, 0.3);
    EXPECT_TRUE(rep.sun_visible);
    EXPECT_TRUE(rep.sun_restored);
    EXPECT_LT(rep.sun_offset_deg, 1.5);

    // Energy: the recovered sky's irradiance on a horizontal plane matches the model's within 15%;
    // without the restored sun it would miss most of it (the disc clips at 1 / k0 of its radiance).
    auto horizontal_irradiance = [n](const SkyImage& sky) {
        double e = 0;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                Vec2 uv = fisheye::pixel_center_uv(i, j, n);
                double cos_theta = fisheye::direction_from_uv(double(uv.x()), double(uv.y())).y();
                e += luminance(sky.pixel(i, j)) * cos_theta * fisheye::pixel_solid_angle(i, j, n);
            }
        return e;
    };
    double e_truth = horizontal_irradiance(s.truth), e_hdr = horizontal_irradiance(hdr);
    EXPECT_NEAR(e_hdr / e_truth, 1.0, 0.15);
    HdrCalibrationParams no_sun = s.params;
    no_sun.restore_sun = false;
    EXPECT_LT(horizontal_irradiance(recover_hdr(imp, no_sun)) / e_truth, 0.5);
    ASSERT_TRUE(hdr.sun_direction.has_value());
}

TEST(HdrRecovery, OvercastFallsBackToMeanLuminance) {
    const int n = 96;
    Image grey(n, n, 3);  // r/b = 1 everywhere: all cloud; brighter towards one side, as overcast is
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            for (int k = 0; k < 3; ++k) grey.at(x, y, k) = std::round((0.35f + 0.4f * x / n) * 255) / 255;
    ImportedPhoto imp = import_canonical(grey, n);
    HdrCalibrationParams p;
    p.time = parse_utc_time("2017-05-24T17:00:00Z");
    p.location = {36.605, -97.485, 318};
    HdrCalibrationReport rep;
    SkyImage hdr = recover_hdr(imp, p, &rep);
    EXPECT_EQ(rep.method, "mean-luminance fallback");
    EXPECT_FALSE(rep.sun_restored);
    EXPECT_GT(rep.scale, 0);
}

TEST(HdrRecovery, RefusesLinearInput) {
    const int n = 64;
    Image photo(n, n, 3);
    std::fill(photo.pixels.begin(), photo.pixels.end(), 0.3f);
    PhotoImportParams p;
    p.resolution = n;
    p.circle = SkyCircle{n / 2.0 - 0.5, n / 2.0 - 0.5, n / 2.0};
    p.encoding = "linear";
    ImportedPhoto imp = import_photo_image(photo, "photo.exr", p);
    HdrCalibrationParams hp;
    hp.time = parse_utc_time("2017-05-24T17:00:00Z");
    hp.location = {36.605, -97.485, 318};
    EXPECT_THROW(recover_hdr(imp, hp), Error);
}

// Real data: one camera with a fixed exposure should calibrate to nearly the same scale all
// morning; the sun behind the TSI's band is restored when the sky beside the band is clear.
TEST(HdrRecovery, TsiCalibrationIsStableAlongTheSequence) {
    DYNSKY_REQUIRE_SHARED();
    CameraPreset preset = camera_preset("arm-tsi");
    std::vector<double> scales;
    for (const char* stamp : {"20170524154000Z", "20170524170000Z", "20170524180930Z"}) {
        std::string path = test::shared_path(std::string("skies/arm_tsi_sgp_20170524/images/tsi_sgpC1_") + stamp +
                                             ".jpg");
        PhotoImportParams p = preset.params;
        p.resolution = 128;
        p.mask_path = find_preset_mask("arm-tsi", path);
        ImportedPhoto imp = import_photo(path, p);
        HdrCalibrationParams hp;
        hp.time = parse_utc_time(time_from_file_name(path));
        hp.location = {preset.latitude_deg, preset.longitude_deg, preset.elevation_m};
        hp.sun_search_deg = preset.sun_search_deg;
        HdrCalibrationReport rep;
        SkyImage hdr = recover_hdr(imp, hp, &rep);
        EXPECT_EQ(rep.method, "clear-sky pixels") << stamp;
        EXPECT_LT(rep.ratio_spread, 0.3) << stamp;
        EXPECT_NO_THROW(validate_sky(hdr, stamp));
        scales.push_back(rep.scale);
    }
    double lo = *std::min_element(scales.begin(), scales.end()), hi = *std::max_element(scales.begin(), scales.end());
    EXPECT_LT(hi / lo, 1.25) << lo << " .. " << hi;
}

}  // namespace
}  // namespace dynsky
