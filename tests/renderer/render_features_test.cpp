// The passes (AOVs), render region, camera overrides, orthographic cameras, lat-long skies,
// adaptive sampling and the firefly remedies of renderer/integrator.h, checked against known
// values or against the plain render they must agree with.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include <tbb/global_control.h>

#include "renderer/integrator.h"
#include "renderer/shapes.h"
#include "renderer/zsobol_sampler.h"
#include "tests/renderer/chi_square.h"
#include "sky/fisheye.h"
#include "sky/latlong.h"
#include "tests/test_support.h"
#include "util/error.h"

namespace dynsky {
namespace {

// A sky with a broad blue gradient and a small, very bright sun (1.5 degrees across) at 40 degrees
// elevation: fireflies wherever a glossy bounce can reach it.
std::shared_ptr<SkyImage> sunny_sky(int n, float sun_radiance, double sun_radius_deg) {
    auto sky = std::make_shared<SkyImage>(n);
    Vec3d sun = fisheye::direction_from_angles(50 * kPiD / 180, 2.0);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            Vec2 uv = fisheye::pixel_center_uv(i, j, n);
            if (uv.squaredNorm() > 1) continue;
            Vec3d w = fisheye::direction_from_uv(uv.x(), uv.y());
            Color c = Color(0.3f, 0.45f, 0.9f) * float(0.4 + 0.6 * w.y());
            if (w.dot(sun) > std::cos(sun_radius_deg * kPiD / 180)) c += Color::Constant(sun_radiance);
            sky->set_pixel(i, j, c);
        }
    return sky;
}

Camera camera_at(const Vec3& eye, const Vec3& target, float yfov) { return look_at_camera(eye, target, yfov); }

// A Lambert square of side 2 in the plane z = 0 facing +Z (towards a camera on +Z).
Scene lambert_wall(const Color& albedo) {
    Scene scene;
    Material m;
    m.base_color = albedo, m.metallic = 0, m.roughness = 1, m.specular = 0;
    scene.materials.push_back(m);
    Eigen::Affine3f face_z(Eigen::AngleAxisf(kPi / 2, Vec3::UnitX()));  // +Y normal to +Z
    add_mesh_instance(&scene, make_ground_quad_mesh(2, 0), face_z, "wall");
    return scene;
}

// A sphere on a rough floor; chrome when glossy.
Scene sphere_on_floor(bool glossy) {
    Scene scene;
    Material sphere, floor;
    sphere.base_color = Color(0.95f, 0.93f, 0.88f), sphere.metallic = glossy ? 1 : 0,
    sphere.roughness = glossy ? 0.05f : 0.7f;
    floor.base_color = Color(0.6f, 0.6f, 0.6f), floor.metallic = 0, floor.roughness = 0.9f;
    scene.materials = {sphere, floor};
    add_mesh_instance(&scene, make_sphere_mesh(64, 32, 0), Eigen::Affine3f::Identity(), "sphere");
    add_mesh_instance(&scene, make_ground_quad_mesh(8, 1), Eigen::Affine3f(Eigen::Translation3f(0, -1, 0)), "floor");
    return scene;
}

TEST(RenderAovs, LambertWallGivesItsAlbedoNormalDepthAndAlphaExactly) {
    const Color albedo(0.25f, 0.5f, 0.75f);
    Scene scene = lambert_wall(albedo);
    Accel accel(scene);
    EnvLight light(sunny_sky(64, 100, 3), 0.3f);
    RenderSettings s;
    s.width = 32, s.height = 32, s.spp = 4, s.quiet = true;
    s.aovs.albedo = s.aovs.normal = s.aovs.depth = s.aovs.alpha = s.aovs.sample_count = true;
    const float distance = 4;
    // tan(yfov / 2) = 0.4: the wall (half side 1) covers |ndc| < 0.625 of the image.
    Camera cam = camera_at(Vec3(0, 0, distance), Vec3::Zero(), 2 * std::atan(0.4f));
    RenderResult r = PathIntegrator(accel, light, s).render(cam);
    int wall = 0, sky = 0;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) {
            float nx = std::abs((x + 0.5f) / 16 - 1), ny = std::abs((y + 0.5f) / 16 - 1);
            EXPECT_EQ(r.sample_count.at(x, y, 0), 4.0f);
            if (nx < 0.55f && ny < 0.55f) {  // every sample on the wall
                ++wall;
                for (int k = 0; k < 3; ++k) EXPECT_EQ(r.albedo.at(x, y, k), albedo[k]);
                EXPECT_NEAR(r.normal.at(x, y, 0), 0.0f, 1e-6f);
                EXPECT_NEAR(r.normal.at(x, y, 1), 0.0f, 1e-6f);
                EXPECT_NEAR(r.normal.at(x, y, 2), 1.0f, 1e-6f);
                EXPECT_NEAR(r.depth.at(x, y, 0), distance, 1e-5f * distance);  // Z depth: the same across the wall
                EXPECT_EQ(r.alpha.at(x, y, 0), 1.0f);
            } else if (nx > 0.7f || ny > 0.7f) {  // every sample on the sky
                ++sky;
                for (int k = 0; k < 3; ++k) EXPECT_EQ(r.albedo.at(x, y, k), 0.0f);
                for (int k = 0; k < 3; ++k) EXPECT_EQ(r.normal.at(x, y, k), 0.0f);
                EXPECT_EQ(r.depth.at(x, y, 0), 1e10f);
                EXPECT_EQ(r.alpha.at(x, y, 0), 0.0f);
            }
        }
    EXPECT_GT(wall, 200);
    EXPECT_GT(sky, 200);
    // The EXR layout: colour with alpha, then the passes under Cycles' names.
    Image layers = render_layers(r);
    EXPECT_EQ(layers.channels, 3 + 1 + 3 + 3 + 1 + 1);
    EXPECT_EQ(layers.channel_names, (std::vector<std::string>{"R", "G", "B", "A", "Denoising Albedo.R",
                                                              "Denoising Albedo.G", "Denoising Albedo.B", "Normal.X",
                                                              "Normal.Y", "Normal.Z", "Depth.Z", "Sample Count.X"}));
    EXPECT_EQ(layers.at(16, 16, layers.channel_index("Denoising Albedo.G")), albedo[1]);
    EXPECT_EQ(layers.at(16, 16, 1), r.color.at(16, 16, 1));
    // Written and read back with the names (OpenEXR may reorder channels; names find them).
    std::string dir = test::temp_dir("aovs");
    write_image(dir + "/layers.exr", layers);
    Image back = read_image(dir + "/layers.exr");
    ASSERT_EQ(back.channels, layers.channels);
    for (const std::string& name : layers.channel_names) {
        int a = layers.channel_index(name), b = back.channel_index(name);
        ASSERT_GE(b, 0) << name;
        EXPECT_EQ(back.at(16, 16, b), layers.at(16, 16, a)) << name;
        EXPECT_EQ(back.at(1, 1, b), layers.at(1, 1, a)) << name;
    }
}

// With an alpha pass the colour is premultiplied, as Cycles' Film > Transparent writes it: where
// A = 0 (sky) the colour is 0, where A = 1 it is the render without the pass, bit for bit (the
// same samples), and at the sphere's edge it holds only its surface samples' light, never more
// than the render with the sky in it. Before, RGB kept the sky where A = 0, and an "over" on a
// plate (oiiotool --over, Nuke, Blender) added the sky to the plate (an output audit).
TEST(RenderAovs, AlphaPremultipliesTheColourAsATransparentFilm) {
    Scene scene = sphere_on_floor(false);
    scene.meshes.pop_back(), scene.instances.pop_back();  // the sphere alone: sky around it
    Accel accel(scene);
    EnvLight light(sunny_sky(64, 200, 3), 0.3f);
    RenderSettings s;
    s.width = 40, s.height = 30, s.spp = 8, s.quiet = true, s.seed = 3;
    Camera cam = camera_at(Vec3(0.5f, 1.0f, 4.5f), Vec3(0, 0, 0), 0.8f);
    const RenderResult plain = PathIntegrator(accel, light, s).render(cam);
    s.aovs.alpha = true;
    const RenderResult film = PathIntegrator(accel, light, s).render(cam);
    int sky = 0, surface = 0, edge = 0;
    for (int y = 0; y < s.height; ++y)
        for (int x = 0; x < s.width; ++x) {
            const float a = film.alpha.at(x, y, 0);
            for (int k = 0; k < 3; ++k) {
                if (a == 0) {
                    EXPECT_EQ(film.color.at(x, y, k), 0.0f) << x << "," << y;
                }
                if (a == 1) {
                    EXPECT_EQ(film.color.at(x, y, k), plain.color.at(x, y, k)) << x << "," << y;
                }
                if (a > 0 && a < 1) {
                    EXPECT_LT(film.color.at(x, y, k), plain.color.at(x, y, k)) << x << "," << y;
                }
            }
            sky += a == 0, surface += a == 1, edge += a > 0 && a < 1;
        }
    EXPECT_GT(sky, 100);
    EXPECT_GT(surface, 50);
    EXPECT_GT(edge, 10);
}

TEST(RenderRegion, RegionEqualsTheSamePixelsOfTheFullRenderBitwise) {
    Scene scene = sphere_on_floor(false);
    Accel accel(scene);
    EnvLight light(sunny_sky(64, 200, 3), 0.3f);
    RenderSettings s;
    s.width = 40, s.height = 30, s.spp = 8, s.quiet = true, s.seed = 9;
    s.aovs.depth = s.aovs.normal = true;
    Camera cam = camera_at(Vec3(0.5f, 1.0f, 4.5f), Vec3(0, -0.3f, 0), 0.8f);
    RenderResult full = PathIntegrator(accel, light, s).render(cam);
    s.region = PixelRegion{7, 5, 29, 23};
    RenderResult part = PathIntegrator(accel, light, s).render(cam);
    ASSERT_EQ(part.color.width, 22);
    ASSERT_EQ(part.color.height, 18);
    for (int y = 0; y < 18; ++y)
        for (int x = 0; x < 22; ++x) {
            for (int k = 0; k < 3; ++k) {
                ASSERT_EQ(part.color.at(x, y, k), full.color.at(x + 7, y + 5, k)) << x << "," << y;
                ASSERT_EQ(part.normal.at(x, y, k), full.normal.at(x + 7, y + 5, k));
            }
            ASSERT_EQ(part.depth.at(x, y, 0), full.depth.at(x + 7, y + 5, 0));
        }
    EXPECT_THROW(parse_region("0,0,41,30", 40, 30), Error);
    EXPECT_THROW(parse_region("5,5,5,9", 40, 30), Error);
    EXPECT_THROW(parse_region("1,2,3", 40, 30), Error);
    EXPECT_THROW(parse_region("1,2,3,x", 40, 30), Error);
    PixelRegion ok = parse_region("1,2,30,20", 40, 30);
    EXPECT_EQ(ok.x1, 30);
    EXPECT_EQ(ok.y0, 2);
}

TEST(RenderSky, LatlongSkyAndItsFisheyeConversionRenderTheSameImage) {
    // The reference: a fisheye sky with the ground model below. The lat-long made from it carries
    // the model's ground radiance in its lower half; read back, both must light the scene alike.
    auto fisheye_sky = sunny_sky(128, 30, 6);
    EnvLight reference(fisheye_sky, 0.3f);
    Image latlong = sky_to_latlong(*fisheye_sky, 512, reference.ground_radiance());
    LatlongEnvironment env = latlong_environment(latlong, "test lat-long", 128);
    EnvLight converted(std::make_shared<SkyImage>(env.sky), 0.3f);
    converted.set_ground_image(std::make_shared<SkyImage>(env.ground));
    for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(converted.sky_irradiance()[k], reference.sky_irradiance()[k], 0.01 * reference.sky_irradiance()[k]);
        EXPECT_NEAR(converted.ground_radiance()[k], reference.ground_radiance()[k],
                    1e-3 * reference.ground_radiance()[k]);
    }
    Scene scene = sphere_on_floor(false);
    Accel accel(scene);
    RenderSettings s;
    s.width = 24, s.height = 18, s.spp = 64, s.quiet = true;
    Camera cam = camera_at(Vec3(0.5f, 0.6f, 4.5f), Vec3(0, -0.3f, 0), 0.9f);
    RenderResult a = PathIntegrator(accel, reference, s).render(cam);
    RenderResult b = PathIntegrator(accel, converted, s).render(cam);
    double sum_a = 0, sum_b = 0;
    for (size_t i = 0; i < a.color.pixels.size(); ++i) sum_a += a.color.pixels[i], sum_b += b.color.pixels[i];
    EXPECT_NEAR(sum_b / sum_a, 1.0, 0.01);
}

// Per pixel, with 16-sample rounds: a pixel that stopped before the cap has an error estimate
// (its own and its neighbourhood's) under the threshold, and one round earlier it had not (checked
// on renders capped at those rounds, whose decisions up to there are the same), and its colour is
// that of a plain render of as many samples (it shares them bitwise).
TEST(AdaptiveSampling, StopsExactlyWhereTheErrorEstimateFallsUnderTheThreshold) {
    Scene scene = sphere_on_floor(false);
    Accel accel(scene);
    EnvLight light(sunny_sky(64, 200, 3), 0.3f);
    Camera cam = camera_at(Vec3(0.5f, 1.0f, 4.5f), Vec3(0, -0.3f, 0), 0.8f);
    RenderSettings s;
    s.width = 20, s.height = 16, s.spp = 96, s.quiet = true, s.seed = 3;
    s.noise_threshold = 0.04f, s.round_spp = 16;
    s.aovs.sample_count = true;
    RenderResult adaptive = PathIntegrator(accel, light, s).render(cam);
    std::map<int, RenderResult> plain, capped;  // by spp
    auto plain_at = [&](int spp) -> const RenderResult& {
        if (!plain.count(spp)) {
            RenderSettings p = s;
            p.spp = spp, p.noise_threshold = 0, p.compute_variance = true;
            plain[spp] = PathIntegrator(accel, light, p).render(cam);
        }
        return plain[spp];
    };
    auto adaptive_at = [&](int spp) -> const RenderResult& {
        if (!capped.count(spp)) {
            RenderSettings c = s;
            c.spp = spp;
            capped[spp] = PathIntegrator(accel, light, c).render(cam);
        }
        return capped[spp];
    };
    int stopped_early = 0, at_cap = 0;
    for (int y = 0; y < s.height; ++y)
        for (int x = 0; x < s.width; ++x) {
            int n = int(adaptive.sample_count.at(x, y, 0));
            ASSERT_EQ(n % 16, 0);
            ASSERT_GE(n, 16);
            const RenderResult& same = plain_at(n);
            for (int k = 0; k < 3; ++k) ASSERT_EQ(adaptive.color.at(x, y, k), same.color.at(x, y, k));
            EXPECT_EQ(adaptive.relative_error.at(x, y, 0), adaptive_at(n).relative_error.at(x, y, 0));
            EXPECT_GE(adaptive.relative_error.at(x, y, 0), same.relative_error.at(x, y, 0));  // its own, and more
            if (n < s.spp) {
                ++stopped_early;
                EXPECT_LT(adaptive.relative_error.at(x, y, 0), s.noise_threshold);
            } else {
                ++at_cap;
            }
            if (n > 16) {
                EXPECT_GE(adaptive_at(n - 16).relative_error.at(x, y, 0), s.noise_threshold) << x << "," << y;
            }
        }
    // Both happen (18 and 302 of 320 with the neighbourhood; 30 stopped on their own estimates).
    EXPECT_GT(stopped_early, 10);
    EXPECT_GT(at_cap, 5);
}

// A floor lit only by an emitter the size of a hand (20 cm at 1 m; emitters are found by the paths
// that hit them, not light-sampled) under a black sky: about 80 % of the pixels' first 16 samples
// miss it. Adaptive sampling must not take "no light seen yet" for "converged": its image agrees
// with a fixed-rate render's. On each pixel's own estimate most stopped at once and the image came
// out 3-6 times too dark.
TEST(AdaptiveSampling, PixelsWhoseFirstSamplesMissedASmallLightDoNotStop) {
    Scene scene;
    Material floor, lamp;
    floor.base_color = Color::Constant(0.5f), floor.metallic = 0, floor.roughness = 1, floor.specular = 0;
    lamp.base_color = Color::Zero(), lamp.metallic = 0, lamp.roughness = 1, lamp.specular = 0;
    lamp.emissive = Color::Constant(100.0f), lamp.double_sided = true;
    scene.materials = {floor, lamp};
    add_mesh_instance(&scene, make_ground_quad_mesh(200, 0), Eigen::Affine3f::Identity(), "floor");
    add_mesh_instance(&scene, make_ground_quad_mesh(0.2f, 1),
                      Eigen::Affine3f(Eigen::Translation3f(0, 1, 0) * Eigen::AngleAxisf(kPi, Vec3::UnitX())), "lamp");
    Accel accel(scene);
    auto sky = std::make_shared<SkyImage>(32);
    for (int j = 0; j < 32; ++j)
        for (int i = 0; i < 32; ++i)
            if (sky->in_disc(i, j)) sky->set_pixel(i, j, Color::Constant(1e-6f));
    EnvLight light(sky, 0.0f);
    const Camera cam = camera_at(Vec3(0, 0.5f, 0), Vec3(0, 0, 0), 1.2f);
    RenderSettings s;
    s.width = 24, s.height = 24, s.spp = 512, s.quiet = true, s.seed = 11;
    s.aovs.sample_count = true;
    auto mean_of = [](const Image& im) {
        double sum = 0;
        for (float v : im.pixels) sum += v;
        return sum / double(im.pixels.size());
    };
    const double fixed = mean_of(PathIntegrator(accel, light, s).render(cam).color);
    // The floor right under a 0.04 m^2 emitter of 100 at 1 m: 0.5 / pi x 100 x 0.04 = 0.64.
    EXPECT_NEAR(fixed, 0.6, 0.1);
    for (float threshold : {0.05f, 0.2f}) {
        s.noise_threshold = threshold, s.round_spp = 16;
        const RenderResult r = PathIntegrator(accel, light, s).render(cam);
        EXPECT_NEAR(mean_of(r.color) / fixed, 1.0, 0.05) << "threshold " << threshold;
        int stopped_at_once = 0;
        for (float n : r.sample_count.pixels) stopped_at_once += n == 16.0f;
        EXPECT_LT(stopped_at_once, int(r.sample_count.pixels.size()) / 10) << "threshold " << threshold;
    }
}

// Rare light found by a pixel's neighbours keeps it sampling; a flat neighbourhood lets it stop.
TEST(AdaptiveSampling, NeighbourhoodEstimateOfKnownStatistics) {
    const int w = 5, h = 5;
    std::vector<int> n(w * h, 16);
    std::vector<double> sum(w * h, 16.0), sum2(w * h, 16.0);  // every sample 1: no variance anywhere
    std::vector<double> e = adaptive_error_estimates(w, h, n, sum, sum2, 1);
    for (double v : e) EXPECT_EQ(v, 0.0);
    // One pixel found the light once (samples 0 x 15 and 50): its neighbours are no longer sure.
    sum[12] = 50, sum2[12] = 2500;
    e = adaptive_error_estimates(w, h, n, sum, sum2, 1);
    EXPECT_GT(e[6], 0.1);  // next to it
    EXPECT_EQ(e[0], 0.0);  // two pixels away, outside the radius
    EXPECT_GE(e[12], pixel_relative_error(16, 50, 2500));
    EXPECT_TRUE(std::isinf(adaptive_error_estimates(1, 1, {1}, {1.0}, {1.0}, 4)[0]));  // one sample says nothing
    // A sun pixel's enormous variance stays in its own neighbourhood: flat pixels far along the row
    // keep an estimate of exactly 0 (summed over the whole row, its 1e14 left a residue everywhere).
    std::vector<int> row_n(40, 16);
    std::vector<double> row_sum(40, 16.0), row_sum2(40, 16.0);
    row_sum[0] = 16e7, row_sum2[0] = 16e14 + 1e15;  // mean 1e7, variance about 6.7e13
    const std::vector<double> row = adaptive_error_estimates(40, 1, row_n, row_sum, row_sum2, 4);
    EXPECT_GT(row[3], 0.1);
    for (int x = 10; x < 40; ++x) EXPECT_EQ(row[size_t(x)], 0.0) << x;
    EXPECT_THROW(adaptive_error_estimates(2, 2, {1}, {1.0}, {1.0}, 1), Error);
}

TEST(AdaptiveSampling, TimeLimitStopsAfterTheFirstRound) {
    Scene scene = sphere_on_floor(false);
    Accel accel(scene);
    EnvLight light(sunny_sky(64, 200, 3), 0.3f);
    RenderSettings s;
    s.width = 8, s.height = 8, s.spp = 256, s.quiet = true, s.round_spp = 16;
    s.time_limit_seconds = 1e-9;  // over before the first round ends: exactly that round is kept
    s.aovs.sample_count = true;
    RenderResult r = PathIntegrator(accel, light, s).render(camera_at(Vec3(0, 0, 4), Vec3::Zero(), 0.8f));
    EXPECT_EQ(r.rounds, 1);
    for (float n : r.sample_count.pixels) EXPECT_EQ(n, 16.0f);
}

TEST(AdaptiveSampling, RelativeErrorOfKnownSamples) {
    // Samples 1, 3: mean 2, variance 2, variance of the mean 1: relative error 1 / 2.
    EXPECT_DOUBLE_EQ(pixel_relative_error(2, 4, 10), 0.5);
    EXPECT_EQ(pixel_relative_error(8, 0, 0), 0.0);
    EXPECT_TRUE(std::isinf(pixel_relative_error(1, 1, 1)));
}

// Relative MSE (the issue's measure, untrimmed): the mean over pixels and channels of
// (a - ref)^2 / (ref^2 + 0.01).
double relative_mse(const Image& a, const Image& ref) {
    double sum = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) {
        double d = a.pixels[i] - ref.pixels[i];
        sum += d * d / (double(ref.pixels[i]) * ref.pixels[i] + 0.01);
    }
    return sum / double(a.pixels.size());
}

// Bias measure: the mean over pixels and channels of (a - ref) / (ref + 0.1).
double mean_relative_difference(const Image& a, const Image& ref) {
    double sum = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) sum += (a.pixels[i] - ref.pixels[i]) / (ref.pixels[i] + 0.1);
    return sum / double(a.pixels.size());
}

TEST(Fireflies, RemediesThatDoNotActLeaveTheImageBitwiseUnchanged) {
    Scene scene = sphere_on_floor(true);
    Accel accel(scene);
    EnvLight light(sunny_sky(64, 5000, 1.5), 0.3f);
    Camera cam = camera_at(Vec3(0.5f, 1.0f, 4.5f), Vec3(0, -0.3f, 0), 0.8f);
    RenderSettings s;
    s.width = 24, s.height = 18, s.spp = 8, s.quiet = true;
    RenderResult off = PathIntegrator(accel, light, s).render(cam);
    s.clamp_indirect = 1e30f, s.filter_glossy = 1e-30f;  // on, but never reached
    RenderResult idle = PathIntegrator(accel, light, s).render(cam);
    EXPECT_EQ(off.color.pixels, idle.color.pixels);
    s.clamp_indirect = 1.0f, s.filter_glossy = 0;  // on and acting
    RenderResult on = PathIntegrator(accel, light, s).render(cam);
    EXPECT_NE(off.color.pixels, on.color.pixels);
}

// A chrome ball on a rough floor under a small, bright sun: the floor sees the sun through the
// ball (a caustic no light sample can find), the untrimmed error's fireflies. Against the
// unbiased reference each remedy trades some bias (measured on converged renders with the
// remedy) for a large cut in the untrimmed error at low spp.
TEST(Fireflies, ClampAndFilterGlossyCutTheUntrimmedErrorOnAGlossyScene) {
    Scene scene = sphere_on_floor(true);
    Accel accel(scene);
    EnvLight light(sunny_sky(64, 5000, 1.5), 0.3f);
    Camera cam = camera_at(Vec3(0.5f, 1.0f, 4.5f), Vec3(0, -0.3f, 0), 0.8f);
    RenderSettings base;
    base.width = 24, base.height = 18, base.quiet = true;
    auto render = [&](float clamp, float filter, int spp, uint64_t seed) {
        RenderSettings s = base;
        s.clamp_indirect = clamp, s.filter_glossy = filter, s.spp = spp, s.seed = seed;
        return PathIntegrator(accel, light, s).render(cam).color;
    };
    const Image reference = render(0, 0, 2048, 1000);
    struct Case {
        const char* name;
        float clamp, filter;
        double error = 0, bias = 0;
    };
    Case cases[] = {{"off", 0, 0}, {"clamp-indirect 10", 10, 0}, {"filter-glossy 1", 0, 1}};
    for (Case& c : cases) {
        c.error = relative_mse(render(c.clamp, c.filter, 16, 1), reference);
        c.bias = c.clamp > 0 || c.filter > 0
                     ? mean_relative_difference(render(c.clamp, c.filter, 2048, 1000), reference)
                     : 0;
        std::printf("%-18s 16 spp relative MSE %.4f; bias (2048 spp, mean relative difference) %+.4f\n", c.name,
                    c.error, c.bias);
    }
    EXPECT_LT(cases[1].error, 0.6 * cases[0].error);
    EXPECT_LT(cases[2].error, 0.7 * cases[0].error);
    // Both darken (they remove light), and not by much.
    for (int k : {1, 2}) {
        EXPECT_LT(cases[k].bias, 0.0) << cases[k].name;
        EXPECT_GT(cases[k].bias, -0.1) << cases[k].name;
    }
}

TEST(ZSobol, SobolDimensionsAreTheKnownSequences) {
    // Dimension 0 is van der Corput; dimension 1 has direction numbers 1, 3, 5, 15, 17 (Joe-Kuo).
    EXPECT_EQ(ZSobolSampler::sobol(1, 0), 0x80000000u);
    EXPECT_EQ(ZSobolSampler::sobol(2, 0), 0x40000000u);
    EXPECT_EQ(ZSobolSampler::sobol(3, 0), 0xC0000000u);
    EXPECT_EQ(ZSobolSampler::sobol(2, 1), 0xC0000000u);
    EXPECT_EQ(ZSobolSampler::sobol(4, 1), 0xA0000000u);
    EXPECT_EQ(ZSobolSampler::sobol(8, 1), 0xF0000000u);
    EXPECT_EQ(ZSobolSampler::sobol(16, 1), 0x88000000u);
    // An Owen scramble permutes: the 2^k first points stay one per stratum of 2^-k.
    for (uint32_t seed : {1u, 77u, 0xDEADBEEFu}) {
        std::vector<int> strata(64, 0);
        for (uint64_t i = 0; i < 64; ++i) ++strata[ZSobolSampler::scramble(ZSobolSampler::sobol(i, 1), seed) >> 26];
        for (int c : strata) EXPECT_EQ(c, 1);
    }
}

// Every dimension the integrator draws, 1D and 2D, over all pixels and samples of an image: the
// histograms pass Pearson's chi-square test against the uniform distribution.
TEST(ZSobol, ChiSquareOfTheSampleDimensions) {
    const int w = 24, h = 16, spp = 16;
    ZSobolSampler sampler(w, h, spp, 7);
    const int dims = 12, bins = 8;
    std::vector<std::vector<double>> one(dims, std::vector<double>(64, 0)),
        two(dims, std::vector<double>(bins * bins, 0));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int i = 0; i < spp; ++i) {
                sampler.start(x, y, i);
                for (int d = 0; d < dims; ++d) {
                    Vec2 u = sampler.uniform2();  // the pixel jitter, then NEE and BSDF pairs
                    float v = sampler.uniform();
                    ASSERT_TRUE(u.x() >= 0 && u.x() < 1 && u.y() >= 0 && u.y() < 1 && v >= 0 && v < 1);
                    ++one[d][int(v * 64)];
                    ++two[d][int(u.y() * bins) * bins + int(u.x() * bins)];
                }
            }
    const double n = double(w) * h * spp;
    for (int d = 0; d < dims; ++d) {
        auto r1 = test::chi_square_test(one[d], std::vector<double>(64, n / 64));
        auto r2 = test::chi_square_test(two[d], std::vector<double>(bins * bins, n / (bins * bins)));
        EXPECT_GT(r1.p_value, 0.01) << "1D dimension " << d << ": " << r1.summary();
        EXPECT_GT(r2.p_value, 0.01) << "2D dimension " << d << ": " << r2.summary();
    }
    // Not just uniform but stratified: one pixel's 16 jitters fall one per 4 x 4 stratum.
    std::vector<int> strata(16, 0);
    for (int i = 0; i < 16; ++i) {
        sampler.start(5, 3, i);
        Vec2 u = sampler.uniform2();
        ++strata[int(u.y() * 4) * 4 + int(u.x() * 4)];
    }
    for (int c : strata) EXPECT_EQ(c, 1);
}

TEST(ZSobol, SameImageOnAnyThreadCountAndLowerErrorPerSample) {
    Scene scene = sphere_on_floor(false);
    Accel accel(scene);
    EnvLight light(sunny_sky(64, 50, 5), 0.3f);
    Camera cam = camera_at(Vec3(0.5f, 1.0f, 4.5f), Vec3(0, -0.3f, 0), 0.8f);
    RenderSettings s;
    s.width = 24, s.height = 16, s.quiet = true, s.pattern = SamplePattern::ZSobol, s.spp = 8;
    Image one, many;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        one = PathIntegrator(accel, light, s).render(cam).color;
    }
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 4);
        many = PathIntegrator(accel, light, s).render(cam).color;
    }
    EXPECT_EQ(one.pixels, many.pixels);
    RenderSettings r = s;
    r.pattern = SamplePattern::Random, r.spp = 4096, r.seed = 99;
    const Image reference = PathIntegrator(accel, light, r).render(cam).color;
    for (int spp : {4, 16, 64}) {
        double e[2];
        for (int k = 0; k < 2; ++k) {
            RenderSettings t = s;
            t.spp = spp, t.pattern = k ? SamplePattern::ZSobol : SamplePattern::Random;
            e[k] = relative_mse(PathIntegrator(accel, light, t).render(cam).color, reference);
        }
        std::printf("%3d spp: relative MSE random %.5f, sobol %.5f (%.2fx)\n", spp, e[0], e[1], e[0] / e[1]);
        EXPECT_LT(e[1], 0.85 * e[0]) << spp << " spp";
    }
}

}  // namespace
}  // namespace dynsky
