#include "renderer/integrator.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "renderer/bsdf.h"
#include "renderer/sampling.h"
#include "renderer/shapes.h"
#include "sky/fisheye.h"
#include "util/interrupt.h"

namespace dynsky {
namespace {

std::shared_ptr<SkyImage> uniform_sky(int n, float value) {
    auto sky = std::make_shared<SkyImage>(n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            if (sky->in_disc(i, j)) sky->set_pixel(i, j, Color::Constant(value));
    return sky;
}

// A sky with a broad bright "sun" (10 degrees across) so BSDF-only sampling converges too.
std::shared_ptr<SkyImage> soft_sun_sky(int n) {
    auto sky = std::make_shared<SkyImage>(n);
    Vec3d sun = fisheye::direction_from_angles(0.6, 2.0);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            Vec2 uv = fisheye::pixel_center_uv(i, j, n);
            if (uv.squaredNorm() > 1) continue;
            Vec3d w = fisheye::direction_from_uv(uv.x(), uv.y());
            Color c = Color(0.3f, 0.45f, 0.9f) * float(0.4 + 0.6 * w.y());
            if (w.dot(sun) > std::cos(5 * kPiD / 180)) c += Color(40, 36, 30);
            sky->set_pixel(i, j, c);
        }
    return sky;
}

Scene sphere_scene(const Material& m, bool with_ground) {
    Scene scene;
    scene.materials.push_back(m);
    add_mesh_instance(&scene, make_sphere_mesh(96, 48, 0), Eigen::Affine3f::Identity(), "sphere");
    if (with_ground) {
        Material g;
        g.base_color = Color(0.6f, 0.6f, 0.6f), g.metallic = 0, g.roughness = 0.9f;
        scene.materials.push_back(g);
        add_mesh_instance(&scene, make_ground_quad_mesh(8, 1), Eigen::Affine3f(Eigen::Translation3f(0, -1, 0)),
                          "ground");
    }
    return scene;
}

// A half-metallic reddish rough material: something of every lobe.
Material copper_like() {
    Material m;
    m.base_color = Color(0.8f, 0.3f, 0.2f), m.metallic = 0.5f, m.roughness = 0.4f;
    return m;
}

// Camera on +Z looking at the origin from far away with a narrow field of view (near-orthographic).
Camera front_camera(float distance, float yfov) {
    Camera c;
    c.yfov = yfov;
    c.camera_to_world = Eigen::Translation3f(0, 0, distance) * Eigen::Matrix3f::Identity();
    return c;
}

double mean_of(const Image& im, int x0, int y0, int x1, int y1, int channel) {
    double s = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) s += im.at(x, y, channel);
    return s / ((x1 - x0) * (y1 - y0));
}

TEST(PathIntegrator, WhiteLambertianFurnaceRendersOne) {
    Material white;
    white.base_color = Color::Ones(), white.metallic = 0, white.roughness = 1, white.specular = 0;
    Scene scene = sphere_scene(white, false);
    Accel accel(scene);
    EnvLight light(uniform_sky(64, 1.0f), 1.0f);  // ground matches: radiance 1 everywhere
    RenderSettings s;
    s.width = 32, s.height = 32, s.spp = 64, s.max_depth = 64, s.rr_start_depth = 64, s.quiet = true;
    PathIntegrator pt(accel, light, s);
    RenderResult r = pt.render(front_camera(6, 0.4f));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean_of(r.color, 0, 0, 32, 32, c), 1.0, 0.01);
    // The sphere's own pixels (centre) too, not just the background.
    EXPECT_NEAR(mean_of(r.color, 10, 10, 22, 22, 1), 1.0, 0.01);
}

// A coarse smooth-shaded mirror in a white furnace reflects 1 everywhere: its shading normals tilt
// far from the facets', and a mirror path sent below the facet used to end there (black wedges,
// minimum 3e-6, mean 0.981) until the shading normal was bent just enough (lifted_shading_normal).
TEST(PathIntegrator, ACoarseSmoothMirrorSphereIsWhiteInAWhiteFurnace) {
    Material mirror;
    mirror.base_color = Color::Ones(), mirror.metallic = 1, mirror.roughness = 0;
    Scene scene;
    scene.materials.push_back(mirror);
    add_mesh_instance(&scene, make_sphere_mesh(8, 4, 0), Eigen::Affine3f::Identity(), "sphere");
    Accel accel(scene);
    EnvLight light(uniform_sky(64, 1.0f), 1.0f);
    RenderSettings s;
    s.width = 48, s.height = 48, s.spp = 64, s.max_depth = 16, s.rr_start_depth = 16, s.quiet = true;
    PathIntegrator pt(accel, light, s);
    RenderResult r = pt.render(front_camera(6, 0.4f));
    double lowest = 1e9, sum = 0;
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 48; ++x) {
            const double v = r.color.at(x, y, 1);
            lowest = std::min(lowest, v), sum += v;
        }
    EXPECT_GT(lowest, 0.9);
    EXPECT_NEAR(sum / (48 * 48), 1.0, 0.005);
}

TEST(PathIntegrator, RoughDielectricLosesOnlyItsSingleScatteringEnergy) {
    Material m;
    m.base_color = Color::Ones(), m.metallic = 0, m.roughness = 0.8f;  // glTF dielectric, F0 = 0.04
    Scene scene = sphere_scene(m, false);
    Accel accel(scene);
    EnvLight light(uniform_sky(64, 1.0f), 1.0f);
    RenderSettings s;
    s.width = 33, s.height = 33, s.spp = 1024, s.max_depth = 8, s.quiet = true;
    PathIntegrator pt(accel, light, s);
    RenderResult r = pt.render(front_camera(40, 0.01f));  // rays almost along the normal at the centre
    double rendered = mean_of(r.color, 15, 15, 18, 18, 0);
    // The model's directional albedo at normal incidence, by quadrature: what a convex object
    // under a uniform unit furnace must reflect. Its shortfall from 1 is the GGX single-scattering loss.
    MetalRoughBsdf bsdf(Color::Ones(), 0.0f, 0.8f);
    const int n = 600;
    double albedo = 0;
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < 2 * n; ++b) {
            float z = (a + 0.5f) / n, phi = 2 * kPi * (b + 0.5f) / (2 * n), rr = safe_sqrt(1 - z * z);
            albedo += bsdf.eval(Vec3(0, 0, 1), Vec3(rr * std::cos(phi), rr * std::sin(phi), z))[0] * z;
        }
    albedo *= 2 * kPiD / (double(n) * 2 * n);
    EXPECT_LT(albedo, 1.0);
    EXPECT_NEAR(rendered, albedo, 0.01 * albedo) << "loss " << 1 - albedo;
    EXPECT_LE(rendered, 1.0 + 0.005);
}

TEST(PathIntegrator, MisLightOnlyAndBsdfOnlyAgreeWithinStandardErrors) {
    for (float roughness : {0.25f, 0.8f}) {
        Material m;
        m.base_color = Color(0.9f, 0.7f, 0.5f), m.metallic = roughness < 0.5f ? 1.0f : 0.0f, m.roughness = roughness;
        Scene scene = sphere_scene(m, true);
        Accel accel(scene);
        EnvLight light(soft_sun_sky(128), 0.3f);
        Camera cam;
        cam.yfov = 0.9f;
        Vec3 eye(0.5f, 1.2f, 4.0f), target(0, -0.3f, 0);
        Vec3 f = (target - eye).normalized(), rt = f.cross(Vec3::UnitY()).normalized(), up = rt.cross(f);
        Eigen::Matrix3f rot;
        rot.col(0) = rt, rot.col(1) = up, rot.col(2) = -f;
        cam.camera_to_world = Eigen::Translation3f(eye) * rot;

        double mean[3], var[3];
        LightStrategy strategies[3] = {LightStrategy::Mis, LightStrategy::LightOnly, LightStrategy::BsdfOnly};
        for (int k = 0; k < 3; ++k) {
            RenderSettings s;
            s.width = 24, s.height = 16, s.spp = 256, s.quiet = true, s.compute_variance = true;
            s.strategy = strategies[k], s.seed = 100 + k;
            RenderResult r = PathIntegrator(accel, light, s).render(cam);
            double sum = 0, v = 0;
            for (int y = 0; y < 16; ++y)
                for (int x = 0; x < 24; ++x) sum += r.color.at(x, y, 1), v += r.variance.at(x, y, 1);
            mean[k] = sum / 384, var[k] = v / (384.0 * 384.0);
        }
        for (int a = 0; a < 3; ++a)
            for (int b = a + 1; b < 3; ++b)
                EXPECT_LT(std::abs(mean[a] - mean[b]), 4 * std::sqrt(var[a] + var[b]))
                    << "strategies " << a << " vs " << b << " roughness " << roughness << ": " << mean[a] << " vs "
                    << mean[b];
        // MIS should not be noisier than the worse of the two (sanity of the weights).
        EXPECT_LE(var[0], std::max(var[1], var[2]));
    }
}

// A tinted glass pane (thin-walled KHR_materials_transmission) 1 m above a Lambertian floor, under a
// uniform sky of radiance 1, seen straight down. Analytic: the floor receives the sky through the
// pane, c (1 - E(mu)), and its own reflection in the pane's underside, E(mu) L_floor, so
// L_floor = a c (1 - E_avg) / (1 - a E_avg) (E_avg the cosine-weighted mean of E); the camera sees
// E(1) + c (1 - E(1)) L_floor. Paths pass the pane with its transmitted share and shadow rays are
// tinted by the same share: counting the sky twice (or not at all) through the pane misses by
// 40-100 %, in MIS and in BSDF-only sampling alike.
TEST(PathIntegrator, ThinGlassPaneOverAFloorMatchesTheAnalyticRadiance) {
    const Color tint(1.0f, 0.6f, 0.3f);
    const float floor_albedo = 0.5f;
    Scene scene;
    Material floor;
    floor.base_color = Color::Constant(floor_albedo), floor.metallic = 0, floor.roughness = 1, floor.specular = 0;
    Material glass;
    glass.base_color = tint, glass.metallic = 0, glass.roughness = 0, glass.transmission = 1;
    scene.materials = {floor, glass};
    add_mesh_instance(&scene, make_ground_quad_mesh(400, 0), Eigen::Affine3f::Identity(), "floor");
    add_mesh_instance(&scene, make_ground_quad_mesh(400, 1), Eigen::Affine3f(Eigen::Translation3f(0, 1, 0)), "pane");
    Accel accel(scene);
    EnvLight light(uniform_sky(64, 1.0f), 1.0f);

    // E(mu): what the pane's specular lobe reflects, 1 - what a white pane transmits.
    MetalRoughBsdf white(Color::Ones(), 0.0f, 0.0f, 1.0f, 1.0f);
    auto reflected = [&](double mu) {
        return 1.0 - white.transmitted(Vec3(float(std::sqrt(1 - mu * mu)), 0, float(mu)))[0];
    };
    double e_avg = 0;
    const int n = 2000;
    for (int i = 0; i < n; ++i) {
        const double mu = (i + 0.5) / n;
        e_avg += 2 * reflected(mu) * mu / n;
    }
    EXPECT_NEAR(e_avg, 0.04 + 0.96 / 21, 0.01);  // Schlick's F0 = 0.04, cosine-weighted

    Camera cam;
    cam.yfov = 0.05f;
    cam.camera_to_world = Eigen::Translation3f(0, 10, 0) * Eigen::AngleAxisf(-kPi / 2, Vec3::UnitX());
    for (LightStrategy strategy : {LightStrategy::Mis, LightStrategy::BsdfOnly}) {
        RenderSettings s;
        s.width = 16, s.height = 16, s.spp = 512, s.max_depth = 32, s.quiet = true, s.strategy = strategy;
        RenderResult r = PathIntegrator(accel, light, s).render(cam);
        for (int c = 0; c < 3; ++c) {
            const double l_floor = floor_albedo * tint[c] * (1 - e_avg) / (1 - floor_albedo * e_avg);
            const double expected = reflected(1.0) + tint[c] * (1 - reflected(1.0)) * l_floor;
            EXPECT_NEAR(mean_of(r.color, 0, 0, 16, 16, c), expected, 0.015 * expected)
                << "channel " << c << (strategy == LightStrategy::Mis ? " (MIS)" : " (BSDF only)");
        }
    }
}

// KHR_materials_unlit: the camera sees the base colour as a surface of that albedo in the open, base x
// E_sky / pi (under a uniform sky of radiance 1, E_sky = pi: the base colour itself, exactly); every
// other ray passes through, so an unlit roof over a Lambert floor leaves the floor at its albedo (an
// opaque roof darkens it), with each light strategy.
TEST(PathIntegrator, UnlitSurfacesAreSeenByTheCameraOnlyAsTheirBaseColour) {
    const float albedo = 0.5f;
    Material floor;
    floor.base_color = Color::Constant(albedo), floor.metallic = 0, floor.roughness = 1, floor.specular = 0;
    Material baked;
    baked.base_color = Color(0.2f, 0.4f, 0.6f), baked.unlit = true;
    Material opaque = floor;
    auto render = [&](const Material& roof, float roof_x, float roof_height, LightStrategy strategy,
                      float sky_radiance = 1.0f) {
        Scene scene;
        scene.materials = {floor, roof};
        add_mesh_instance(&scene, make_ground_quad_mesh(400, 0), Eigen::Affine3f::Identity(), "floor");
        TriangleMesh top = make_ground_quad_mesh(4, 1);
        add_mesh_instance(&scene, top,
                          Eigen::Affine3f(Eigen::Translation3f(roof_x, roof_height, 0) *
                                          Eigen::AngleAxisf(kPi, Vec3::UnitX())),
                          "roof");
        Accel accel(scene);
        EnvLight light(uniform_sky(64, sky_radiance), 1.0f);
        Camera cam;
        cam.yfov = 0.002f;
        cam.camera_to_world = Eigen::Translation3f(0, 10, 0) * Eigen::AngleAxisf(-kPi / 2, Vec3::UnitX());
        RenderSettings s;
        s.width = 4, s.height = 4, s.spp = 1024, s.max_depth = 4, s.quiet = true, s.strategy = strategy;
        return PathIntegrator(accel, light, s).render(cam);
    };
    // Seen: the roof under the camera shows its colour in every pixel, with no noise.
    const RenderResult seen = render(baked, 0, 5, LightStrategy::Mis);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x)
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(seen.color.at(x, y, c), baked.base_color[c], 1e-3f);
    // A sky three times as bright shows it three times as bright.
    const RenderResult brighter = render(baked, 0, 5, LightStrategy::Mis, 3.0f);
    EXPECT_NEAR(mean_of(brighter.color, 0, 0, 4, 4, 2), 3 * baked.base_color[2], 3e-3);
    // Not seen: a roof 1 high beside the camera's view hides a large part of the floor point's sky.
    for (LightStrategy strategy : {LightStrategy::Mis, LightStrategy::BsdfOnly, LightStrategy::LightOnly}) {
        const RenderResult through = render(baked, 2.5f, 1, strategy);
        // Light sampling alone is the noisiest of the three (+-2 % over seeds at this count).
        const double tolerance = strategy == LightStrategy::LightOnly ? 0.03 : 0.01;
        EXPECT_NEAR(mean_of(through.color, 0, 0, 4, 4, 0), albedo, tolerance * albedo) << int(strategy);
        const RenderResult shadowed = render(opaque, 2.5f, 1, strategy);
        EXPECT_LT(mean_of(shadowed.color, 0, 0, 4, 4, 0), 0.9 * albedo);
    }
}

// KHR_lights_punctual over a Lambert floor under a uniform sky of radiance 1: the floor shows a
// (the sky) plus a / pi x E from the light, E = I cos / d^2 (point, spot with its cone) or E cos
// (directional), in the sky's units (candela and lux / 683). Looked at from straight above.
TEST(PathIntegrator, PunctualLightsAddTheirAnalyticIrradiance) {
    const float albedo = 0.5f;
    Material floor;
    floor.base_color = Color::Constant(albedo), floor.metallic = 0, floor.roughness = 1, floor.specular = 0;
    auto radiance_at = [&](const PunctualLight& lamp, float x, LightStrategy strategy, bool with_wall = false) {
        Scene scene;
        scene.materials = {floor};
        add_mesh_instance(&scene, make_ground_quad_mesh(400, 0), Eigen::Affine3f::Identity(), "floor");
        // A small roof halfway between the light and the floor point, beside the camera's rays.
        if (with_wall)
            add_mesh_instance(&scene, make_ground_quad_mesh(0.2f, 0),
                              Eigen::Affine3f(Eigen::Translation3f(0.5f * (lamp.position.x() + x),
                                                                   0.5f * lamp.position.y(), 0) *
                                              Eigen::AngleAxisf(kPi, Vec3::UnitX())),
                              "roof");
        scene.lights = {lamp};
        Accel accel(scene);
        EnvLight light(uniform_sky(64, 1.0f), 1.0f);
        Camera cam;
        cam.yfov = 0.002f;
        cam.camera_to_world = Eigen::Translation3f(x, 10, 0) * Eigen::AngleAxisf(-kPi / 2, Vec3::UnitX());
        RenderSettings s;
        s.width = 4, s.height = 4, s.spp = 1024, s.max_depth = 4, s.quiet = true, s.strategy = strategy;
        RenderResult r = PathIntegrator(accel, light, s).render(cam);
        return Vec3(float(mean_of(r.color, 0, 0, 4, 4, 0)), float(mean_of(r.color, 0, 0, 4, 4, 1)),
                    float(mean_of(r.color, 0, 0, 4, 4, 2)));
    };
    const float h = 2;
    PunctualLight point;
    point.position = Vec3(0, h, 0);
    point.intensity = Color(1.0f, 0.5f, 0.25f) * float(4 * kPi);  // W/sr: 683 x 4 pi cd of white
    for (LightStrategy strategy : {LightStrategy::Mis, LightStrategy::BsdfOnly, LightStrategy::LightOnly}) {
        const Vec3 l = radiance_at(point, 0, strategy);
        for (int c = 0; c < 3; ++c) {
            const double expected = albedo + albedo / kPi * point.intensity[c] / (h * h);
            EXPECT_NEAR(l[c], expected, 0.01 * expected) << "point, channel " << c;
        }
    }
    // Off-axis, within the range's window: E = I cos^3 / h^2 (1 - (d / range)^4).
    PunctualLight ranged = point;
    ranged.range = 5;
    const float x = 1.5f, d = std::hypot(x, h), cos_t = h / d;
    const double window = 1 - std::pow(d / 5.0, 4);
    EXPECT_NEAR(radiance_at(ranged, x, LightStrategy::Mis)[0],
                albedo + albedo / kPi * point.intensity[0] * cos_t / (d * d) * window,
                0.01 * (albedo + albedo / kPi * point.intensity[0] * cos_t / (d * d) * window));
    // A spot pointing down, the point seen between its inner (0.5 rad) and outer (0.8 rad) cones.
    PunctualLight spot = point;
    spot.type = PunctualLight::Type::Spot, spot.direction = Vec3(0, -1, 0);
    spot.cos_inner = std::cos(0.5f), spot.cos_outer = std::cos(0.8f);
    const float xs = h * std::tan(0.65f), ds = std::hypot(xs, h), cs = h / ds;
    const double cone = std::pow((cs - spot.cos_outer) / (spot.cos_inner - spot.cos_outer), 2);
    const double spot_expected = albedo + albedo / kPi * spot.intensity[0] * cone * cs / (ds * ds);
    EXPECT_NEAR(radiance_at(spot, xs, LightStrategy::Mis)[0], spot_expected, 0.01 * spot_expected);
    // Outside its cone a spot adds nothing.
    EXPECT_NEAR(radiance_at(spot, h * std::tan(0.9f), LightStrategy::Mis)[0], albedo, 0.01 * albedo);
    // The sun as a directional light, 60 degrees from the zenith: E cos 60.
    PunctualLight sun;
    sun.type = PunctualLight::Type::Directional;
    sun.direction = Vec3(std::sin(kPi / 3), -std::cos(kPi / 3), 0);
    sun.intensity = Color::Constant(100000.0f / 683);  // 1e5 lux
    const double sun_expected = albedo + albedo / kPi * sun.intensity[0] * 0.5;
    EXPECT_NEAR(radiance_at(sun, 0, LightStrategy::Mis)[1], sun_expected, 0.01 * sun_expected);
    // A roof between a point light and the floor shadows it: the sky's share is left (the roof
    // hides a little of the sky too).
    PunctualLight beside = point;
    beside.position = Vec3(1, h, 0);
    const Vec3 lit = radiance_at(beside, 0, LightStrategy::Mis),
               shadowed = radiance_at(beside, 0, LightStrategy::Mis, true);
    EXPECT_GT(lit[0], 1.5 * albedo);
    EXPECT_NEAR(shadowed[0], albedo, 0.05 * albedo) << "the light must not pass the roof";
}

TEST(PathIntegrator, SameSeedSameImageOnAnyThreadCount) {
    Scene scene = sphere_scene(copper_like(), true);
    Accel accel(scene);
    EnvLight light(soft_sun_sky(64), 0.3f);
    RenderSettings s;
    s.width = 40, s.height = 30, s.spp = 8, s.quiet = true, s.seed = 42;
    Camera cam = frame_bounds_camera(scene.world_bounds(), 4.0f / 3.0f);
    Image one, many;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        one = PathIntegrator(accel, light, s).render(cam).color;
    }
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 4);
        many = PathIntegrator(accel, light, s).render(cam).color;
    }
    ASSERT_EQ(one.pixels.size(), many.pixels.size());
    EXPECT_EQ(0, std::memcmp(one.pixels.data(), many.pixels.data(), one.pixels.size() * sizeof(float)));
    s.seed = 43;
    Image other = PathIntegrator(accel, light, s).render(cam).color;
    EXPECT_NE(0, std::memcmp(one.pixels.data(), other.pixels.data(), one.pixels.size() * sizeof(float)));
}

// A tilted white Lambert quad under a uniform sky over a black ground shows albedo x the sky it sees,
// also when its vertices are stored 3 km out and its node places it back at the origin, as
// exports of surveyed sites do: Embree's rounding then scales with the stored coordinates, and an
// offset counting only the ray's own |o| + t left 28 % of some rays re-hitting their own triangle
// (2.8 % darker).
TEST(PathIntegrator, ATiltedQuadStoredFarOutAndPlacedBackShowsItsAlbedo) {
    const float albedo = 0.8f, sky = 1.0f;
    EnvLight light(uniform_sky(32, sky), 0.0f);
    for (float stored : {0.0f, 3000.0f}) {
        Scene scene;
        Material white;
        white.base_color = Color::Constant(albedo), white.metallic = 0, white.roughness = 1, white.specular = 0;
        scene.materials.push_back(white);
        TriangleMesh quad = make_ground_quad_mesh(20, 0);
        const Eigen::Matrix3f tilt = Eigen::AngleAxisf(0.5f, Vec3(1, 0, 0.3f).normalized()).toRotationMatrix();
        for (Vec3& p : quad.positions) p = tilt * p + Vec3(stored, 0.7f * stored, -stored);
        add_mesh_instance(&scene, quad, Eigen::Affine3f(Eigen::Translation3f(-stored, -0.7f * stored, stored)), "quad");
        Accel accel(scene);
        Camera cam;
        cam.yfov = 0.3f;
        const Vec3 normal = tilt * Vec3(0, 1, 0);
        cam.camera_to_world = Eigen::Translation3f(8.0f * normal) *
                              Eigen::Quaternionf::FromTwoVectors(Vec3(0, 0, -1), -normal).toRotationMatrix();
        RenderSettings s;
        s.width = 16, s.height = 16, s.spp = 64, s.max_depth = 4, s.quiet = true;
        const Image im = PathIntegrator(accel, light, s).render(cam).color;
        // It sees the sky above the horizon and the black ground (albedo 0) below: of the cosine-
        // weighted hemisphere, (1 + cos tilt) / 2 is sky.
        const double expected = albedo * sky * (1 + normal.y()) / 2;
        EXPECT_NEAR(mean_of(im, 0, 0, 16, 16, 1), expected, 0.005 * expected) << "stored " << stored << " m out";
    }
}

// A render asked to stop (an interrupt, util/interrupt.h) ends after its round of samples with the
// image of those samples: the same pixels as a render of that many samples. (The request stays set
// in this test process: other tests do not stop on request.)
TEST(PathIntegrator, ARenderAskedToStopKeepsItsFirstRoundOfSamples) {
    Scene scene = sphere_scene(copper_like(), true);
    Accel accel(scene);
    EnvLight light(soft_sun_sky(64), 0.3f);
    RenderSettings s;
    s.width = 24, s.height = 16, s.quiet = true, s.seed = 7, s.round_spp = 4;
    const Camera cam = frame_bounds_camera(scene.world_bounds(), 1.5f);
    s.spp = 4;
    const RenderResult four = PathIntegrator(accel, light, s).render(cam);
    EXPECT_FALSE(four.stopped);
    s.spp = 1000, s.stop_on_request = true;
    request_stop();
    const RenderResult stopped = PathIntegrator(accel, light, s).render(cam);
    EXPECT_TRUE(stopped.stopped);
    EXPECT_EQ(stopped.rounds, 1);
    ASSERT_EQ(stopped.color.pixels.size(), four.color.pixels.size());
    EXPECT_EQ(0, std::memcmp(stopped.color.pixels.data(), four.color.pixels.data(),
                             four.color.pixels.size() * sizeof(float)));
}

// Rays leave a surface by its position's error bound, not by a fixed share of the distance from
// the origin: from inside a closed white sphere under a bright sky nothing can be seen, whether the
// sphere is 2 m across at the origin, 50 micrometres across (a model authored in millimetres), or
// 0.8 m across 10 km from the origin (georeferenced coordinates). With 1e-4 x max(1, |p|) the rays of
// the far sphere started 1 m outside it, and those of the small one 0.1 mm outside it: both lit.
TEST(PathIntegrator, NoLightLeaksIntoAClosedSphereAtAnyScaleOrDistanceFromTheOrigin) {
    EnvLight light(uniform_sky(32, 10.0f), 1.0f);
    for (const auto& [radius, offset] : {std::pair<float, float>{1.0f, 0.0f}, {2.5e-5f, 0.0f}, {0.4f, 1e4f}}) {
        Scene scene;
        Material white;
        white.base_color = Color::Constant(0.9f), white.metallic = 0, white.roughness = 1;
        scene.materials.push_back(white);
        const Eigen::Affine3f place = Eigen::Translation3f(offset, 0.5f * offset, -offset) * Eigen::Scaling(radius);
        add_mesh_instance(&scene, make_sphere_mesh(48, 24, 0), place, "sphere");
        Accel accel(scene);
        Camera cam;
        cam.yfov = 1.5f;
        cam.camera_to_world = Eigen::Translation3f(offset, 0.5f * offset, -offset) * Eigen::Matrix3f::Identity();
        RenderSettings s;
        s.width = 24, s.height = 16, s.spp = 16, s.max_depth = 6, s.quiet = true;
        const Image im = PathIntegrator(accel, light, s).render(cam).color;
        double sum = 0;
        for (float v : im.pixels) sum += v;
        EXPECT_LT(sum / double(im.pixels.size()), 1e-3) << "radius " << radius << " m, " << offset << " m away";
    }
}

}  // namespace
}  // namespace dynsky
