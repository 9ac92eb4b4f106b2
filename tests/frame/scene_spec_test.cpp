// Camera overrides of the scene spec (--look-at, --fov) and orthographic glTF cameras, rendered.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>

#include "frame/scene_spec.h"
#include "renderer/integrator.h"
#include "sky/fisheye.h"
#include "tests/test_support.h"
#include "util/error.h"

namespace dynsky {
namespace {

std::shared_ptr<SkyImage> gradient_sky(int n) {
    auto sky = std::make_shared<SkyImage>(n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            Vec2 uv = fisheye::pixel_center_uv(i, j, n);
            if (uv.squaredNorm() > 1) continue;
            Vec3d w = fisheye::direction_from_uv(uv.x(), uv.y());
            sky->set_pixel(i, j,
                           Color(0.3f, 0.45f, 0.9f) * float(0.4 + 0.6 * w.y()) + Color::Constant(float(w.x() > 0.5)));
        }
    return sky;
}

// A glTF file with the Lambert wall and two cameras: perspective at eye (0, 2, 4) pitched down to
// look at the origin (a rotation about X written as a quaternion), and orthographic on +Z.
std::string write_camera_gltf(const std::string& dir, float yfov, float ymag) {
    const float positions[] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
    const uint16_t indices[] = {0, 1, 2, 0, 2, 3};
    std::ofstream bin(dir + "/wall.bin", std::ios::binary);
    bin.write(reinterpret_cast<const char*>(positions), sizeof positions);
    bin.write(reinterpret_cast<const char*>(indices), sizeof indices);
    bin.close();
    double pitch = -std::atan2(2.0, 4.0);  // look down from (0, 2, 4) to the origin
    char json[4096];
    std::snprintf(json, sizeof json, R"({
 "asset": {"version": "2.0"},
 "scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
 "nodes": [{"mesh": 0},
           {"camera": 0, "translation": [0, 2, 4], "rotation": [%.9f, 0, 0, %.9f]},
           {"camera": 1, "translation": [0, 0, 4]}],
 "cameras": [{"type": "perspective", "perspective": {"yfov": %.9f, "znear": 0.01}},
             {"type": "orthographic", "orthographic": {"xmag": %.9f, "ymag": %.9f, "znear": 0.01, "zfar": 100}}],
 "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
 "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0}}],
 "buffers": [{"uri": "wall.bin", "byteLength": 60}],
 "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 12}],
 "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0]},
               {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}]
})",
                  std::sin(pitch / 2), std::cos(pitch / 2), yfov, ymag, ymag);
    std::ofstream(dir + "/cameras.gltf") << json;
    return dir + "/cameras.gltf";
}

// A pose where every mesh is hidden by a scale of 0 (how animations hide objects: a pop-in starts
// so) is the sky and the ground seen from the file's camera, with a warning; `animate --play-anim`
// stopped at such a first frame ("no triangles to render"). Without a camera nothing says where to
// look: an error that says why.
TEST(RenderCamera, APoseWithEveryMeshHiddenShowsTheSkyFromTheFilesCamera) {
    std::string dir = test::temp_dir("camera-hidden");
    const std::string path = write_camera_gltf(dir, 0.6f, 1.5f);
    std::string json;
    {
        std::ifstream in(path);
        json.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    auto replaced = [](std::string s, const std::string& from, const std::string& to) {
        const size_t at = s.find(from);
        EXPECT_NE(at, std::string::npos) << from;
        return at == std::string::npos ? s : s.replace(at, from.size(), to);
    };
    const std::string hidden = replaced(json, R"("nodes": [{"mesh": 0},)",
                                        R"("nodes": [{"mesh": 0, "scale": [0, 0, 0]},)");
    std::ofstream(dir + "/hidden.gltf") << hidden;
    std::ofstream(dir + "/hidden_nocam.gltf")
        << replaced(hidden, R"("scenes": [{"nodes": [0, 1, 2]}])", R"("scenes": [{"nodes": [0]}])");
    const LoadedScene seen = load_scene(SceneSpec{dir + "/hidden.gltf", 0, 0.3f, {}, 0, -1, ""}, 1.0f);
    EXPECT_TRUE(seen.scene.instances.empty());
    EXPECT_EQ(seen.scene.hidden_meshes, 1);
    try {
        load_scene(SceneSpec{dir + "/hidden_nocam.gltf", 0, 0.3f, {}, 0, -1, ""}, 1.0f);
        ADD_FAILURE() << "a hidden scene without a camera loaded";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("no camera to look from"), std::string::npos) << e.what();
    }
}

TEST(RenderCamera, LookAtOverrideEqualsTheEquivalentGltfCamera) {
    std::string dir = test::temp_dir("camera");
    const float yfov = 0.6f;
    std::string path = write_camera_gltf(dir, yfov, 1.5f);
    SceneSpec file_camera{path, 0, 0.3f, {}, 0, -1, ""};
    SceneSpec look_at{path, 0, 0.3f, {0, 2, 4, 0, 0, 0}, yfov * 180 / kPiD, -1, ""};
    LoadedScene a = load_scene(file_camera, 1.0f), b = load_scene(look_at, 1.0f);
    EXPECT_LT((a.camera.camera_to_world.matrix() - b.camera.camera_to_world.matrix()).cwiseAbs().maxCoeff(), 1e-6f);
    EXPECT_NEAR(a.camera.yfov, b.camera.yfov, 1e-6f);
    Accel accel(a.scene);
    EnvLight light(gradient_sky(64), 0.3f);
    RenderSettings s;
    s.width = 24, s.height = 24, s.spp = 8, s.quiet = true;
    s.aovs.depth = true;
    RenderResult ra = PathIntegrator(accel, light, s).render(a.camera);
    RenderResult rb = PathIntegrator(accel, light, s).render(b.camera);
    // Cameras equal to float rounding: the same paths except where a ray grazes an edge.
    int differ = 0;
    for (size_t i = 0; i < ra.color.pixels.size(); ++i)
        differ += std::abs(ra.color.pixels[i] - rb.color.pixels[i]) > 1e-4f * (1 + std::abs(ra.color.pixels[i]));
    EXPECT_LE(differ, 3) << "of " << ra.color.pixels.size();
    // The view is pitched down: the centre pixel sees the origin at the distance to the eye.
    EXPECT_NEAR(ra.depth.at(12, 12, 0), std::sqrt(20.0f), 0.2f);
    // --fov alone changes the field of view of the file's camera; bad overrides are errors.
    SceneSpec fov_only{path, 0, 0.3f, {}, 30, -1, ""};
    EXPECT_NEAR(load_scene(fov_only, 1.0f).camera.yfov, 30 * kPi / 180, 1e-6f);
    EXPECT_THROW(load_scene(SceneSpec{path, 0, 0.3f, {0, 2, 4}, 0, -1, ""}, 1.0f), Error);
    EXPECT_THROW(load_scene(SceneSpec{path, 0, 0.3f, {1, 1, 1, 1, 1, 1}, 0, -1, ""}, 1.0f), Error);
    // An eye 1e19 m out made rays Embree aborted on (exit 134); 1e20 apart read as "the same point".
    for (const std::vector<double>& far : {std::vector<double>{0, 0, 1e19, 0, 0, 0}, {1e20, 0, 0, 0, 0, 0}}) {
        try {
            load_scene(SceneSpec{path, 0, 0.3f, far, 0, -1, ""}, 1.0f);
            ADD_FAILURE() << "a look-at eye at " << far[0] + far[2] << " m was accepted";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("within 1e+08 m"), std::string::npos) << e.what();
        }
    }
    EXPECT_THROW(load_scene(SceneSpec{path, 0, 0.3f, {}, 180, -1, ""}, 1.0f), Error);
    EXPECT_THROW(load_scene(SceneSpec{path, 1, 0.3f, {}, 40, -1, ""}, 1.0f), Error);  // --fov on an orthographic camera
}

// --camera N is the file's N-th camera: with cameras A, B and C of which only B and C are placed
// (and the placed ones listed in another order), 1 is B and 2 is C; A has no place to look from.
TEST(RenderCamera, CameraIndexIsTheFilesCamerasArray) {
    std::string dir = test::temp_dir("camera_index");
    std::string path = write_camera_gltf(dir, 0.6f, 1.5f);
    std::string json;
    {
        std::ifstream in(path);
        json.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    // A new camera 0, "A", placed nowhere; the perspective one becomes 1 ("C"), the orthographic one 2 ("B").
    auto replace = [&](const std::string& from, const std::string& to) {
        const size_t at = json.find(from);
        ASSERT_NE(at, std::string::npos) << from;
        json.replace(at, from.size(), to);
    };
    replace("{\"camera\": 1,", "{\"camera\": 2,");
    replace("{\"camera\": 0,", "{\"camera\": 1,");
    replace("\"cameras\": [{\"type\": \"perspective\"",
            "\"cameras\": [{\"name\": \"A\", \"type\": \"perspective\", \"perspective\": {\"yfov\": 1.0, "
            "\"znear\": 0.1}}, {\"type\": \"perspective\"");
    // The array is now A, perspective, orthographic: name them B and C in the order placed above.
    replace("{\"type\": \"perspective\", \"perspective\": {\"yfov\": 0.6",
            "{\"name\": \"C\", \"type\": \"perspective\", \"perspective\": {\"yfov\": 0.6");
    replace("{\"type\": \"orthographic\"", "{\"name\": \"B\", \"type\": \"orthographic\"");
    const size_t end_of_cameras = json.find("]", json.find("\"cameras\""));
    json.insert(end_of_cameras,
                ", {\"name\": \"D\", \"type\": \"perspective\", \"perspective\": {\"yfov\": 1.0, "
                "\"znear\": 0.1}}");
    std::ofstream(path) << json;
    // cameras = [A, C (perspective, on node 1), B (orthographic, on node 2), D]; placed: C, B.
    SceneSpec spec{path, 1, 0.3f, {}, 0, -1, ""};
    EXPECT_EQ(load_scene(spec, 1.0f).camera.name, "C");
    spec.camera = 2;
    EXPECT_EQ(load_scene(spec, 1.0f).camera.name, "B");
    // The default, camera 0, placed nowhere: the first camera placed (a file whose cameras[0] is a
    // spare still renders by default).
    spec.camera = 0;
    EXPECT_EQ(load_scene(spec, 1.0f).camera.name, "C");
    spec.camera = 3;
    try {
        load_scene(spec, 1.0f);
        FAIL() << "camera D has no node, yet it was rendered";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("'D') is not placed on any node"), std::string::npos) << e.what();
    }
    spec.camera = 4;
    try {
        load_scene(spec, 1.0f);
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("the file has 4 camera(s)"), std::string::npos) << e.what();
    }
}

// --look-at keeps the world's +Y as the image's up down to a hair from vertical: two views a degree
// apart near the zenith (or the nadir) are a degree apart in the image too, not half a turn.
TEST(RenderCamera, LookAtUpTurnsSmoothlyThroughNearlyVerticalViews) {
    for (double down : {1.0, -1.0})
        for (double t : {0.2, 0.05, 0.03, 0.01, 1e-3, 1e-5, 1e-7}) {
            const Camera cam = look_at_camera(Vec3(0, 0, 0), Vec3(0, float(down), float(t)), 0.8f);
            const Eigen::Matrix3f r = cam.camera_to_world.linear();
            // Leaning towards +Z while looking up, the image's top is towards -Z (and +Z looking down).
            EXPECT_LT(down * r.col(1).z(), -0.97) << "target (0, " << down << ", " << t << ")";
            EXPECT_NEAR(r.determinant(), 1.0f, 1e-5f);
            EXPECT_NEAR((r.transpose() * r - Eigen::Matrix3f::Identity()).cwiseAbs().maxCoeff(), 0.0f, 1e-5f);
        }
    // Exactly vertical: a fixed up (+Z hint), still a rotation.
    const Eigen::Matrix3f r = look_at_camera(Vec3(0, 0, 0), Vec3(0, 1, 0), 0.8f).camera_to_world.linear();
    EXPECT_NEAR(r.determinant(), 1.0f, 1e-5f);
}

TEST(RenderCamera, OrthographicCameraSeesTheWallAtOneDepthAndItsTrueSize) {
    std::string dir = test::temp_dir("camera");
    const float ymag = 1.6f;  // the wall (half side 1) spans 1 / 1.6 of the half height
    LoadedScene sc = load_scene(SceneSpec{write_camera_gltf(dir, 0.6f, ymag), 1, 0.3f, {}, 0, -1, ""}, 1.0f);
    ASSERT_TRUE(sc.camera.orthographic);
    Accel accel(sc.scene);
    EnvLight light(gradient_sky(64), 0.3f);
    RenderSettings s;
    s.width = 32, s.height = 32, s.spp = 16, s.quiet = true;
    s.aovs.depth = s.aovs.alpha = true;
    RenderResult r = PathIntegrator(accel, light, s).render(sc.camera);
    double covered = 0;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) {
            covered += r.alpha.at(x, y, 0);
            if (r.alpha.at(x, y, 0) == 1.0f) {
                EXPECT_NEAR(r.depth.at(x, y, 0), 4.0f, 1e-5f);  // parallel rays
            }
        }
    // Exact coverage (1 / 1.6)^2 of the image, up to the antialiased edge pixels' sampling noise.
    EXPECT_NEAR(covered / (32 * 32), 1 / (ymag * ymag), 0.01);
}

}  // namespace
}  // namespace dynsky
