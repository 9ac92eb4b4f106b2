#include "motion/radiance_scale.h"

#include <gtest/gtest.h>

#include "sky/clear_sky.h"
#include "sky/fisheye.h"
#include "sky/procedural_clouds.h"

namespace dynsky {
namespace {

SkyImage clear_sky(double elevation_deg, int n = 128) {
    ClearSkyParams p;
    p.sun_direction = fisheye::direction_from_angles((90 - elevation_deg) * kPiD / 180, 2.0);
    SkyImage sky = make_clear_sky(p, n);
    return sky;
}

SkyImage scaled(SkyImage sky, double factor) {
    scale_radiance(&sky, factor);
    return sky;
}

// Skies at the models' scale (a clear sky, a procedural cumulus) measure about 1 and are left alone;
// the same skies in other units measure their factor, from the clear pixels or, overcast, the mean.
TEST(RadianceScale, SkiesAtScaleMeasureOneOthersTheirFactor) {
    for (double elevation : {10.0, 35.0, 70.0}) {
        const SkyImage sky = clear_sky(elevation);
        const RadianceScale at = measure_radiance_scale(sky);
        ASSERT_TRUE(at.measured) << elevation;
        EXPECT_NEAR(at.factor, 1.0, 0.02) << elevation;
        EXPECT_EQ(at.clear_weight, 1.0);
        EXPECT_FALSE(at.apply);
        for (double f : {3.0, 1e-3, 1e-6, 1000.0}) {
            const RadianceScale s = measure_radiance_scale(scaled(sky, f));
            EXPECT_NEAR(s.factor / f, 1.0, 0.02) << elevation << " x " << f;
            EXPECT_TRUE(s.apply) << elevation << " x " << f;
        }
        EXPECT_FALSE(measure_radiance_scale(scaled(sky, 1.3)).apply);  // within the band: moved as it is
    }
    ProceduralSkyParams p;
    p.coverage = 0.5;
    p.layers = {cumulus_layer()};
    p.clear_sky.sun_direction = fisheye::direction_from_angles(0.8, 1.2);
    const SkyImage cumulus = ProceduralSky(p).render(0, 128);
    const RadianceScale c = measure_radiance_scale(cumulus);
    EXPECT_NEAR(c.factor, 1.0, 0.1);
    EXPECT_FALSE(c.apply);
    EXPECT_NEAR(measure_radiance_scale(scaled(cumulus, 20)).factor / 20, c.factor, 1e-3 * c.factor);
    // Overcast (no clear pixel): the mean's ratio, the same for any units.
    p.coverage = 1.0;
    const SkyImage overcast = ProceduralSky(p).render(0, 128);
    const RadianceScale o = measure_radiance_scale(overcast);
    EXPECT_LT(o.clear_weight, 1.0);
    EXPECT_NEAR(measure_radiance_scale(scaled(overcast, 1e-4)).factor / 1e-4, o.factor, 1e-3 * o.factor);
    // An overcast that says it is W m^-2 sr^-1 is dark because it is dark: taken at its word (moved
    // at the model's scale it read as a thinner cloud, and `compare` darkened its clear sky by the
    // same factor). A clear sky scaled by hand keeps its attributes, but its clear pixels measure
    // the scale: moved at the model's scale still.
    ASSERT_EQ(overcast.units, kAbsoluteRadiance);
    for (const bool says : {true, false}) {
        SkyImage dark = scaled(overcast, 0.3);
        if (!says) dark.units.clear();
        std::shared_ptr<const SkyImage> none;
        EXPECT_EQ(bring_to_model_scale(&dark, &none).apply, !says) << says;
    }
    // ... unless it is brighter than any sky can be (30 x the clear-sky model's mean): then it is
    // not in those units whatever it says (an overcast x 1e4 clipped at the log map's top and came
    // out at 0.2 % of itself after one step).
    for (const double f : {5.0, 1e4}) {
        SkyImage bright = scaled(overcast, f);
        ASSERT_EQ(bright.units, kAbsoluteRadiance);
        std::shared_ptr<const SkyImage> none;
        const RadianceScale b = bring_to_model_scale(&bright, &none);
        EXPECT_EQ(b.apply, f > 100) << f << ": " << b.factor;
    }
    {
        SkyImage bright = scaled(clear_sky(35), 3);
        ASSERT_EQ(bright.units, kAbsoluteRadiance);
        std::shared_ptr<const SkyImage> none;
        EXPECT_TRUE(bring_to_model_scale(&bright, &none).apply);
    }
    // No sun to compare with (below the horizon, or unknown and not visible): not measured.
    SkyImage night = clear_sky(10);
    night.sun_direction = Vec3(0.0f, -0.5f, 0.866f);
    EXPECT_FALSE(measure_radiance_scale(night).measured);
}

}  // namespace
}  // namespace dynsky
