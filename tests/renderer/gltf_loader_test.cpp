#include "renderer/gltf_json_check.h"
#include "renderer/gltf_loader.h"
#include "renderer/material_eval.h"

#include <gtest/gtest.h>

#include <draco/compression/encode.h>
#include <draco/mesh/triangle_soup_mesh_builder.h>
#include <meshoptimizer.h>
#include <opencv2/imgcodecs.hpp>

#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "tests/test_support.h"
#include "util/color.h"
#include "util/error.h"
#include "util/image.h"

// libtinygltf's base64 encoder (its header declares it only to the library's implementation).
namespace tinygltf {
std::string base64_encode(unsigned char const* bytes, unsigned int length);
}

namespace dynsky {
namespace {

namespace fs = std::filesystem;

using test::read_text;

void write_bytes(const std::string& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
}

std::string scene_path(const std::string& relative) { return test::shared_path("scenes/" + relative); }

// The message of the dynsky::Error that loading `path` throws ("" if it loads).
std::string load_error(const std::string& path) {
    try {
        load_gltf(path);
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

int instances_of(const Scene& s, int group) {
    int n = 0;
    for (const Instance& i : s.instances) n += i.mesh_group == group;
    return n;
}

int group_named(const Scene& s, const std::string& name) {
    for (size_t i = 0; i < s.meshes.size(); ++i)
        if (s.meshes[i].name == name) return int(i);
    return -1;
}

const Material* material_named(const Scene& s, const std::string& name) {
    for (const Material& m : s.materials)
        if (m.name == name) return &m;
    return nullptr;
}

bool has_warning_containing(const Scene& s, const std::string& text) {
    for (const std::string& w : s.warnings)
        if (w.find(text) != std::string::npos) return true;
    return false;
}

// ---------------------------------------------------------------------------------------------
// Real scenes from ../shared/scenes

// The scenes the feature tests below inspect, loaded once per test program (decoding their
// 2048-pixel textures is most of this file's run time). Others are loaded and dropped.
const std::set<std::string> kInspected = {"SimpleInstancing/SimpleInstancing.glb",
                                          "CesiumMilkTruck/CesiumMilkTruck.glb",
                                          "Cameras/Cameras.gltf",
                                          "OrientationTest/OrientationTest.glb",
                                          "EmissiveStrengthTest/EmissiveStrengthTest.glb",
                                          "ClearCoatTest/ClearCoatTest.glb",
                                          "GlassBrokenWindow/GlassBrokenWindow.glb"};

const Scene& inspected_scene(const std::string& relative) {
    static std::map<std::string, Scene> cache;
    auto it = cache.find(relative);
    if (it == cache.end()) it = cache.emplace(relative, load_gltf(scene_path(relative))).first;
    return it->second;
}

// Scene file -> triangle count, as ../shared/scenes/PROVENANCE.md states them.
std::map<std::string, size_t> provenance_triangle_counts() {
    std::string text = read_text(scene_path("PROVENANCE.md"));
    std::map<std::string, size_t> counts;
    std::regex section("^## (\\S+)"), triangles("\\*\\*Triangles:\\*\\* ([0-9,]+)"), path_re("`([^`]+\\.gl(b|tf))`"),
        tile("`([^`]+\\.glb)` ([0-9,]+) tris");
    auto number = [](std::string s) {
        s.erase(std::remove(s.begin(), s.end(), ','), s.end());
        return size_t(std::stoull(s));
    };
    std::istringstream in(text);
    std::string line, folder, file;
    std::smatch m;
    while (std::getline(in, line)) {
        if (std::regex_search(line, m, section)) folder = m[1], file.clear();
        if (line.find("**Repo / commit / path:**") != std::string::npos && std::regex_search(line, m, path_re))
            file = fs::path(m[1].str()).filename().string();
        if (std::regex_search(line, m, triangles) && !file.empty()) counts[folder + "/" + file] = number(m[1]);
        if (line.find("**Tiles:**") != std::string::npos)
            for (auto it = std::sregex_iterator(line.begin(), line.end(), tile); it != std::sregex_iterator(); ++it)
                counts[folder + "/" + (*it)[1].str()] = number((*it)[2].str());
    }
    return counts;
}

TEST(GltfLoader, EverySharedSceneLoadsWithTheTriangleCountProvenanceStates) {
    DYNSKY_REQUIRE_SHARED();
    std::map<std::string, size_t> counts = provenance_triangle_counts();
    // 15 scene folders with one file each, plus the 15 KenneyCityKit tiles.
    ASSERT_EQ(counts.size(), 30u) << "PROVENANCE.md parse";
    for (const auto& [file, triangles] : counts) {
        SCOPED_TRACE(file);
        ASSERT_TRUE(fs::exists(scene_path(file)));
        Scene loaded;
        const Scene& s = kInspected.count(file) ? inspected_scene(file) : (loaded = load_gltf(scene_path(file)));
        EXPECT_EQ(s.triangle_count(), triangles);
        EXPECT_FALSE(s.world_bounds().empty());
        for (const MeshGroup& g : s.meshes)
            for (const TriangleMesh& m : g.primitives) {
                size_t n = m.positions.size();
                ASSERT_EQ(m.normals.size(), n);
                ASSERT_EQ(m.tangents.size(), n);
                for (const auto& uv : m.texcoords) ASSERT_TRUE(uv.empty() || uv.size() == n);
                for (uint32_t i : m.indices) ASSERT_LT(i, n);
                ASSERT_LT(m.material, int(s.materials.size()));
            }
    }
}

TEST(GltfLoader, SimpleInstancingMakesOneInstancePerGpuInstance) {
    DYNSKY_REQUIRE_SHARED();
    const Scene& s = inspected_scene("SimpleInstancing/SimpleInstancing.glb");
    ASSERT_EQ(s.meshes.size(), 1u);
    ASSERT_EQ(s.instances.size(), 125u);
    EXPECT_EQ(instances_of(s, 0), 125);
    // The TRANSLATION accessor spans [0, 10]^3 (its min/max): 5 x 5 x 5 distinct positions.
    Vec3 lo = Vec3::Constant(1e9f), hi = Vec3::Constant(-1e9f);
    std::set<std::tuple<int, int, int>> distinct;
    for (const Instance& i : s.instances) {
        Vec3 t = i.transform.translation();
        lo = lo.cwiseMin(t), hi = hi.cwiseMax(t);
        distinct.insert({int(std::lround(t.x() * 100)), int(std::lround(t.y() * 100)), int(std::lround(t.z() * 100))});
    }
    EXPECT_EQ(distinct.size(), 125u);
    EXPECT_NEAR((lo - Vec3::Zero()).norm(), 0.0f, 1e-5f);
    EXPECT_NEAR((hi - Vec3::Constant(10)).norm(), 0.0f, 1e-5f);
    EXPECT_FALSE(has_warning_containing(s, "EXT_mesh_gpu_instancing"));
}

TEST(GltfLoader, CesiumMilkTruckBuildsTheWheelMeshOnceForTwoNodes) {
    DYNSKY_REQUIRE_SHARED();
    const Scene& s = inspected_scene("CesiumMilkTruck/CesiumMilkTruck.glb");
    ASSERT_EQ(s.meshes.size(), 2u);  // the file's two meshes, each built once
    int wheels = group_named(s, "Wheels");
    ASSERT_GE(wheels, 0);
    EXPECT_EQ(instances_of(s, wheels), 2);
    std::vector<Vec3> where;
    for (const Instance& i : s.instances)
        if (i.mesh_group == wheels) where.push_back(i.transform.translation());
    EXPECT_GT((where[0] - where[1]).norm(), 1.0f);  // front and rear axles
    // Two glTF textures name the same image with the default sampler, both as base colour.
    EXPECT_EQ(s.textures.size(), 1u);
    EXPECT_EQ(material_named(s, "wheels")->base_color_texture.texture,
              material_named(s, "truck")->base_color_texture.texture);
    EXPECT_TRUE(has_warning_containing(s, "animation"));
}

TEST(GltfLoader, CamerasFileGivesItsPerspectiveAndOrthographicCamerasAndGeneratedFlatNormals) {
    DYNSKY_REQUIRE_SHARED();
    std::vector<std::string> warnings;
    Scene s = load_gltf(scene_path("Cameras/Cameras.gltf"), &warnings);  // fresh: checks the warnings argument
    ASSERT_EQ(s.cameras.size(), 2u);
    const Camera& c = s.cameras[0];
    EXPECT_FALSE(c.orthographic);
    EXPECT_NEAR(c.yfov, 0.7f, 1e-6f);
    EXPECT_NEAR(c.aspect_ratio, 1.0f, 1e-6f);
    EXPECT_NEAR((c.camera_to_world.translation() - Vec3(0.5f, 0.5f, 3.0f)).norm(), 0.0f, 1e-6f);
    EXPECT_NEAR((c.camera_to_world.linear() - Eigen::Matrix3f::Identity()).norm(), 0.0f, 1e-6f);
    // The second camera: orthographic, xmag = ymag = 1, at the same place.
    const Camera& o = s.cameras[1];
    EXPECT_TRUE(o.orthographic);
    EXPECT_NEAR(o.ymag, 1.0f, 1e-6f);
    EXPECT_NEAR(o.aspect_ratio, 1.0f, 1e-6f);
    EXPECT_NEAR((o.camera_to_world.translation() - Vec3(0.5f, 0.5f, 3.0f)).norm(), 0.0f, 1e-6f);
    bool camera_warning = false;
    for (const std::string& w : warnings) camera_warning |= w.find("camera") != std::string::npos;
    EXPECT_FALSE(camera_warning);
    EXPECT_EQ(warnings, s.warnings);

    // No NORMAL in the file: flat normals, one per triangle, following its counter-clockwise winding.
    ASSERT_EQ(s.meshes.size(), 1u);
    const TriangleMesh& m = s.meshes[0].primitives[0];
    ASSERT_EQ(m.triangle_count(), 2u);
    ASSERT_EQ(m.normals.size(), m.positions.size());
    for (size_t t = 0; t < m.indices.size(); t += 3) {
        const Vec3 &a = m.positions[m.indices[t]], &b = m.positions[m.indices[t + 1]],
                   &d = m.positions[m.indices[t + 2]];
        Vec3 face = (b - a).cross(d - a).normalized();
        EXPECT_NEAR(std::abs(face.z()), 1.0f, 1e-6f);  // the square lies in z = 0
        for (int k = 0; k < 3; ++k) EXPECT_NEAR((m.normals[m.indices[t + k]] - face).norm(), 0.0f, 1e-6f);
    }
    EXPECT_EQ(s.material(m.material).name, "glTF default");
    // The square's node rotates by -45 degrees about X (quaternion (-0.383, 0, 0, 0.92375)).
    ASSERT_EQ(s.instances.size(), 1u);
    Vec3 y = s.instances[0].transform.linear() * Vec3::UnitY();
    EXPECT_NEAR(std::atan2(y.z(), y.y()), -kPi / 4, 2e-3f);
}

TEST(GltfLoader, OrientationTestNodesMatchTheirKnownPlacements) {
    DYNSKY_REQUIRE_SHARED();
    const Scene& s = inspected_scene("OrientationTest/OrientationTest.glb");
    ASSERT_EQ(s.instances.size(), 13u);
    auto instance = [&](const std::string& mesh) -> const Instance& {
        int g = group_named(s, mesh);
        EXPECT_GE(g, 0) << mesh;
        for (const Instance& i : s.instances)
            if (i.mesh_group == g) return i;
        return s.instances[0];
    };
    // Node translations (TRS nodes and matrix nodes alike).
    const std::pair<const char*, Vec3> placements[] = {{"ArrowMeshX1", Vec3(5, 0, 0)}, {"ArrowMeshX2", Vec3(-5, 0, 0)},
                                                       {"ArrowMeshY1", Vec3(0, 5, 0)}, {"ArrowMeshY2", Vec3(0, -5, 0)},
                                                       {"ArrowMeshZ1", Vec3(0, 0, 5)}, {"ArrowMeshZ2", Vec3(0, 0, -5)}};
    for (const auto& [mesh, t] : placements)
        EXPECT_NEAR((instance(mesh).transform.translation() - t).norm(), 0.0f, 1e-5f) << mesh;
    // Each arrow, rotated by its node, touches its target (targets have identity nodes). A wrong
    // quaternion convention or a transposed matrix points the arrows elsewhere.
    for (const char* axis : {"X1", "X2", "Y1", "Y2", "Z1", "Z2"}) {
        const Instance& arrow = instance(std::string("ArrowMesh") + axis);
        const Instance& target = instance(std::string("TargetMesh") + axis);
        Bounds3 box;
        for (const Vec3& p : s.meshes[size_t(target.mesh_group)].primitives[0].positions)
            box.extend(target.transform * p);
        float closest = 1e9f;
        for (const Vec3& p : s.meshes[size_t(arrow.mesh_group)].primitives[0].positions) {
            Vec3 w = arrow.transform * p;
            closest = std::min(closest, (w - w.cwiseMax(box.lo).cwiseMin(box.hi)).norm());
        }
        EXPECT_LT(closest, 0.02f) << axis;
    }
}

TEST(GltfLoader, EmissiveStrengthMultipliesTheEmissiveFactor) {
    DYNSKY_REQUIRE_SHARED();
    const Scene& s = inspected_scene("EmissiveStrengthTest/EmissiveStrengthTest.glb");
    const Color factor(0.1f, 0.5f, 0.9f);  // every material's emissiveFactor in the file
    for (auto [name, strength] :
         {std::pair<const char*, float>{"Emit1", 1}, {"Emit2", 2}, {"Emit4", 4}, {"Emit8", 8}, {"Emit16", 16}}) {
        const Material* m = material_named(s, name);
        ASSERT_NE(m, nullptr) << name;
        EXPECT_NEAR((m->emissive - factor * strength).matrix().norm(), 0.0f, 1e-5f) << name;
    }
}

TEST(GltfLoader, ClearCoatTestReadsItsCoatsAndSharesTextures) {
    DYNSKY_REQUIRE_SHARED();
    const Scene& s = inspected_scene("ClearCoatTest/ClearCoatTest.glb");
    // The coats are read; only the coat's own normal map is not (said once per material).
    EXPECT_FALSE(has_warning_containing(s, "'KHR_materials_clearcoat' is not supported"));
    EXPECT_TRUE(has_warning_containing(s, "clearcoatNormalTexture is not read"));
    EXPECT_FLOAT_EQ(material_named(s, "Simple_Coated")->clearcoat, 1.0f);
    EXPECT_FLOAT_EQ(material_named(s, "Simple_Coated")->clearcoat_roughness, 0.03f);
    EXPECT_FLOAT_EQ(material_named(s, "Simple_Base")->clearcoat, 0.0f);
    EXPECT_TRUE(material_named(s, "Partial_Coated")->clearcoat_texture.present());
    EXPECT_TRUE(material_named(s, "RoughVariations_Coated")->clearcoat_roughness_texture.present());
    // 10 glTF textures over 6 images; the core slots use images 1 (base colour), 2 (metal-rough),
    // 3 and 4 (normal maps, image 3 through four different glTF textures) and 5 (emissive), the
    // coats image 0 (linear) and the metal-rough image again: 6 distinct (image, sampler, colour
    // space) combinations.
    EXPECT_EQ(s.textures.size(), 6u);
    int shared = material_named(s, "BaseNorm_Base")->normal_texture.texture;
    EXPECT_GE(shared, 0);
    for (const char* name : {"BaseNorm_Coated", "SharedNorm_Base", "SharedNorm_Coating"})
        EXPECT_EQ(material_named(s, name)->normal_texture.texture, shared) << name;
    EXPECT_NE(material_named(s, "CoatNorm_Coating")->normal_texture.texture, shared);
    EXPECT_EQ(material_named(s, "Partial_Coating")->alpha_mode, AlphaMode::Blend);
    EXPECT_TRUE(material_named(s, "LabelMaterial")->emissive_texture.present());
}

TEST(GltfLoader, GlassBrokenWindowReadsTransmissionAndKeepsAlphaMask) {
    DYNSKY_REQUIRE_SHARED();
    const Scene& s = inspected_scene("GlassBrokenWindow/GlassBrokenWindow.glb");
    EXPECT_FALSE(has_warning_containing(s, "KHR_materials_transmission")) << "read, not ignored";
    const Material* glass = material_named(s, "WindowGlass");
    ASSERT_NE(glass, nullptr);
    EXPECT_FLOAT_EQ(glass->transmission, 1.0f);
    EXPECT_EQ(glass->alpha_mode, AlphaMode::Mask);
    EXPECT_FLOAT_EQ(material_named(s, "WindowFrame")->transmission, 0.0f);
}

// ---------------------------------------------------------------------------------------------
// Synthetic files: a small glTF writer with an external .bin

class MiniGltf {
  public:
    template <typename T>
    int view(const std::vector<T>& data, const std::string& extra = "") {
        while (bin_.size() % 4) bin_.push_back('\0');
        size_t offset = bin_.size();
        bin_.append(reinterpret_cast<const char*>(data.data()), data.size() * sizeof(T));
        views_.push_back("{\"buffer\":0,\"byteOffset\":" + std::to_string(offset) +
                         ",\"byteLength\":" + std::to_string(data.size() * sizeof(T)) + extra + "}");
        return int(views_.size()) - 1;
    }
    int accessor(int view, int component_type, size_t count, const std::string& type, const std::string& extra = "") {
        accessors_.push_back("{" + (view >= 0 ? "\"bufferView\":" + std::to_string(view) + "," : std::string()) +
                             "\"componentType\":" + std::to_string(component_type) +
                             ",\"count\":" + std::to_string(count) + ",\"type\":\"" + type + "\"" + extra + "}");
        return int(accessors_.size()) - 1;
    }
    // Writes NAME.gltf and NAME.bin into dir; `body` holds the remaining top-level members.
    std::string write(const std::string& dir, const std::string& name, const std::string& body) const {
        write_bytes(dir + "/" + name + ".bin", bin_);
        std::string json = "{\"asset\":{\"version\":\"2.0\"}," + body + ",\"buffers\":[{\"uri\":\"" + name +
                           ".bin\",\"byteLength\":" + std::to_string(bin_.size()) + "}],\"bufferViews\":[" +
                           join(views_) + "],\"accessors\":[" + join(accessors_) + "]}";
        std::string path = dir + "/" + name + ".gltf";
        write_bytes(path, json);
        return path;
    }

  private:
    static std::string join(const std::vector<std::string>& v) {
        std::string s;
        for (size_t i = 0; i < v.size(); ++i) s += (i ? "," : "") + v[i];
        return s;
    }
    std::string bin_;
    std::vector<std::string> views_, accessors_;
};

constexpr int kFloat = 5126, kUByte = 5121, kUShort = 5123, kUInt = 5125, kByte = 5120, kShort = 5122;

// A unit quad in z = 0 as 4 vertices (0,0) (1,0) (1,1) (0,1).
std::vector<float> quad_positions() { return {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}; }

std::string one_node_scene(const std::string& meshes, const std::string& extra = "") {
    return "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],\"meshes\":[" + meshes + "]" +
           (extra.empty() ? "" : "," + extra);
}

// A scene its nodes place far from the origin (georeferenced site coordinates) is moved near it,
// by whole metres, before its transforms are rounded to float: its camera with it. 1000 km out a
// float resolves 6 cm, and a room rendered there was lit through its walls.
TEST(GltfLoader, AScenePlacedFarOutByItsNodesIsMovedNearTheOrigin) {
    std::string dir = test::temp_dir("gltf");
    for (double far : {0.0, 2.5e6}) {
        MiniGltf g;
        const int pos = g.accessor(g.view(quad_positions()), kFloat, 4, "VEC3");
        const int idx = g.accessor(g.view(std::vector<uint16_t>{0, 1, 2, 0, 2, 3}), kUShort, 6, "SCALAR");
        const std::string mesh = "{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) +
                                 "},\"indices\":" + std::to_string(idx) + "}]}";
        const std::string t = "[" + std::to_string(far + 0.25) + ",3," + std::to_string(-far) + "]";
        const std::string json =
            "\"scene\":0,\"scenes\":[{\"nodes\":[0,1]}],\"nodes\":[{\"mesh\":0,\"translation\":" + t +
            "},{\"camera\":0,\"translation\":[" + std::to_string(far) + ",4," + std::to_string(-far + 5) +
            "]}],\"cameras\":[{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.8,\"znear\":0.1}}],"
            "\"meshes\":[" +
            mesh + "]";
        const Scene s = load_gltf(g.write(dir, "far", json));
        const Eigen::Vector3d& shift = s.origin_shift;  // near the middle of the nodes, whole metres
        if (far > 0) EXPECT_LT((shift - Eigen::Vector3d(far, 0, -far)).cwiseAbs().maxCoeff(), 10) << far;
        else EXPECT_EQ(shift, Eigen::Vector3d::Zero());
        EXPECT_EQ(shift, shift.array().round().matrix().eval());
        ASSERT_EQ(s.instances.size(), 1u);
        const Vec3 at = s.instances[0].transform.translation();
        EXPECT_LT(at.cwiseAbs().maxCoeff(), 10) << far;
        EXPECT_EQ(at.cast<double>() + shift, Eigen::Vector3d(far + 0.25, 3, -far)) << far;
        ASSERT_EQ(s.cameras.size(), 1u);
        const Vec3 eye = s.cameras[0].camera_to_world.translation();
        // Exactly where it was relative to the camera: 0.25 m right of it, 1 m below, 5 m in front.
        EXPECT_EQ(s.instances[0].transform.translation() - eye, Vec3(0.25f, -1, -5)) << far;
    }
}

// A camera's view ignores its node's scale (glTF 2.0, 3.10): under a mirroring scale, its own or a
// parent's, it still looks down the node's -Z with +Y up. Eigen's rotation() of the mirrored
// matrix turned it round to look along +Z, away from what it was placed to see.
TEST(GltfLoader, AMirroringScaleDoesNotTurnACameraRound) {
    std::string dir = test::temp_dir("gltf");
    for (const char* scale : {"[1,1,1]", "[-1,1,1]", "[1,-1,1]", "[2,3,-0.5]", "[-1,-1,1]"}) {
        MiniGltf g;
        g.view(quad_positions());  // (a buffer of at least a byte)
        const std::string json = std::string("\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"scale\":") +
                                 scale +
                                 ",\"children\":[1]},{\"camera\":0,\"translation\":[0,0,3]}],\"cameras\":[{"
                                 "\"type\":\"perspective\",\"perspective\":{\"yfov\":0.8,\"znear\":0.1}}]";
        const Scene s = load_gltf(g.write(dir, "mirror", json));
        ASSERT_EQ(s.cameras.size(), 1u) << scale;
        const Eigen::Matrix3f r = s.cameras[0].camera_to_world.linear();
        EXPECT_NEAR((r * r.transpose() - Eigen::Matrix3f::Identity()).norm(), 0, 1e-5) << scale;
        EXPECT_NEAR(r.determinant(), 1, 1e-5) << scale;  // a rotation, not a mirror
        // The node's -Z and +Y, normalised: what the camera looks along and holds up.
        const std::string sc = scale;
        const float sy = sc == "[1,-1,1]" || sc == "[-1,-1,1]" ? -1.0f : 1.0f;
        const float sz = sc == "[2,3,-0.5]" ? -1.0f : 1.0f;
        EXPECT_NEAR((r * Vec3(0, 0, -1) - Vec3(0, 0, -sz)).norm(), 0, 1e-5) << scale;
        EXPECT_NEAR((r * Vec3(0, 1, 0) - Vec3(0, sy, 0)).norm(), 0, 1e-5) << scale;
    }
}

TEST(GltfLoader, StripsAndFansBecomeTriangleListsAndPointsAreSkipped) {
    std::string dir = test::temp_dir("gltf");
    MiniGltf g;
    // The unit quad in strip order: (0,0) (1,0) (0,1) (1,1).
    const std::vector<float> q = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
    int pos = g.accessor(g.view(q), kFloat, 4, "VEC3");
    int five = g.accessor(g.view(std::vector<float>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, -1, 1, 0}), kFloat, 5, "VEC3");
    std::string prims = "{\"attributes\":{\"POSITION\":" + std::to_string(pos) +
                        "},\"mode\":5},"  // strip, not indexed
                        "{\"attributes\":{\"POSITION\":" +
                        std::to_string(five) +
                        "},\"mode\":6},"  // fan
                        "{\"attributes\":{\"POSITION\":" +
                        std::to_string(pos) +
                        "},\"mode\":0},"  // points
                        "{\"attributes\":{\"POSITION\":" +
                        std::to_string(pos) + "},\"mode\":1}";  // lines
    Scene s = load_gltf(g.write(dir, "modes", one_node_scene("{\"name\":\"m\",\"primitives\":[" + prims + "]}")));
    ASSERT_EQ(s.meshes.size(), 1u);
    ASSERT_EQ(s.meshes[0].primitives.size(), 2u);
    EXPECT_TRUE(has_warning_containing(s, "points and lines"));
    // Flat normals unweld vertices (no NORMAL), so compare positions: strip {0,1,2}, {1,3,2}
    // (glTF 2.0: p_i = {v_i, v_(i+1+i%2), v_(i+2-i%2)}), fan {1,2,0}, {2,3,0}, {3,4,0}.
    auto corners = [](const TriangleMesh& m) {
        std::vector<Vec3> c;
        for (uint32_t i : m.indices) c.push_back(m.positions[i]);
        return c;
    };
    auto v = [&](int i) { return Vec3(q[3 * i], q[3 * i + 1], q[3 * i + 2]); };
    std::vector<Vec3> strip = corners(s.meshes[0].primitives[0]);
    std::vector<Vec3> want_strip = {v(0), v(1), v(2), v(1), v(3), v(2)};
    ASSERT_EQ(strip.size(), want_strip.size());
    for (size_t i = 0; i < strip.size(); ++i) EXPECT_EQ(strip[i], want_strip[i]) << i;
    std::vector<Vec3> fan = corners(s.meshes[0].primitives[1]);
    std::vector<Vec3> five_v = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0), Vec3(-1, 1, 0)};
    std::vector<Vec3> want_fan = {five_v[1], five_v[2], five_v[0], five_v[2], five_v[3],
                                  five_v[0], five_v[3], five_v[4], five_v[0]};
    ASSERT_EQ(fan.size(), want_fan.size());
    for (size_t i = 0; i < fan.size(); ++i) EXPECT_EQ(fan[i], want_fan[i]) << i;
    // Both keep a counter-clockwise winding seen from +Z, so every flat normal is +Z.
    for (const TriangleMesh& m : s.meshes[0].primitives)
        for (const Vec3& n : m.normals) EXPECT_NEAR((n - Vec3::UnitZ()).norm(), 0.0f, 1e-6f);
}

TEST(GltfLoader, ReadsEveryComponentTypeNormalizedOrNot) {
    std::string dir = test::temp_dir("gltf");
    MiniGltf g;
    // KHR_mesh_quantization-style data: SHORT positions (not normalised), BYTE normals and
    // UBYTE texcoords (normalised), USHORT colours (normalised), UINT and UBYTE indices.
    int pos = g.accessor(g.view(std::vector<int16_t>{0, 0, 0, 0, 200, 0, 300, -100, 0}), kShort, 3, "VEC3");
    int nrm = g.accessor(g.view(std::vector<int8_t>{127, 0, 0, 0, -128, 0, 0, 0, 127, 0}), kByte, 3, "VEC3",
                         ",\"normalized\":true");
    int uv = g.accessor(g.view(std::vector<uint8_t>{0, 255, 51, 0, 255, 102, 0, 0}), kUByte, 3, "VEC2",
                        ",\"normalized\":true");
    int col = g.accessor(g.view(std::vector<uint16_t>{65535, 0, 32768, 0, 65535, 0, 0, 0, 65535, 0}), kUShort, 3,
                         "VEC3", ",\"normalized\":true");
    int idx32 = g.accessor(g.view(std::vector<uint32_t>{0, 1, 2}), kUInt, 3, "SCALAR");
    int idx8 = g.accessor(g.view(std::vector<uint8_t>{2, 1, 0, 0}), kUByte, 3, "SCALAR");
    std::string attrs = "\"attributes\":{\"POSITION\":" + std::to_string(pos) + ",\"NORMAL\":" + std::to_string(nrm) +
                        ",\"TEXCOORD_0\":" + std::to_string(uv) + ",\"COLOR_0\":" + std::to_string(col) + "}";
    std::string mesh = "{\"primitives\":[{" + attrs + ",\"indices\":" + std::to_string(idx32) + "},{" + attrs +
                       ",\"indices\":" + std::to_string(idx8) + "}]}";
    Scene s = load_gltf(g.write(dir, "types",
                                one_node_scene(mesh,
                                               "\"extensionsUsed\":[\"KHR_mesh_quantization\"],"
                                               "\"extensionsRequired\":[\"KHR_mesh_quantization\"]")));
    ASSERT_EQ(s.meshes[0].primitives.size(), 2u);
    const TriangleMesh& m = s.meshes[0].primitives[0];
    EXPECT_EQ(m.positions[1], Vec3(0, 200, 0));
    EXPECT_EQ(m.positions[2], Vec3(300, -100, 0));
    EXPECT_NEAR((m.normals[0] - Vec3(1, 0, 0)).norm(), 0.0f, 1e-6f);
    EXPECT_NEAR((m.normals[1] - Vec3(0, -1, 0)).norm(), 0.0f, 1e-6f);  // -128 clamps to -1
    EXPECT_NEAR((m.texcoords[0][0] - Vec2(0, 1)).norm(), 0.0f, 1e-6f);
    EXPECT_NEAR((m.texcoords[0][1] - Vec2(0.2f, 0)).norm(), 0.0f, 1e-6f);
    EXPECT_NEAR((m.texcoords[0][2] - Vec2(1, 0.4f)).norm(), 0.0f, 1e-6f);
    EXPECT_NEAR((m.colors[0] - Vec4(1, 0, 32768.0f / 65535, 1)).norm(), 0.0f, 1e-6f);
    EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2}));
    EXPECT_EQ(s.meshes[0].primitives[1].indices, (std::vector<uint32_t>{2, 1, 0}));
}

TEST(GltfLoader, SparseAccessorsReplaceTheListedElements) {
    std::string dir = test::temp_dir("gltf");
    MiniGltf g;
    int base = g.view(quad_positions());
    int sparse_idx = g.view(std::vector<uint16_t>{3, 1});
    int sparse_val = g.view(std::vector<float>{7, 8, 9, 4, 5, 6});
    std::string sparse = ",\"sparse\":{\"count\":2,\"indices\":{\"bufferView\":" + std::to_string(sparse_idx) +
                         ",\"componentType\":5123},\"values\":{\"bufferView\":" + std::to_string(sparse_val) + "}}";
    int pos = g.accessor(base, kFloat, 4, "VEC3", sparse);
    // A sparse accessor without a bufferView: zeros, then the substitutions.
    int zeros = g.accessor(-1, kFloat, 4, "VEC3", sparse);
    int idx = g.accessor(g.view(std::vector<uint16_t>{0, 1, 2, 0, 2, 3}), kUShort, 6, "SCALAR");
    std::string mesh = "{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) +
                       ",\"NORMAL\":" + std::to_string(zeros) + "},\"indices\":" + std::to_string(idx) + "}]}";
    Scene s = load_gltf(g.write(dir, "sparse", one_node_scene(mesh)));
    const TriangleMesh& m = s.meshes[0].primitives[0];
    EXPECT_EQ(m.positions[0], Vec3(0, 0, 0));
    EXPECT_EQ(m.positions[1], Vec3(4, 5, 6));
    EXPECT_EQ(m.positions[2], Vec3(1, 1, 0));
    EXPECT_EQ(m.positions[3], Vec3(7, 8, 9));
    // NORMAL: (4,5,6) and (7,8,9) normalised at 1 and 3; zero normals at 0 and 2 were repaired.
    EXPECT_NEAR((m.normals[1] - Vec3(4, 5, 6).normalized()).norm(), 0.0f, 1e-6f);
    EXPECT_NEAR((m.normals[3] - Vec3(7, 8, 9).normalized()).norm(), 0.0f, 1e-6f);
    EXPECT_NEAR(m.normals[0].norm(), 1.0f, 1e-5f);
    EXPECT_TRUE(has_warning_containing(s, "normals were zero"));
}

// Writes a 2 x 1 PNG: left texel (1, 128/255, 0, 1), right texel (0, 0, 1, 1).
std::string write_png(const std::string& dir, const std::string& name) {
    Image img(2, 1, 4);
    const float px[8] = {1, 128.0f / 255, 0, 1, 0, 0, 1, 1};
    std::copy(px, px + 8, img.pixels.begin());
    write_image(dir + "/" + name, img);
    return name;
}

TEST(GltfLoader, TexturesAreSharedPerImageSamplerAndColourSpace) {
    std::string dir = test::temp_dir("gltf");
    MiniGltf g;
    int pos = g.accessor(g.view(quad_positions()), kFloat, 4, "VEC3");
    int uv = g.accessor(g.view(std::vector<float>{0, 0, 1, 0, 1, 1, 0, 1}), kFloat, 4, "VEC2");
    int uv1 = g.accessor(g.view(std::vector<float>{0, 0, 2, 0, 2, 2, 0, 2}), kFloat, 4, "VEC2");
    std::string png = write_png(dir, "t.png");
    std::string transform =
        "\"extensions\":{\"KHR_texture_transform\":{\"offset\":[0.25,0.5],\"rotation\":0.3,\"scale\":[2,3],\"texCoord\":1}}";
    std::string body =
        "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":" +
        std::to_string(pos) + ",\"TEXCOORD_0\":" + std::to_string(uv) + ",\"TEXCOORD_1\":" + std::to_string(uv1) +
        "},\"material\":1}]}],"
        "\"images\":[{\"uri\":\"" +
        png +
        "\"}],"
        "\"samplers\":[{\"magFilter\":9728,\"wrapS\":33071,\"wrapT\":33648},{}],"
        "\"textures\":[{\"source\":0,\"sampler\":0},{\"source\":0,\"sampler\":0},{\"source\":0,\"sampler\":1}],"
        "\"materials\":["
        "{\"name\":\"a\",\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0},\"baseColorFactor\":[0.5,0.25,1,0.75],"
        "\"metallicFactor\":0.2,\"roughnessFactor\":0.7},\"normalTexture\":{\"index\":1,\"scale\":0.5},"
        "\"occlusionTexture\":{\"index\":0,\"strength\":0.25},\"emissiveTexture\":{\"index\":1},"
        "\"emissiveFactor\":[1,2,3],\"alphaMode\":\"MASK\",\"alphaCutoff\":0.3,\"doubleSided\":true},"
        "{\"name\":\"b\",\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":2},"
        "\"metallicRoughnessTexture\":{\"index\":1," +
        transform +
        "}},\"alphaMode\":\"BLEND\"}],"
        "\"extensionsUsed\":[\"KHR_texture_transform\",\"KHR_materials_iridescence\"]";
    Scene s = load_gltf(g.write(dir, "textures", body));
    EXPECT_TRUE(has_warning_containing(s, "KHR_materials_iridescence"));
    ASSERT_EQ(s.materials.size(), 2u);
    const Material &a = s.materials[0], &b = s.materials[1];
    // (image 0, sampler 0, sRGB): a.baseColor and a.emissive (textures 0 and 1 are identical);
    // (image 0, sampler 0, linear): a.normal, a.occlusion, b.metallicRoughness;
    // (image 0, default sampler, sRGB): b.baseColor.
    EXPECT_EQ(s.textures.size(), 3u);
    EXPECT_EQ(a.base_color_texture.texture, a.emissive_texture.texture);
    EXPECT_EQ(a.normal_texture.texture, a.occlusion_texture.texture);
    EXPECT_EQ(a.normal_texture.texture, b.metallic_roughness_texture.texture);
    EXPECT_NE(a.base_color_texture.texture, a.normal_texture.texture);
    EXPECT_NE(a.base_color_texture.texture, b.base_color_texture.texture);
    // Colour spaces: the sRGB texture decodes 128/255, the linear one keeps it.
    const Texture& srgb = *s.textures[size_t(a.base_color_texture.texture)];
    const Texture& linear = *s.textures[size_t(a.normal_texture.texture)];
    EXPECT_NEAR(srgb.evaluate(Vec2(0.25f, 0.5f))[1], srgb_to_linear(128.0f / 255), 1e-6f);
    EXPECT_NEAR(linear.evaluate(Vec2(0.25f, 0.5f))[1], 128.0f / 255, 1e-6f);
    // Sampler 0: NEAREST, CLAMP_TO_EDGE in u: u = 0.74 is still the right texel; u = -3 the left.
    EXPECT_NEAR(linear.evaluate(Vec2(0.74f, 0.5f))[2], 1.0f, 1e-6f);
    EXPECT_NEAR(linear.evaluate(Vec2(-3.0f, 0.5f))[0], 1.0f, 1e-6f);
    // Default sampler: LINEAR, REPEAT: u = 0.5 blends both texels half and half.
    EXPECT_NEAR(s.textures[size_t(b.base_color_texture.texture)]->evaluate(Vec2(0.5f, 0.5f))[2], 0.5f, 1e-6f);
    // Factors and modes.
    EXPECT_NEAR((a.base_color - Color(0.5f, 0.25f, 1)).matrix().norm(), 0.0f, 1e-7f);
    EXPECT_FLOAT_EQ(a.base_alpha, 0.75f);
    EXPECT_FLOAT_EQ(a.metallic, 0.2f);
    EXPECT_FLOAT_EQ(a.roughness, 0.7f);
    EXPECT_FLOAT_EQ(a.normal_texture.scale, 0.5f);
    EXPECT_FLOAT_EQ(a.occlusion_texture.scale, 0.25f);
    EXPECT_NEAR((a.emissive - Color(1, 2, 3)).matrix().norm(), 0.0f, 1e-7f);
    EXPECT_EQ(a.alpha_mode, AlphaMode::Mask);
    EXPECT_FLOAT_EQ(a.alpha_cutoff, 0.3f);
    EXPECT_TRUE(a.double_sided);
    EXPECT_EQ(b.alpha_mode, AlphaMode::Blend);
    EXPECT_FALSE(b.double_sided);
    // KHR_texture_transform on b's metallicRoughnessTexture, with its texCoord override.
    EXPECT_EQ(b.metallic_roughness_texture.texcoord, 1);
    EXPECT_NEAR((b.metallic_roughness_texture.uv_transform -
                 texture_transform_matrix(Vec2(0.25f, 0.5f), 0.3f, Vec2(2, 3)))
                    .norm(),
                0.0f, 1e-6f);
    EXPECT_TRUE(a.base_color_texture.uv_transform.isIdentity());
    EXPECT_EQ(s.meshes[0].primitives[0].texcoords[1][2], Vec2(2, 2));
}

TEST(GltfLoader, AGreyPngsTransparentKeyColourIsItsAlpha) {
    // A 2 x 1 grey PNG (grey 0, grey 200) whose tRNS chunk makes grey 0 transparent, as lossless
    // PNG optimisers write a cut-out mask with on/off alpha. OpenCV decoded it opaque (the leaves
    // of a MASK material rendered as a solid black sheet).
    std::string dir = test::temp_dir("gltf");
    write_bytes(
        dir + "/key.png",
        std::string(
            "\x89\x50\x4e\x47\x0d\x0a\x1a\x0a\x00\x00\x00\x0d\x49\x48\x44\x52\x00\x00\x00\x02\x00\x00\x00\x01\x08\x00\x00\x00\x00\xd1\x49\x20\x56\x00\x00\x00\x02\x74\x52\x4e\x53\x00\x00\x76\x93\xcd\x38\x00\x00\x00\x0b\x49\x44\x41\x54\x78\x9c\x63\x60\x38\x01\x00\x00\xcb\x00\xc9\x69\xc8\xc3\x6c\x00\x00\x00\x00\x49\x45\x4e\x44\xae\x42\x60\x82",
            82));
    MiniGltf g;
    int pos = g.accessor(g.view(quad_positions()), kFloat, 4, "VEC3");
    int uv = g.accessor(g.view(std::vector<float>{0, 0, 1, 0, 1, 1, 0, 1}), kFloat, 4, "VEC2");
    std::string body =
        "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":" +
        std::to_string(pos) + ",\"TEXCOORD_0\":" + std::to_string(uv) +
        "},\"material\":0}]}],\"images\":[{\"uri\":\"key.png\"}],"
        "\"samplers\":[{\"magFilter\":9728}],\"textures\":[{\"source\":0,\"sampler\":0}],"
        "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}},"
        "\"alphaMode\":\"MASK\"}]";
    Scene s = load_gltf(g.write(dir, "key", body));
    ASSERT_EQ(s.textures.size(), 1u);
    const Vec4 left = s.textures[0]->evaluate(Vec2(0.25f, 0.5f)), right = s.textures[0]->evaluate(Vec2(0.75f, 0.5f));
    EXPECT_NEAR(left[3], 0.0f, 1e-6f);
    EXPECT_NEAR(right[3], 1.0f, 1e-6f);
    EXPECT_NEAR(right[0], srgb_to_linear(200.0f / 255), 1e-6f);
    EXPECT_NEAR(right[2], right[0], 1e-6f);
}

TEST(GltfLoader, TextureTransformMatrixFollowsTheExtensionSpec) {
    // uv' = T(offset) R(rotation) S(scale) uv, rotation counter-clockwise (u towards -v).
    const float off_u = 0.3f, off_v = -0.2f, rot = 0.7f, su = 1.5f, sv = 0.5f;
    Eigen::Matrix3f m = texture_transform_matrix(Vec2(off_u, off_v), rot, Vec2(su, sv));
    for (Vec2 uv : {Vec2(0, 0), Vec2(1, 0), Vec2(0.3f, 0.8f), Vec2(-2, 5)}) {
        float x = su * uv.x(), y = sv * uv.y();
        Vec2 want(std::cos(rot) * x + std::sin(rot) * y + off_u, -std::sin(rot) * x + std::cos(rot) * y + off_v);
        Vec3 got = m * Vec3(uv.x(), uv.y(), 1);
        EXPECT_NEAR((got.head<2>() - want).norm(), 0.0f, 1e-6f);
        EXPECT_NEAR(got.z(), 1.0f, 1e-7f);
    }
    // The extension's worked example: offset [0, 1], rotation pi/2, scale [0.5, 0.5] "utilizes only
    // the lower left quadrant of the source image" (v down: u in [0, 0.5], v in [0.5, 1]).
    Eigen::Matrix3f ex = texture_transform_matrix(Vec2(0, 1), kPi / 2, Vec2(0.5f, 0.5f));
    for (Vec2 uv : {Vec2(0, 0), Vec2(1, 0), Vec2(0, 1), Vec2(1, 1), Vec2(0.5f, 0.5f)}) {
        Vec3 t = ex * Vec3(uv.x(), uv.y(), 1);
        EXPECT_GE(t.x(), -1e-6f);
        EXPECT_LE(t.x(), 0.5f + 1e-6f);
        EXPECT_GE(t.y(), 0.5f - 1e-6f);
        EXPECT_LE(t.y(), 1.0f + 1e-6f);
    }
    // Its second example, offset [0, 1] and scale [1, -1], flips v.
    Vec3 flipped = texture_transform_matrix(Vec2(0, 1), 0, Vec2(1, -1)) * Vec3(0.2f, 0.1f, 1);
    EXPECT_NEAR((flipped.head<2>() - Vec2(0.2f, 0.9f)).norm(), 0.0f, 1e-6f);
}

TEST(GltfLoader, NodeMatricesAndTrsComposeParentFirst) {
    std::string dir = test::temp_dir("gltf");
    MiniGltf g;
    int pos = g.accessor(g.view(quad_positions()), kFloat, 4, "VEC3");
    // Parent: column-major matrix translating by (10, 0, 0) and scaling x by 2. Child: TRS with
    // translation (0, 1, 0), 90 degrees about +Z, uniform scale 3. Second child: the same mesh.
    std::string body =
        "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":["
        "{\"matrix\":[2,0,0,0, 0,1,0,0, 0,0,1,0, 10,0,0,1],\"children\":[1,2]},"
        "{\"translation\":[0,1,0],\"rotation\":[0,0,0.70710678,0.70710678],\"scale\":[3,3,3],\"mesh\":0},"
        "{\"mesh\":0}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":" +
        std::to_string(pos) + "}}]}]";
    Scene s = load_gltf(g.write(dir, "nodes", body));
    ASSERT_EQ(s.meshes.size(), 1u);
    ASSERT_EQ(s.instances.size(), 2u);
    // Local point (1, 0, 0): child -> scale 3 -> rotate to (0, 3, 0) -> +(0, 1, 0) = (0, 4, 0);
    // parent -> x * 2 + 10 = (10, 4, 0).
    EXPECT_NEAR((s.instances[0].transform * Vec3(1, 0, 0) - Vec3(10, 4, 0)).norm(), 0.0f, 1e-5f);
    EXPECT_NEAR((s.instances[1].transform * Vec3(1, 0, 0) - Vec3(12, 0, 0)).norm(), 0.0f, 1e-5f);
}

// A buffer's base64 that decodes to fewer bytes than its byteLength: said so (tinygltf's own
// "Failed to decode 'uri'" read as if the base64 were broken).
TEST(GltfLoader, ABufferShorterThanItsByteLengthIsSaidSo) {
    const std::string dir = test::temp_dir("gltf");
    write_bytes(dir + "/short.gltf",
                "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":100,"
                "\"uri\":\"data:application/octet-stream;base64,AAAAAA==\"}]}");
    const std::string e = load_error(dir + "/short.gltf");
    EXPECT_NE(e.find("does not decode to its byteLength"), std::string::npos) << e;
    fs::remove_all(dir);
}

TEST(GltfLoader, UnsupportedExtensionsRequiredFailAndUsedWarn) {
    std::string dir = test::temp_dir("gltf");
    MiniGltf g;
    int pos = g.accessor(g.view(quad_positions()), kFloat, 4, "VEC3");
    std::string mesh = "{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) + "}}]}";
    std::string path = g.write(dir, "required",
                               one_node_scene(mesh,
                                              "\"extensionsUsed\":[\"KHR_texture_basisu\"],"
                                              "\"extensionsRequired\":[\"KHR_texture_basisu\"]"));
    std::string e = load_error(path);
    EXPECT_NE(e.find("required.gltf"), std::string::npos) << e;
    EXPECT_NE(e.find("KHR_texture_basisu"), std::string::npos) << e;
    Scene s = load_gltf(g.write(dir, "used",
                                one_node_scene(mesh, "\"extensionsUsed\":[\"KHR_materials_iridescence\"]")));
    EXPECT_TRUE(has_warning_containing(s, "KHR_materials_iridescence"));
    EXPECT_EQ(s.triangle_count(), 1u);  // 4 vertices, not indexed: one triangle, one vertex left over
    EXPECT_TRUE(has_warning_containing(s, "4 vertices (no indices) is not a multiple of 3"));
}

// KHR_materials_transmission: its factor and texture are read; a factor outside [0, 1] is refused;
// rough glass is rendered clear, and the loader says so.
TEST(GltfLoader, TransmissionFactorAndTextureAreReadAndBadFactorsRefused) {
    std::string dir = test::temp_dir("gltf");
    MiniGltf g;
    int pos = g.accessor(g.view(quad_positions()), kFloat, 4, "VEC3");
    int uv = g.accessor(g.view(std::vector<float>{0, 0, 1, 0, 1, 1, 0, 1}), kFloat, 4, "VEC2");
    std::string png = write_png(dir, "t.png");
    auto file = [&](const std::string& name, const std::string& extension, double roughness) {
        std::string mesh = "{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) +
                           ",\"TEXCOORD_0\":" + std::to_string(uv) + "},\"material\":0}]}";
        std::string extra =
            "\"extensionsUsed\":[\"KHR_materials_transmission\"],\"materials\":[{\"name\":\"glass\","
            "\"pbrMetallicRoughness\":{\"metallicFactor\":0,\"roughnessFactor\":" +
            std::to_string(roughness) + "},\"extensions\":{\"KHR_materials_transmission\":" + extension +
            "}}],\"textures\":[{\"source\":0}],\"images\":[{\"uri\":\"" + png + "\"}]";
        return g.write(dir, name, one_node_scene(mesh, extra));
    };
    Scene s = load_gltf(file("glass", "{\"transmissionFactor\":0.8,\"transmissionTexture\":{\"index\":0}}", 0.05));
    const Material* m = material_named(s, "glass");
    ASSERT_NE(m, nullptr);
    EXPECT_FLOAT_EQ(m->transmission, 0.8f);
    EXPECT_TRUE(m->transmission_texture.present());
    EXPECT_FALSE(has_warning_containing(s, "transmission"));
    Scene rough = load_gltf(file("rough", "{\"transmissionFactor\":1}", 0.6));
    EXPECT_TRUE(has_warning_containing(rough, "rendered as clear glass"));
    EXPECT_FLOAT_EQ(load_gltf(file("none", "{}", 0.0)).materials[0].transmission, 0.0f);  // the default factor
    for (const char* bad :
         {"{\"transmissionFactor\":1.5}", "{\"transmissionFactor\":-0.1}", "{\"transmissionFactor\":\"half\"}"}) {
        std::string e = load_error(file("bad", bad, 0.0));
        EXPECT_NE(e.find("bad.gltf"), std::string::npos) << e;
        EXPECT_NE(e.find("transmissionFactor"), std::string::npos) << e;
    }
    EXPECT_NE(load_error(file("badtex", "{\"transmissionFactor\":1,\"transmissionTexture\":{\"index\":7}}", 0.0))
                  .find("texture 7"),
              std::string::npos);
}

// Factors outside their range are said (clamped, as before, but no longer silently), and a broken
// data: URI is not echoed whole into the message (megabytes for a real buffer).
TEST(GltfLoader, ClampedFactorsWarnAndBrokenDataUrisAreQuotedShort) {
    std::string dir = test::temp_dir("gltf");
    MiniGltf g;
    int pos = g.accessor(g.view(quad_positions()), kFloat, 4, "VEC3");
    std::string mesh = "{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) + "},\"material\":0}]}";
    std::vector<std::string> notes;
    load_gltf(g.write(dir, "factors",
                      one_node_scene(mesh,
                                     "\"materials\":[{\"pbrMetallicRoughness\":{\"metallicFactor\":-3,"
                                     "\"roughnessFactor\":7}}]")),
              &notes);
    std::string all;
    for (const std::string& n : notes) all += n + "\n";
    EXPECT_NE(all.find("metallicFactor -3 is outside [0, 1], clamped"), std::string::npos) << all;
    EXPECT_NE(all.find("roughnessFactor 7 is outside [0, 1], clamped"), std::string::npos) << all;
    const std::string uri = "data:application/octet-stream;base64," + std::string(3000, 'A') + "!!";
    write_bytes(dir + "/datauri.gltf",
                "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":4000,\"uri\":\"" + uri + "\"}]}");
    const std::string e = load_error(dir + "/datauri.gltf");
    EXPECT_NE(e.find("datauri.gltf"), std::string::npos) << e;
    EXPECT_LT(e.size(), 600u) << e;
    fs::remove_all(dir);
}

// Textures that together would not fit in memory are refused from their headers, before decoding:
// 18 PNGs of 8192^2 zeros (5 MB of files) would have ended in an out-of-memory kill. Here 1024
// headers of 8192^2 each (a few bytes apiece; 1.4 TB to decode).
TEST(GltfLoader, TexturesBeyondTheMachinesMemoryAreRefusedBeforeDecoding) {
    std::string dir = test::temp_dir("gltf");
    MiniGltf g;
    int pos = g.accessor(g.view(quad_positions()), kFloat, 4, "VEC3");
    int uv = g.accessor(g.view(std::vector<float>{0, 0, 1, 0, 1, 1, 0, 1}), kFloat, 4, "VEC2");
    // A PNG signature and IHDR of 8192 x 8192 RGBA: all the header reader looks at.
    const std::string header("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\0\x20\0\0\0\x20\0\x08\x06\0\0\0\0\0\0\0", 33);
    const int count = 1024;
    std::string images, textures, materials, primitives;
    for (int i = 0; i < count; ++i) {
        write_bytes(dir + "/t" + std::to_string(i) + ".png", header);
        const std::string sep = i ? "," : "";
        images += sep + "{\"uri\":\"t" + std::to_string(i) + ".png\"}";
        textures += sep + "{\"source\":" + std::to_string(i) + "}";
        materials += sep + "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":" + std::to_string(i) + "}}}";
        primitives += sep + "{\"attributes\":{\"POSITION\":" + std::to_string(pos) +
                      ",\"TEXCOORD_0\":" + std::to_string(uv) + "},\"material\":" + std::to_string(i) + "}";
    }
    const std::string path = g.write(dir, "huge",
                                     one_node_scene("{\"primitives\":[" + primitives + "]}",
                                                    "\"images\":[" + images + "],\"textures\":[" + textures +
                                                        "],\"materials\":[" + materials + "]"));
    const std::string e = load_error(path);
    EXPECT_NE(e.find("huge.gltf"), std::string::npos) << e;
    EXPECT_NE(e.find("1024 texture image(s) hold 6.87e+10 texels"), std::string::npos) << e;
    EXPECT_NE(e.find("of memory allows"), std::string::npos) << e;
    // One PNG of 16385^2: beyond stb's header reader, it went unchecked to libpng (5.4 GB for zeros).
    write_bytes(dir + "/t0.png",
                std::string("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\0\x40\x01\0\0\x40\x01\x08\x06\0\0\0\0\0\0\0", 33));
    const std::string one = load_error(
        g.write(dir, "one",
                one_node_scene("{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) +
                                   ",\"TEXCOORD_0\":" + std::to_string(uv) + "},\"material\":0}]}",
                               "\"images\":[{\"uri\":\"t0.png\"}],\"textures\":[{\"source\":0}],\"materials\":[{"
                               "\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}]")));
    EXPECT_NE(one.find("16385 x 16385"), std::string::npos) << one;
    EXPECT_NE(one.find("each side at most 16384"), std::string::npos) << one;
    fs::remove_all(dir);
}

// ---------------------------------------------------------------------------------------------
// Bad input: every case throws dynsky::Error naming the file

TEST(GltfLoader, BadInputThrowsAnErrorNamingTheFile) {
    DYNSKY_REQUIRE_SHARED();
    std::string dir = test::temp_dir("gltf");
    std::string box = read_text(scene_path("Box/Box.glb"));
    ASSERT_GT(box.size(), 1000u);

    struct Case {
        std::string file, bytes, expect;  // expect: a word the message must contain
    };
    std::vector<Case> cases = {
        {"truncated.glb", box.substr(0, box.size() / 2), "truncated"},
        {"tiny.glb", box.substr(0, 10), "truncated"},
        {"invalid.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [ {,] }", "JSON"},
        {"image.glb", read_text(dir + "/" + write_png(dir, "real.png")), "PNG"},
        {"empty.gltf", "", "empty"},
    };
    for (const Case& c : cases) {
        write_bytes(dir + "/" + c.file, c.bytes);
        std::string e = load_error(dir + "/" + c.file);
        EXPECT_NE(e.find(c.file), std::string::npos) << c.file << ": " << e;
        EXPECT_NE(e.find(c.expect), std::string::npos) << c.file << ": " << e;
    }
    std::string e = load_error(dir + "/does_not_exist.glb");
    EXPECT_NE(e.find("does_not_exist.glb"), std::string::npos) << e;
}

TEST(GltfLoader, MissingBinAndTextureFilesAreNamed) {
    std::string dir = test::temp_dir("gltf");
    MiniGltf g;
    int pos = g.accessor(g.view(quad_positions()), kFloat, 4, "VEC3");
    std::string mesh = "{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) + "},\"material\":0}]}";
    std::string tex =
        "\"images\":[{\"uri\":\"gone.png\"}],\"textures\":[{\"source\":0}],"
        "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}]";
    std::string path = g.write(dir, "notex", one_node_scene(mesh, tex));
    std::string e = load_error(path);
    EXPECT_NE(e.find("notex.gltf"), std::string::npos) << e;
    EXPECT_NE(e.find("gone.png"), std::string::npos) << e;
    // An empty file and a PNG cut short are said to be so (not "missing", not "unknown format").
    write_bytes(dir + "/gone.png", "");
    e = load_error(path);
    EXPECT_NE(e.find("is empty (0 bytes)"), std::string::npos) << e;
    write_bytes(dir + "/gone.png", std::string("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\0\0\x10\0\0\0\x10", 24));
    e = load_error(path);
    EXPECT_NE(e.find("a PNG that cannot be decoded (corrupt or cut short"), std::string::npos) << e;
    // One byte of the compressed pixels changed: libpng's CRC check refuses it (stb decoded garbage).
    {
        Image img(16, 16, 3);
        for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = float(i % 7) / 7.0f;
        write_image(dir + "/gone.png", img);
        std::string png = read_text(dir + "/gone.png");
        const size_t idat = png.find("IDAT");
        ASSERT_NE(idat, std::string::npos);
        png[idat + 8] = char(png[idat + 8] ^ 0x5a);
        write_bytes(dir + "/gone.png", png);
        e = load_error(path);
        EXPECT_NE(e.find("gone.png"), std::string::npos) << e;
        EXPECT_NE(e.find("a PNG that cannot be decoded"), std::string::npos) << e;
    }

    path = g.write(dir, "nobin", one_node_scene(mesh, "\"materials\":[{}]"));
    fs::remove(dir + "/nobin.bin");
    e = load_error(path);
    EXPECT_NE(e.find("nobin.gltf"), std::string::npos) << e;
    EXPECT_NE(e.find("nobin.bin"), std::string::npos) << e;
}

// A '+' in a URI's path is a '+' (RFC 3986); tinygltf took it for a space (form encoding), so
// "a+b.bin" was "missing file 'a b.bin'", and with an "a b.bin" beside it that file was read.
TEST(GltfLoader, UrisWithAPlusReadTheFileWithThePlus) {
    std::string dir = test::temp_dir("gltf");
    MiniGltf g;
    int pos = g.accessor(g.view(quad_positions()), kFloat, 4, "VEC3");
    std::string mesh = "{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) + "},\"material\":0}]}";
    std::string tex = "\"images\":[{\"uri\":\"" + write_png(dir, "t+1.png") +
                      "\"}],\"textures\":[{\"source\":0}],"
                      "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}]";
    std::string path = g.write(dir, "a+b", one_node_scene(mesh, tex));
    write_bytes(dir + "/a b.bin", "not this one");
    Scene scene = load_gltf(path);
    EXPECT_GT(scene.triangle_count(), 0u);
    ASSERT_FALSE(scene.textures.empty());
    EXPECT_EQ(scene.textures[0]->name(), "t+1.png");
    // Missing, the texture is named as written, its path as looked for.
    fs::remove(dir + "/t+1.png");
    write_png(dir, "t 1.png");
    std::string e = load_error(path);
    EXPECT_NE(e.find("missing texture file"), std::string::npos) << e;
    EXPECT_NE(e.find("t+1.png"), std::string::npos) << e;
    // A missing buffer says where it was looked for too.
    fs::remove(dir + "/a+b.bin");
    e = load_error(path);
    EXPECT_NE(e.find("missing file 'a+b.bin' (a buffer referenced by the glTF, looked for in '" +
                     fs::absolute(dir).lexically_normal().string() + "')"),
              std::string::npos)
        << e;
    fs::remove_all(dir);
}

TEST(GltfLoader, OutOfRangeAccessorsIndicesAndNodesThrow) {
    std::string dir = test::temp_dir("gltf");
    MiniGltf g;
    int view = g.view(quad_positions());
    int pos = g.accessor(view, kFloat, 4, "VEC3");
    int too_long = g.accessor(view, kFloat, 5, "VEC3");  // 60 bytes from a 48-byte view
    int bad_index = g.accessor(g.view(std::vector<uint16_t>{0, 1, 4}), kUShort, 3, "SCALAR");
    auto mesh = [](int p, int idx) {
        return "{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(p) + "}" +
               (idx >= 0 ? ",\"indices\":" + std::to_string(idx) : std::string()) + "}]}";
    };
    struct Case {
        std::string name, body, expect;
    };
    std::vector<Case> cases = {
        {"accessor_range", one_node_scene(mesh(too_long, -1)), "out of range"},
        {"index_range", one_node_scene(mesh(pos, bad_index)), "index 4"},
        {"no_accessor", one_node_scene(mesh(99, -1)), "accessor 99"},
        {"no_material", one_node_scene("{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":3}]}"),
         "material 3"},
        {"cycle", "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"children\":[1]},{\"children\":[0]}]", "node"},
        {"no_mesh", "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":5}]", "mesh 5"},
    };
    for (const Case& c : cases) {
        std::string e = load_error(g.write(dir, c.name, c.body));
        EXPECT_NE(e.find(c.name + ".gltf"), std::string::npos) << c.name << ": " << e;
        EXPECT_NE(e.find(c.expect), std::string::npos) << c.name << ": " << e;
    }
}

// A bad-input audit's finds: each once loaded silently and rendered nothing, or the wrong thing.
TEST(GltfLoader, ScenesThatWouldRenderNothingOrTheWrongThingAreRefused) {
    std::string dir = test::temp_dir("gltf");
    MiniGltf g;
    const int pos = g.accessor(g.view(quad_positions()), kFloat, 4, "VEC3");
    const int idx = g.accessor(g.view(std::vector<uint16_t>{0, 1, 2, 0, 2, 3}), kUShort, 6, "SCALAR");
    std::vector<float> far = quad_positions();
    for (float& v : far) v = v * 1e19f + 1e20f;
    const int huge = g.accessor(g.view(far), kFloat, 4, "VEC3");
    const int line = g.accessor(g.view(std::vector<float>{0, 0, 0, 1, 0, 0, 2, 0, 0}), kFloat, 3, "VEC3");
    const int ushort_pos = g.accessor(g.view(std::vector<uint16_t>{0, 0, 0, 1, 0, 0, 0, 1, 0, 0}), kUShort, 3, "VEC3");
    auto mesh = [&](int p) {
        return "{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(p) +
               "},\"indices\":" + std::to_string(p == pos ? idx : -1) + "}]}";
    };
    auto plain = [&](int p) { return "{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(p) + "}}]}"; };
    const std::string quad = mesh(pos);
    const std::string camera = "\"cameras\":[{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.8,\"znear\":0.1}}]";
    const std::string textured =
        "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0,\"extensions\":{"
        "\"KHR_texture_transform\":{\"scale\":[1e300,1]}}}}}],\"textures\":[{\"source\":0}],\"images\":[{\"uri\":"
        "\"t.png\"}],\"extensionsUsed\":[\"KHR_texture_transform\"]";
    struct Case {
        std::string name, body, expect;
    };
    const std::vector<Case> cases = {
        {"far_away", one_node_scene(plain(huge)), "from the origin"},
        {"camera_scale0",
         "\"scene\":0,\"scenes\":[{\"nodes\":[0,1]}],\"nodes\":[{\"mesh\":0},{\"camera\":0,\"scale\":[0,0,0]}],"
         "\"meshes\":[" +
             quad + "]," + camera,
         "singular"},
        // A camera at 1e20 m made rays Embree aborts on (an assertion, exit 134).
        {"camera_far",
         "\"scene\":0,\"scenes\":[{\"nodes\":[0,1]}],\"nodes\":[{\"mesh\":0},{\"camera\":0,\"translation\":[1e20,0,0]}],"
         "\"meshes\":[" +
             quad + "]," + camera,
         "camera 'camera 0' is 1e+20 m from the origin"},
        {"scene_index", "\"scene\":5,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],\"meshes\":[" + quad + "]",
         "scene to show is 5"},
        {"integer_positions", one_node_scene(plain(ushort_pos)), "KHR_mesh_quantization"},
        {"transform_inf",
         "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],\"meshes\":[{\"primitives\":[{"
         "\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":0}]}]," +
             textured,
         "KHR_texture_transform is not finite"},
        {"matrix_15",
         "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0,\"matrix\":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0]}],"
         "\"meshes\":[" +
             quad + "]",
         "matrix has 15 numbers, not 16"},
        {"nul_uri",
         "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],\"meshes\":[" + quad +
             "],\"images\":[{\"uri\":\"t.png%00.jpg\"}]",
         "NUL"},
        // tinygltf decodes "%zz" to a NUL: "scene%zz.bin" opened the file "scene".
        {"bad_escape",
         "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],\"meshes\":[" + quad +
             "],\"images\":[{\"uri\":\"t%zz.png\"}]",
         "invalid percent escape"},
    };
    for (const Case& c : cases) {
        std::string e = load_error(g.write(dir, c.name, c.body));
        EXPECT_NE(e.find(c.name + ".gltf"), std::string::npos) << c.name << ": " << e;
        EXPECT_NE(e.find(c.expect), std::string::npos) << c.name << ": " << e;
    }
    // Orthographic views of absurd size and absurd aspect ratios: the camera skipped or its aspect
    // taken from the image, with a warning (an ymag of 1e20 aborted in Embree, 1e-30 drew one colour).
    for (const char* ortho : {"{\"xmag\":1,\"ymag\":1e20,\"znear\":0.1,\"zfar\":10}",
                              "{\"xmag\":1,\"ymag\":1e-30,\"znear\":0.1,\"zfar\":10}"}) {
        std::vector<std::string> notes;
        Scene skipped = load_gltf(g.write(dir, "ortho",
                                          "\"scene\":0,\"scenes\":[{\"nodes\":[0,1]}],\"nodes\":[{\"mesh\":0},"
                                          "{\"camera\":0}],\"meshes\":[" +
                                              quad + "],\"cameras\":[{\"type\":\"orthographic\",\"orthographic\":" +
                                              ortho + "}]"),
                                  &notes);
        EXPECT_TRUE(skipped.cameras.empty()) << ortho;
        EXPECT_NE(std::string(notes.empty() ? "" : notes[0]).find("ymag"), std::string::npos) << ortho;
    }
    std::vector<std::string> notes;
    Scene squashed = load_gltf(
        g.write(dir, "aspect",
                "\"scene\":0,\"scenes\":[{\"nodes\":[0,1]}],\"nodes\":[{\"mesh\":0},{\"camera\":0}],\"meshes\":[" +
                    quad +
                    "],\"cameras\":[{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.8,\"znear\":0.1,"
                    "\"aspectRatio\":1e-30}}]"),
        &notes);
    ASSERT_EQ(squashed.cameras.size(), 1u);
    EXPECT_EQ(squashed.cameras[0].aspect_ratio, 0.0f);  // the image's
    EXPECT_NE(std::string(notes.empty() ? "" : notes[0]).find("aspect ratio"), std::string::npos);

    // Zero-area triangles only: skipped with a warning, so nothing is left to render.
    std::vector<std::string> warnings;
    Scene flat = load_gltf(g.write(dir, "collinear", one_node_scene(plain(line))), &warnings);
    EXPECT_TRUE(flat.instances.empty());
    EXPECT_NE(std::string(warnings.empty() ? "" : warnings[0]).find("zero area"), std::string::npos);
    // Another glTF version.
    std::string text = read_text(g.write(dir, "v3", one_node_scene(quad)));
    text.replace(text.find("\"2.0\""), 5, "\"3.0\"");
    write_bytes(dir + "/v3.gltf", text);
    EXPECT_NE(load_error(dir + "/v3.gltf").find("only glTF 2.x"), std::string::npos);
    fs::remove_all(dir);
}

// tinygltf reads a value of the wrong JSON type as absent: a matrix of strings was identity, a
// mesh index "0" gave "no triangles", a byteOffset of -12 was 0. Each is named by its path.
TEST(GltfLoader, ValuesOfTheWrongTypeOrOutsideTheSpecAreNamedByTheirPath) {
    std::string dir = test::temp_dir("gltf");
    MiniGltf g;
    const int pos = g.accessor(g.view(quad_positions()), kFloat, 4, "VEC3");
    MiniGltf shifted_file = g, strided_file = g, packed_file = g, sparse_file = g;  // each bad accessor alone
    const int shifted = shifted_file.accessor(shifted_file.view(quad_positions()), kFloat, 4, "VEC3",
                                              ",\"byteOffset\":-12");
    const int strided = strided_file.accessor(strided_file.view(quad_positions(), ",\"byteStride\":-12"), kFloat, 4,
                                              "VEC3");
    const int packed = packed_file.accessor(packed_file.view(quad_positions(), ",\"byteStride\":0"), kFloat, 4, "VEC3");
    // A sparse count tinygltf reads as a 32-bit int: 3e9 was reported as -1294967296.
    const int sparse = sparse_file.accessor(sparse_file.view(quad_positions()), kFloat, 4, "VEC3",
                                            ",\"sparse\":{\"count\":3000000000,\"indices\":{\"bufferView\":0,"
                                            "\"componentType\":5123},\"values\":{\"bufferView\":0}}");
    const int uv_int = g.accessor(g.view(std::vector<uint16_t>{0, 0, 1, 0, 1, 1, 0, 1}), kUShort, 4, "VEC2");
    const int uv = g.accessor(g.view(std::vector<float>{0, 0, 1, 0, 1, 1, 0, 1}), kFloat, 4, "VEC2");
    auto mesh = [](int p, const std::string& more = "") {
        return "{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(p) + more + "}}]}";
    };
    auto with_node = [&](const std::string& node) {
        return "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0," + node + "}],\"meshes\":[" +
               mesh(pos) + "]";
    };
    struct Case {
        std::string name, body, expect;
    };
    const std::vector<Case> errors = {
        {"matrix_strings", with_node("\"matrix\":[\"a\",0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]"),
         "nodes[0].matrix[0] is the string \"a\", not a number"},
        {"matrix_projective", with_node("\"matrix\":[1,0,0,0.5,0,1,0,0,0,0,1,0,0,0,0,1]"),
         "nodes[0].matrix has the bottom row (0.5, 0, 0, 1), not (0, 0, 0, 1)"},
        {"rotation_zero", with_node("\"rotation\":[0,0,0,0]"), "nodes[0].rotation is (0, 0, 0, 0), not a rotation"},
        {"mesh_string",
         "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":\"0\"}],\"meshes\":[" + mesh(pos) + "]",
         "nodes[0].mesh is the string \"0\", not an index"},
        {"mesh_decimal",
         "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0.0}],\"meshes\":[" + mesh(pos) + "]",
         "nodes[0].mesh is written 0.0: glTF integers have no decimal point or exponent"},
        {"scene_huge",
         "\"scene\":18446744073709551615,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
         "\"meshes\":[" +
             mesh(pos) + "]",
         "scene is 1.84467e+19, beyond 2^53"},
        {"mesh_2_to_the_32",  // tinygltf's 32-bit int read it as mesh 0
         "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":4294967296}],\"meshes\":[" + mesh(pos) + "]",
         "nodes[0].mesh is 4294967296, beyond any array (indices are below 2^31)"},
        {"light_2_to_the_32",
         "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0,\"extensions\":{\"KHR_lights_punctual\":"
         "{\"light\":4294967296}}}],\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"point\"}]}},"
         "\"meshes\":[" +
             mesh(pos) + "]",
         "nodes[0].extensions.KHR_lights_punctual.light is 4294967296, beyond any array"},
        // Anywhere else an index lies, extensions included (found by its key).
        {"joint_2_to_the_32", with_node("\"skin\":0") + ",\"skins\":[{\"joints\":[0,4294967296]}]",
         "skins[0].joints[1] is 4294967296, beyond any array"},
        {"transform_texcoord_2_to_the_32",
         with_node("\"name\":\"n\"") +
             ",\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0,\"extensions\":"
             "{\"KHR_texture_transform\":{\"texCoord\":4294967296}}}}}],\"textures\":[{\"source\":0}],"
             "\"images\":[{\"uri\":\"t.png\"}]",
         "KHR_texture_transform.texCoord is 4294967296, beyond any array"},
        {"position_2_to_the_32",
         "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],\"meshes\":[" +
             mesh(pos, ",\"NORMAL\":4294967297") + "]",
         "meshes[0].primitives[0].attributes.NORMAL is 4294967297, beyond any array"},
        {"scene_negative",
         "\"scene\":-1,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],\"meshes\":[" + mesh(pos) + "]",
         "scene is -1; it must be at least 0"},

        {"base_colour_short",
         one_node_scene(mesh(pos),
                        "\"materials\":[{\"pbrMetallicRoughness\":{"
                        "\"baseColorFactor\":[1,1]}}]"),
         "materials[0].pbrMetallicRoughness.baseColorFactor has 2 numbers, not 4"},
        {"integer_uv", one_node_scene(mesh(pos, ",\"TEXCOORD_0\":" + std::to_string(uv_int))),
         "TEXCOORD_0 has integer components that are not normalized"},
    };
    for (const Case& c : errors) {
        std::string e = load_error(g.write(dir, c.name, c.body));
        EXPECT_NE(e.find(c.name + ".gltf"), std::string::npos) << c.name << ": " << e;
        EXPECT_NE(e.find(c.expect), std::string::npos) << c.name << ": " << e;
    }
    std::string e = load_error(shifted_file.write(dir, "offset_negative", one_node_scene(mesh(shifted))));
    EXPECT_NE(e.find("accessors[1].byteOffset is -12; it must be at least 0"), std::string::npos) << e;
    e = load_error(sparse_file.write(dir, "sparse_huge", one_node_scene(mesh(sparse))));
    EXPECT_NE(e.find("accessors[1].sparse.count is 3e+09"), std::string::npos) << e;
    e = load_error(strided_file.write(dir, "stride_negative", one_node_scene(mesh(strided))));
    EXPECT_NE(e.find("bufferViews[1].byteStride is -12"), std::string::npos) << e;
    // asset.version as a number said "asset object not found".
    std::string text = read_text(g.write(dir, "version", with_node("\"name\":\"n\"")));
    text.replace(text.find("\"2.0\""), 5, "2.0");
    write_bytes(dir + "/version.gltf", text);
    EXPECT_NE(load_error(dir + "/version.gltf").find("asset.version is 2, not a string"), std::string::npos);

    // What dynsky does not use, or reads leniently: a warning, and the value not used.
    auto warned = [&](const std::string& name, const std::string& body, const std::string& expect) {
        std::vector<std::string> notes;
        Scene s = load_gltf(g.write(dir, name, body), &notes);
        bool found = false;
        for (const std::string& n : notes) found = found || n.find(expect) != std::string::npos;
        EXPECT_TRUE(found) << name << ": no warning containing '" << expect << "'";
        return s;
    };
    auto camera_scene = [&](const std::string& camera) {
        return "\"scene\":0,\"scenes\":[{\"nodes\":[0,1]}],\"nodes\":[{\"mesh\":0},{\"camera\":0}],\"meshes\":[" +
               mesh(pos) + "],\"cameras\":[" + camera + "]";
    };
    // Each camera kept, its value said and not used (the aspect left to the image).
    const std::vector<std::array<std::string, 3>> cameras = {
        {"aspect0", "{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.8,\"znear\":0.1,\"aspectRatio\":0}}",
         "cameras[0].perspective.aspectRatio 0 is not positive"},
        {"znear0", "{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.8,\"znear\":0}}",
         "cameras[0].perspective.znear 0 is not positive"},
        {"zfar_near", "{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.8,\"znear\":50,\"zfar\":1}}",
         "cameras[0].perspective.zfar 1 is not beyond znear 50"},
        {"xmag0", "{\"type\":\"orthographic\",\"orthographic\":{\"xmag\":0,\"ymag\":1,\"znear\":0,\"zfar\":10}}",
         "cameras[0].orthographic.xmag is 0"},
    };
    for (const auto& [name, camera, expect] : cameras) {
        Scene c = warned(name, camera_scene(camera), expect);
        ASSERT_EQ(c.cameras.size(), 1u) << name;
        EXPECT_EQ(c.cameras[0].aspect_ratio, 0.0f) << name;
    }
    Scene f = warned("yfov_tiny",
                     camera_scene("{\"type\":\"perspective\",\"perspective\":{\"yfov\":1e-30,\"znear\":0.1}}"),
                     "yfov 1e-30 rad is outside 0.01 to 179.9 degrees");
    ASSERT_EQ(f.cameras.size(), 1u);
    EXPECT_GT(f.cameras[0].yfov, 0.1f);  // the default
    // The application's own data may hold any number.
    EXPECT_NO_THROW(load_gltf(g.write(dir, "extras", with_node("\"extras\":{\"id\":4294967296}"))));
    std::vector<std::string> notes;
    Scene p = load_gltf(packed_file.write(dir, "stride0", one_node_scene(mesh(packed))), &notes);
    ASSERT_FALSE(notes.empty());
    EXPECT_NE(notes[0].find("bufferViews[1].byteStride is 0"), std::string::npos) << notes[0];
    ASSERT_EQ(p.meshes.size(), 1u);
    EXPECT_EQ(p.meshes[0].primitives[0].positions[2], Vec3(1, 1, 0));  // read as tightly packed
    // A node with both a matrix and TRS (the spec forbids it): the matrix, said.
    warned("matrix_and_trs", with_node("\"matrix\":[1,0,0,0,0,1,0,0,0,0,1,0,2,0,0,1],\"translation\":[0,5,0]"),
           "nodes[0] has both a matrix and translation / rotation / scale");
    // A texture on a UV set the primitive lacks.
    write_png(dir, "t.png");
    warned("uv1_missing",
           one_node_scene("{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) +
                              ",\"TEXCOORD_0\":" + std::to_string(uv) + "},\"material\":0}]}",
                          "\"materials\":[{\"name\":\"m\",\"pbrMetallicRoughness\":{\"baseColorTexture\":{"
                          "\"index\":0,\"texCoord\":1}}}],\"textures\":[{\"source\":0}],\"images\":[{\"uri\":"
                          "\"t.png\"}]"),
           "material 'm' maps a texture with TEXCOORD_1, which the primitive does not have");
    // Fourteen bytes that start like a GIF header said "26400 x 29281 pixels, beyond what dynsky
    // reads": they are no image at all.
    write_bytes(dir + "/em.png", "GIF89a garbage");
    e = load_error(
        g.write(dir, "gif_text",
                one_node_scene("{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) +
                                   ",\"TEXCOORD_0\":" + std::to_string(uv) + "},\"material\":0}]}",
                               "\"materials\":[{\"emissiveFactor\":[1,1,1],\"emissiveTexture\":{\"index\":0}}],"
                               "\"textures\":[{\"source\":0}],\"images\":[{\"uri\":\"em.png\"}]")));
    EXPECT_NE(e.find("not an image, or a corrupt one (a file of 14 bytes whose header says: image is 26400 x 29281"),
              std::string::npos)
        << e;
    fs::remove_all(dir);
}

// Two loads of the same file alike: every instance where the other has it, every mesh's vertices,
// the cameras and the materials.
void expect_same_scene(const Scene& a, const Scene& b, const std::string& what) {
    ASSERT_EQ(a.instances.size(), b.instances.size()) << what;
    ASSERT_EQ(a.meshes.size(), b.meshes.size()) << what;
    for (size_t i = 0; i < a.instances.size(); ++i) {
        EXPECT_EQ(a.instances[i].mesh_group, b.instances[i].mesh_group) << what << " instance " << i;
        EXPECT_TRUE(a.instances[i].transform.matrix().isApprox(b.instances[i].transform.matrix(), 1e-6f))
            << what << " instance " << i;
    }
    for (size_t m = 0; m < a.meshes.size(); ++m) {
        ASSERT_EQ(a.meshes[m].primitives.size(), b.meshes[m].primitives.size()) << what;
        for (size_t p = 0; p < a.meshes[m].primitives.size(); ++p) {
            const TriangleMesh &x = a.meshes[m].primitives[p], &y = b.meshes[m].primitives[p];
            ASSERT_EQ(x.positions.size(), y.positions.size()) << what;
            EXPECT_EQ(x.indices, y.indices) << what;
            for (size_t v = 0; v < x.positions.size(); ++v)
                EXPECT_LT((x.positions[v] - y.positions[v]).norm(), 1e-6f) << what << " mesh " << m << " vertex " << v;
        }
    }
    ASSERT_EQ(a.cameras.size(), b.cameras.size()) << what;
    for (size_t c = 0; c < a.cameras.size(); ++c)
        EXPECT_TRUE(a.cameras[c].camera_to_world.matrix().isApprox(b.cameras[c].camera_to_world.matrix(), 1e-6f))
            << what << " camera " << c;
    EXPECT_EQ(a.materials.size(), b.materials.size()) << what;
    EXPECT_EQ(a.textures.size(), b.textures.size()) << what;
}

// KHR_lights_punctual: each node's light placed by its world transform, shining along its -Z, in
// the sky's radiometric units (candela and lux / 683); impossible lights are refused by name.
// Animations sampled at a time: a LINEAR translation, a LINEAR rotation (slerped), a STEP
// translation, a CUBICSPLINE scale (Hermite with its tangents) and LINEAR morph weights, held at
// their ends; without a time the rest pose, with a warning.
TEST(GltfLoader, AnimationsArePosedAtTheTimeAsked) {
    std::string dir = test::temp_dir("gltf");
    MiniGltf g;
    int pos = g.accessor(g.view(quad_positions()), kFloat, 4, "VEC3");
    int idx = g.accessor(g.view(std::vector<uint16_t>{0, 1, 2, 0, 2, 3}), kUShort, 6, "SCALAR");
    int up = g.accessor(g.view(std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1}), kFloat, 4, "VEC3");
    int times = g.accessor(g.view(std::vector<float>{0, 2}), kFloat, 2, "SCALAR");
    int moves = g.accessor(g.view(std::vector<float>{0, 0, 0, 4, 0, 0}), kFloat, 2, "VEC3");
    const float h = 0.70710678f;  // 0 and 90 degrees about z
    int turns = g.accessor(g.view(std::vector<float>{0, 0, 0, 1, 0, 0, h, h}), kFloat, 2, "VEC4");
    int steps = g.accessor(g.view(std::vector<float>{0, 0, 0, 0, 5, 0}), kFloat, 2, "VEC3");
    // Cubic spline keys: in-tangent, value, out-tangent; scale 1 -> 3 with tangents 0 and 0.
    int spline = g.accessor(g.view(std::vector<float>{0, 0, 0, 1, 1, 1, 0, 0, 0, 0, 0, 0, 3, 3, 3, 0, 0, 0}), kFloat, 6,
                            "VEC3");
    int weights = g.accessor(g.view(std::vector<float>{0, 1}), kFloat, 2, "SCALAR");
    const std::string mesh = "{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) +
                             "},\"indices\":" + std::to_string(idx) +
                             ",\"targets\":[{\"POSITION\":" + std::to_string(up) + "}]}]}";
    auto sampler = [](int in, int out, const char* mode) {
        return "{\"input\":" + std::to_string(in) + ",\"output\":" + std::to_string(out) + ",\"interpolation\":\"" +
               mode + "\"}";
    };
    auto channel = [](int sampler_index, int node, const char* path) {
        return "{\"sampler\":" + std::to_string(sampler_index) + ",\"target\":{\"node\":" + std::to_string(node) +
               ",\"path\":\"" + path + "\"}}";
    };
    const std::string path = g.write(
        dir, "animated",
        "\"scene\":0,\"scenes\":[{\"nodes\":[0,1]}],\"nodes\":[{\"mesh\":0},{\"mesh\":0,\"translation\":[0,0,9]}],"
        "\"meshes\":[" +
            mesh + "],\"animations\":[{\"samplers\":[" + sampler(times, moves, "LINEAR") + "," +
            sampler(times, turns, "LINEAR") + "," + sampler(times, steps, "STEP") + "," +
            sampler(times, spline, "CUBICSPLINE") + "," + sampler(times, weights, "LINEAR") + "],\"channels\":[" +
            channel(0, 0, "translation") + "," + channel(1, 0, "rotation") + "," + channel(2, 1, "translation") + "," +
            channel(3, 1, "scale") + "," + channel(4, 1, "weights") + "]}]");
    auto corner = [](const Scene& s, int node) {  // where the quad's corner (1, 0, 0) lands
        const Instance& in = s.instances.at(size_t(node));
        const TriangleMesh& m = s.meshes[size_t(in.mesh_group)].primitives[0];
        return Vec3(in.transform * m.positions[m.indices[1]]);
    };
    Scene rest = load_gltf(path);
    EXPECT_TRUE(has_warning_containing(rest, "1 animation(s) not played"));
    EXPECT_LT((corner(rest, 1) - Vec3(1, 0, 9)).norm(), 1e-5f);
    Scene mid = load_gltf(path, nullptr, 1.0);
    EXPECT_FALSE(has_warning_containing(mid, "animation"));
    // Node 0 at 1 s: moved to (2, 0, 0), turned 45 degrees: (1, 0, 0) -> (2 + cos 45, sin 45, 0).
    EXPECT_LT((corner(mid, 0) - Vec3(2 + h, h, 0)).norm(), 1e-4f) << corner(mid, 0).transpose();
    // Node 1 at 1 s: STEP holds (0, 0, 0); the spline's midpoint with flat tangents is 2; the morph
    // weight 0.5 lifts the corner by 0.5 before the scale: (2, 0, 1).
    EXPECT_LT((corner(mid, 1) - Vec3(2, 0, 1)).norm(), 1e-4f) << corner(mid, 1).transpose();
    Scene late = load_gltf(path, nullptr, 50.0);  // held at the last keys
    EXPECT_LT((corner(late, 0) - Vec3(4, 1, 0)).norm(), 1e-4f) << corner(late, 0).transpose();
    EXPECT_LT((corner(late, 1) - Vec3(3, 5, 3)).norm(), 1e-4f) << corner(late, 1).transpose();
    // Posed again and again from one load (animate --play-anim): as loaded at each time.
    AnimatedGltf animated(path);
    for (double t : {1.0, 50.0, 0.0, 0.25})
        expect_same_scene(animated.pose(t), load_gltf(path, nullptr, t), "at " + std::to_string(t) + " s");
    // A frame a rounding under the last key (24 fps, the key at Blender's frame 8: t = 1/3 against
    // the float 0.33333334): the last key's value, read within the samples (it read past them; the
    // sanitized suite catches that).
    int third = g.accessor(g.view(std::vector<float>{0, 1.0f / 3.0f}), kFloat, 2, "SCALAR");
    const std::string last_key =
        g.write(dir, "last_key",
                "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],\"meshes\":[" + mesh +
                    "],\"animations\":[{\"samplers\":[" + sampler(third, moves, "LINEAR") + "," +
                    sampler(third, spline, "CUBICSPLINE") + "],\"channels\":[" + channel(0, 0, "translation") + "," +
                    channel(1, 0, "scale") + "]}]");
    EXPECT_LT((corner(load_gltf(last_key, nullptr, 1.0 / 3.0), 0) - Vec3(7, 0, 0)).norm(), 1e-3f);
    // Morph weights animated on a mesh without targets, or on a node without a mesh: nothing to
    // move, said (ignored without a word, where other channels that do nothing warn).
    const std::string plain_mesh = "{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) +
                                   "},\"indices\":" + std::to_string(idx) + "}]}";
    const Scene idle = load_gltf(
        g.write(dir, "no_targets",
                "\"scene\":0,\"scenes\":[{\"nodes\":[0,1]}],\"nodes\":[{\"mesh\":0},{\"translation\":[0,1,0]}],"
                "\"meshes\":[" +
                    plain_mesh + "],\"animations\":[{\"samplers\":[" + sampler(times, weights, "LINEAR") +
                    "],\"channels\":[" + channel(0, 0, "weights") + "," + channel(0, 1, "weights") + "]}]"),
        nullptr, 1.0);
    EXPECT_TRUE(has_warning_containing(idle, "node 0, whose mesh has no morph targets: nothing to move"));
    EXPECT_TRUE(has_warning_containing(idle, "node 1, which has no mesh: nothing to move"));
    fs::remove_all(dir);
}

// A file with several animations (actions exported from Blender: Idle, Walk, Run) plays them all
// at once unless --animation picks one, by name or index, and says so; a name it lacks is refused
// with the list it has.
TEST(GltfLoader, OneAnimationOfSeveralPlaysByNameOrIndex) {
    std::string dir = test::temp_dir("gltf");
    MiniGltf g;
    int pos = g.accessor(g.view(quad_positions()), kFloat, 4, "VEC3");
    int idx = g.accessor(g.view(std::vector<uint16_t>{0, 1, 2, 0, 2, 3}), kUShort, 6, "SCALAR");
    int times = g.accessor(g.view(std::vector<float>{0, 2}), kFloat, 2, "SCALAR");
    int along_x = g.accessor(g.view(std::vector<float>{0, 0, 0, 4, 0, 0}), kFloat, 2, "VEC3");
    int along_y = g.accessor(g.view(std::vector<float>{0, 0, 0, 0, 6, 0}), kFloat, 2, "VEC3");
    auto animation = [&](const char* name, int out) {
        return std::string("{\"name\":\"") + name + "\",\"samplers\":[{\"input\":" + std::to_string(times) +
               ",\"output\":" + std::to_string(out) +
               "}],\"channels\":[{\"sampler\":0,\"target\":{\"node\":0,"
               "\"path\":\"translation\"}}]}";
    };
    const std::string path =
        g.write(dir, "two_actions",
                "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],\"meshes\":[{\"primitives\":[{"
                "\"attributes\":{\"POSITION\":" +
                    std::to_string(pos) + "},\"indices\":" + std::to_string(idx) + "}]}],\"animations\":[" +
                    animation("Walk", along_x) + "," + animation("Jump", along_y) + "]");
    auto origin = [](const Scene& s) { return Vec3(s.instances.at(0).transform * Vec3(0, 0, 0)); };
    const Scene both = load_gltf(path, nullptr, 2.0);
    EXPECT_TRUE(has_warning_containing(both, "2 animations play together (0 'Walk', 1 'Jump')"));
    EXPECT_LT((origin(both) - Vec3(0, 6, 0)).norm(), 1e-5f);  // the last one written wins
    const Scene walk = load_gltf(path, nullptr, 2.0, "Walk");
    EXPECT_FALSE(has_warning_containing(walk, "animation"));
    EXPECT_LT((origin(walk) - Vec3(4, 0, 0)).norm(), 1e-5f);
    EXPECT_LT((origin(load_gltf(path, nullptr, 1.0, "1")) - Vec3(0, 3, 0)).norm(), 1e-5f);
    // Picked but not posed (no time): the rest pose, and the warning says how to pose it.
    EXPECT_TRUE(has_warning_containing(load_gltf(path, nullptr, -1, "Walk"), "--animation Walk picking which"));
    AnimatedGltf animated(path, "Walk");
    expect_same_scene(animated.pose(1.5), load_gltf(path, nullptr, 1.5, "Walk"), "Walk at 1.5 s");
    std::string e;
    try {
        load_gltf(path, nullptr, 1.0, "Run");
    } catch (const Error& error) {
        e = error.what();
    }
    EXPECT_NE(e.find("has no animation 'Run' (--animation; its animations: 0 'Walk', 1 'Jump')"), std::string::npos)
        << e;
    // Names need not be unique: the first of that name plays, and the warning names the others (both
    // played, without a word); a name that is also another animation's index goes first, and says so.
    const std::string twice = g.write(
        dir, "twice",
        "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],\"meshes\":[{\"primitives\":[{"
        "\"attributes\":{\"POSITION\":" +
            std::to_string(pos) + "},\"indices\":" + std::to_string(idx) + "}]}],\"animations\":[" +
            animation("Walk", along_x) + "," + animation("0", along_y) + "," + animation("Walk", along_y) + "]");
    const Scene first = load_gltf(twice, nullptr, 2.0, "Walk");
    EXPECT_LT((origin(first) - Vec3(4, 0, 0)).norm(), 1e-5f);
    EXPECT_TRUE(has_warning_containing(first, "2 animations are named 'Walk': animation 0 plays, not 2"));
    const Scene named_zero = load_gltf(twice, nullptr, 2.0, "0");
    EXPECT_LT((origin(named_zero) - Vec3(0, 6, 0)).norm(), 1e-5f);
    EXPECT_TRUE(has_warning_containing(named_zero, "--animation 0 is the name of animation 1, which plays"));
    fs::remove_all(dir);
}

// animate --play-anim poses one file per frame: posing a file loaded once gives what loading it at
// that time gives (transforms, TRS and morph animations, skins), in any order of times, and every
// pose shares the first load's decoded textures.
TEST(AnimatedGltf, PosesAsLoadingAtThatTimeWithTheTexturesDecodedOnce) {
    DYNSKY_REQUIRE_SHARED();
    const std::string truck = test::shared_path("scenes/CesiumMilkTruck/CesiumMilkTruck.glb");
    AnimatedGltf animated(truck);
    Scene first = animated.pose(0.0);
    ASSERT_FALSE(first.textures.empty());
    for (double t : {0.9, 0.0, 2.5, 0.3, 40.0}) {
        const Scene posed = animated.pose(t);
        expect_same_scene(posed, load_gltf(truck, nullptr, t), "CesiumMilkTruck at " + std::to_string(t) + " s");
        for (size_t k = 0; k < posed.textures.size(); ++k)
            EXPECT_EQ(posed.textures[k].get(), first.textures[k].get()) << "texture " << k << " decoded again";
    }
    // The wheels turn: two poses differ.
    const Scene a = animated.pose(0.0), b = animated.pose(0.9);
    bool moved = false;
    for (size_t i = 0; i < a.instances.size(); ++i)
        moved |= !a.instances[i].transform.matrix().isApprox(b.instances[i].transform.matrix(), 1e-4f);
    EXPECT_TRUE(moved);
    EXPECT_THROW(animated.pose(-1.0), Error);
    EXPECT_THROW(animated.pose(std::nan("")), Error);
}

// KHR_draco_mesh_compression: a quad compressed by draco (positions quantised to 14 bits) loads
// as its two triangles with their positions and UVs; a compressed buffer that is not draco is
// refused by name, and so is an attribute id the compressed mesh lacks.
TEST(GltfLoader, DracoCompressedMeshesAreDecoded) {
    std::string dir = test::temp_dir("gltf");
    const float corner[4][3] = {{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {0, 1, 0}};
    const float uv[4][2] = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
    const int tri[2][3] = {{0, 1, 2}, {0, 2, 3}};
    draco::TriangleSoupMeshBuilder builder;
    builder.Start(2);
    const int pos_att = builder.AddAttribute(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32);
    const int uv_att = builder.AddAttribute(draco::GeometryAttribute::TEX_COORD, 2, draco::DT_FLOAT32);
    for (int f = 0; f < 2; ++f) {
        builder.SetAttributeValuesForFace(pos_att, draco::FaceIndex(f), corner[tri[f][0]], corner[tri[f][1]],
                                          corner[tri[f][2]]);
        builder.SetAttributeValuesForFace(uv_att, draco::FaceIndex(f), uv[tri[f][0]], uv[tri[f][1]], uv[tri[f][2]]);
    }
    std::unique_ptr<draco::Mesh> mesh = builder.Finalize();
    ASSERT_TRUE(mesh);
    draco::Encoder encoder;
    encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, 14);
    draco::EncoderBuffer encoded;
    ASSERT_TRUE(encoder.EncodeMeshToBuffer(*mesh, &encoded).ok());
    const std::string bytes(encoded.data(), encoded.size());
    const int pos_id = int(mesh->attribute(pos_att)->unique_id()), uv_id = int(mesh->attribute(uv_att)->unique_id());

    auto write = [&](const std::string& name, const std::string& buffer, int position_id) {
        write_bytes(dir + "/" + name + ".bin", buffer);
        const std::string json =
            "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
            "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1},\"indices\":2,"
            "\"extensions\":{\"KHR_draco_mesh_compression\":{\"bufferView\":0,\"attributes\":{\"POSITION\":" +
            std::to_string(position_id) + ",\"TEXCOORD_0\":" + std::to_string(uv_id) +
            "}}}}]}],\"accessors\":[{\"componentType\":5126,\"count\":4,\"type\":\"VEC3\",\"min\":[0,0,0],"
            "\"max\":[2,1,0]},{\"componentType\":5126,\"count\":4,\"type\":\"VEC2\"},{\"componentType\":5125,"
            "\"count\":6,\"type\":\"SCALAR\"}],\"bufferViews\":[{\"buffer\":0,\"byteLength\":" +
            std::to_string(buffer.size()) + "}],\"buffers\":[{\"uri\":\"" + name +
            ".bin\",\"byteLength\":" + std::to_string(buffer.size()) +
            "}],\"extensionsUsed\":[\"KHR_draco_mesh_compression\"],\"extensionsRequired\":[\"KHR_draco_mesh_"
            "compression\"]}";
        write_bytes(dir + "/" + name + ".gltf", json);
        return dir + "/" + name + ".gltf";
    };
    Scene s = load_gltf(write("draco", bytes, pos_id));
    ASSERT_EQ(s.triangle_count(), 2u);
    // draco may reorder faces and rotate their corners: each corner is one of the quad's, with its
    // UV, and the two triangles cover the quad (area 2) facing +z as given.
    const TriangleMesh& m = s.meshes.at(0).primitives.at(0);
    for (size_t k = 0; k < m.indices.size(); ++k) {
        const Vec3& p = m.positions[m.indices[k]];
        int c = -1;
        for (int j = 0; j < 4; ++j)
            if ((p - Vec3(corner[j][0], corner[j][1], corner[j][2])).norm() < 1e-3f) c = j;
        ASSERT_GE(c, 0) << k << ": " << p.transpose();
        EXPECT_LT((m.texcoords[0][m.indices[k]] - Vec2(uv[c][0], uv[c][1])).norm(), 1e-5f) << k;
    }
    float area = 0;
    for (size_t k = 0; k < 6; k += 3) {
        const Vec3 &a = m.positions[m.indices[k]], &b = m.positions[m.indices[k + 1]],
                   &c = m.positions[m.indices[k + 2]];
        area += 0.5f * (b - a).cross(c - a).z();
    }
    EXPECT_NEAR(area, 2.0f, 1e-3f);
    EXPECT_FALSE(has_warning_containing(s, "draco"));

    std::string e = load_error(write("not_draco", std::string(64, 'x'), pos_id));
    EXPECT_NE(e.find("KHR_draco_mesh_compression: the compressed mesh does not decode"), std::string::npos) << e;
    e = load_error(write("bad_id", bytes, 7));
    EXPECT_NE(e.find("attribute 'POSITION' is not in the compressed mesh"), std::string::npos) << e;
    fs::remove_all(dir);
}

// EXT_meshopt_compression (gltfpack's output): a quad whose positions (a vertex stream), normals
// (octahedral filter) and triangle indices are meshopt-compressed in buffer 0 behind views of an
// empty fallback buffer loads as the quad; a stream that does not decode, a view whose size
// disagrees and a count far beyond the compressed bytes are refused by name.
TEST(GltfLoader, MeshoptCompressedViewsAreDecoded) {
    std::string dir = test::temp_dir("gltf");
    const std::vector<float> positions = {0, 0, 0, 2, 0, 0, 2, 1, 0, 0, 1, 0};
    const std::vector<unsigned> indices = {0, 1, 2, 0, 2, 3};
    auto encode_vertices = [](const void* v, size_t count, size_t stride) {
        std::vector<unsigned char> out(meshopt_encodeVertexBufferBound(count, stride));
        out.resize(meshopt_encodeVertexBuffer(out.data(), out.size(), v, count, stride));
        return std::string(out.begin(), out.end());
    };
    std::vector<unsigned char> idx(meshopt_encodeIndexBufferBound(6, 4));
    idx.resize(meshopt_encodeIndexBuffer(idx.data(), idx.size(), indices.data(), 6));
    std::vector<int8_t> octa(16);  // 4 x (x, y, z = 127 as 1.0, pad), 8-bit octahedral normals
    // Tilted normals (0.6, 0, 0.8): their octahedral code read raw would be (0.39, 0, 0.92).
    const std::vector<float> tilted = {0.6f, 0, 0.8f, 0, 0.6f, 0, 0.8f, 0, 0.6f, 0, 0.8f, 0, 0.6f, 0, 0.8f, 0};
    meshopt_encodeFilterOct(octa.data(), 4, 4, 8, tilted.data());
    const std::string pos_bytes = encode_vertices(positions.data(), 4, 12), idx_bytes(idx.begin(), idx.end()),
                      nrm_bytes = encode_vertices(octa.data(), 4, 4);
    std::string bin = pos_bytes;
    while (bin.size() % 4) bin.push_back('\0');
    const size_t idx_at = bin.size();
    bin += idx_bytes;
    while (bin.size() % 4) bin.push_back('\0');
    const size_t nrm_at = bin.size();
    bin += nrm_bytes;
    auto write = [&](const std::string& name, const std::string& compressed, size_t index_view_length,
                     size_t index_count) {
        write_bytes(dir + "/" + name + ".bin", compressed);
        auto view = [&](size_t fallback_at, size_t length, size_t stride, size_t at, size_t size, size_t count,
                        const std::string& mode, const std::string& filter) {
            return "{\"buffer\":1,\"byteOffset\":" + std::to_string(fallback_at) +
                   ",\"byteLength\":" + std::to_string(length) +
                   (mode == "ATTRIBUTES" ? ",\"byteStride\":" + std::to_string(stride) : "") +
                   ",\"extensions\":{\"EXT_meshopt_compression\":{\"buffer\":0,\"byteOffset\":" + std::to_string(at) +
                   ",\"byteLength\":" + std::to_string(size) + ",\"byteStride\":" + std::to_string(stride) +
                   ",\"count\":" + std::to_string(count) + ",\"mode\":\"" + mode + "\",\"filter\":\"" + filter +
                   "\"}}}";
        };
        const std::string json =
            "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
            "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":2},\"indices\":1}]}],"
            "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\",\"min\":[0,0,0],"
            "\"max\":[2,1,0]},{\"bufferView\":1,\"componentType\":5125,\"count\":" +
            std::to_string(index_count) +
            ",\"type\":\"SCALAR\"},{\"bufferView\":2,\"componentType\":5120,\"normalized\":true,\"count\":4,\"type\":"
            "\"VEC3\"}],\"bufferViews\":[" +
            view(0, 48, 12, 0, pos_bytes.size(), 4, "ATTRIBUTES", "NONE") + "," +
            view(48, index_view_length, 4, idx_at, idx_bytes.size(), index_count, "TRIANGLES", "NONE") + "," +
            view(72, 16, 4, nrm_at, nrm_bytes.size(), 4, "ATTRIBUTES", "OCTAHEDRAL") + "],\"buffers\":[{\"uri\":\"" +
            name + ".bin\",\"byteLength\":" + std::to_string(compressed.size()) +
            "},{\"byteLength\":88,\"extensions\":{\"EXT_meshopt_compression\":{\"fallback\":true}}}],"
            "\"extensionsUsed\":[\"EXT_meshopt_compression\",\"KHR_mesh_quantization\"],\"extensionsRequired\":["
            "\"EXT_meshopt_compression\",\"KHR_mesh_quantization\"]}";
        write_bytes(dir + "/" + name + ".gltf", json);
        return dir + "/" + name + ".gltf";
    };
    Scene s = load_gltf(write("meshopt", bin, 24, 6));
    ASSERT_EQ(s.triangle_count(), 2u);
    const TriangleMesh& m = s.meshes.at(0).primitives.at(0);
    for (size_t k = 0; k < 6; ++k) {
        const Vec3& p = m.positions[m.indices[k]];
        EXPECT_LT(
            (p - Vec3(positions[3 * indices[k]], positions[3 * indices[k] + 1], positions[3 * indices[k] + 2])).norm(),
            1e-6f)
            << k;
        EXPECT_LT((m.normals[m.indices[k]] - Vec3(0.6f, 0, 0.8f)).norm(), 0.02f)
            << k << ": " << m.normals[m.indices[k]].transpose();
    }
    EXPECT_FALSE(has_warning_containing(s, "meshopt"));

    std::string broken = bin;
    for (size_t k = 0; k < pos_bytes.size(); ++k) broken[k] = char(0xff);
    std::string e = load_error(write("meshopt_broken", broken, 24, 6));
    EXPECT_NE(e.find("bufferView 0 EXT_meshopt_compression: the compressed data does not decode"), std::string::npos)
        << e;
    e = load_error(write("meshopt_length", bin, 20, 6));
    EXPECT_NE(e.find("bufferView 1 EXT_meshopt_compression: count x byteStride is 24 bytes but the view holds 20"),
              std::string::npos)
        << e;
    e = load_error(write("meshopt_huge", bin, 24, 300000000));
    EXPECT_NE(e.find("is beyond what"), std::string::npos) << e;
    fs::remove_all(dir);
}

// Skins are posed at the nodes' own transforms (linear blend skinning, joint = world x inverse
// bind matrix) into world space, ignoring the skinned node's transform as the spec says; bad joint
// indices and missing skins are refused by name.
TEST(GltfLoader, SkinnedMeshesArePosedByTheirJoints) {
    std::string dir = test::temp_dir("gltf");
    MiniGltf g;
    int pos = g.accessor(g.view(quad_positions()), kFloat, 4, "VEC3");
    int idx = g.accessor(g.view(std::vector<uint16_t>{0, 1, 2, 0, 2, 3}), kUShort, 6, "SCALAR");
    int joints = g.accessor(g.view(std::vector<uint8_t>{0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0}), kUByte, 4,
                            "VEC4");
    int bad_joints = g.accessor(g.view(std::vector<uint8_t>{0, 0, 0, 0, 0, 0, 0, 0, 7, 0, 0, 0, 0, 1, 0, 0}), kUByte, 4,
                                "VEC4");
    int weights = g.accessor(g.view(std::vector<float>{1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0.5f, 0.5f, 0, 0}), kFloat,
                             4, "VEC4");
    // Joint 1's inverse bind matrix lowers by 1 before its node turns 90 degrees about z and lifts by 2.
    std::vector<float> ibm = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0,  1,
                              1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, -1, 1};
    int inverse_bind = g.accessor(g.view(ibm), kFloat, 2, "MAT4");
    auto write = [&](const std::string& name, int joint_accessor, const std::string& skin) {
        const std::string prim = "{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) +
                                 ",\"JOINTS_0\":" + std::to_string(joint_accessor) +
                                 ",\"WEIGHTS_0\":" + std::to_string(weights) + "},\"indices\":" + std::to_string(idx) +
                                 "}]}";
        return g.write(dir, name,
                       "\"scene\":0,\"scenes\":[{\"nodes\":[0,1]}],\"nodes\":[{\"mesh\":0,\"skin\":" + skin +
                           ",\"translation\":[5,0,0]},{\"children\":[2]},{\"translation\":[0,0,2],\"rotation\":[0,0," +
                           "0.70710678,0.70710678]}],\"meshes\":[" + prim + "],\"skins\":[{\"joints\":[1,2]," +
                           "\"inverseBindMatrices\":" + std::to_string(inverse_bind) + "}]");
    };
    Scene s = load_gltf(write("skinned", joints, "0"));
    ASSERT_EQ(s.instances.size(), 1u);
    EXPECT_TRUE(s.instances[0].transform.matrix().isIdentity(1e-6f)) << "the skinned node's own transform is ignored";
    // Corners in triangle order (flat normals split the vertices): 0 1 2, 0 2 3.
    const TriangleMesh& m = s.meshes[size_t(s.instances[0].mesh_group)].primitives[0];
    const std::vector<Vec3> corner = {{0, 0, 0}, {1, 0, 0}, {-1, 1, 1}, {-0.5f, 0.5f, 0.5f}};
    const int order[6] = {0, 1, 2, 0, 2, 3};
    ASSERT_EQ(m.indices.size(), 6u);
    for (size_t k = 0; k < 6; ++k) {
        const Vec3& p = m.positions[m.indices[k]];
        EXPECT_LT((p - corner[size_t(order[k])]).norm(), 1e-5f) << k << ": " << p.transpose();
    }
    EXPECT_FALSE(has_warning_containing(s, "skin")) << "posed, not ignored";

    std::string e = load_error(write("bad_joint", bad_joints, "0"));
    EXPECT_NE(e.find("JOINTS_0 2 names joint 7, but the skin has 2 joints"), std::string::npos) << e;
    e = load_error(write("no_skin", joints, "3"));
    EXPECT_NE(e.find("refers to skin 3, which does not exist"), std::string::npos) << e;
    fs::remove_all(dir);
}

// Morph targets are applied with the node's weights, else the mesh's defaults; nodes with other
// weights get their own geometry.
TEST(GltfLoader, MorphTargetsAreAppliedWithTheirWeights) {
    std::string dir = test::temp_dir("gltf");
    MiniGltf g;
    int pos = g.accessor(g.view(quad_positions()), kFloat, 4, "VEC3");
    int idx = g.accessor(g.view(std::vector<uint16_t>{0, 1, 2, 0, 2, 3}), kUShort, 6, "SCALAR");
    int up = g.accessor(g.view(std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1}), kFloat, 4, "VEC3");
    const std::string mesh = "{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) +
                             "},\"indices\":" + std::to_string(idx) +
                             ",\"targets\":[{\"POSITION\":" + std::to_string(up) + "}]}],\"weights\":[0.5]}";
    Scene s = load_gltf(g.write(dir, "morph",
                                "\"scene\":0,\"scenes\":[{\"nodes\":[0,1]}],\"nodes\":[{\"mesh\":0},{\"mesh\":0," +
                                    std::string("\"weights\":[1],\"translation\":[10,0,0]}],\"meshes\":[") + mesh +
                                    "]"));
    ASSERT_EQ(s.instances.size(), 2u);
    for (int k = 0; k < 2; ++k) {
        const Instance& in = s.instances[size_t(k)];
        const TriangleMesh& m = s.meshes[size_t(in.mesh_group)].primitives[0];
        Vec3 corner = in.transform * m.positions[m.indices[2]];
        const Vec3 expected = k == 0 ? Vec3(1, 1, 0.5f) : Vec3(11, 1, 1);
        EXPECT_LT((corner - expected).norm(), 1e-5f) << k << ": " << corner.transpose();
    }
    EXPECT_FALSE(has_warning_containing(s, "morph")) << "applied, not ignored";
    // A target of the wrong size is refused at load even at weight 0 (an animation raising its
    // weight later failed at that frame, after the frames before it were written).
    const int short_target = g.accessor(g.view(std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 1}), kFloat, 3, "VEC3");
    const std::string bad = "{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) +
                            "},\"indices\":" + std::to_string(idx) +
                            ",\"targets\":[{\"POSITION\":" + std::to_string(short_target) + "}]}],\"weights\":[0]}";
    const std::string e = load_error(
        g.write(dir, "morph_short",
                "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],\"meshes\":[" + bad + "]"));
    EXPECT_NE(e.find("morph target 0 POSITION has 3 elements but the primitive has 4 vertices"), std::string::npos)
        << e;
    fs::remove_all(dir);
}

TEST(GltfLoader, PunctualLightsArePlacedAndConvertedToTheSkysUnits) {
    std::string dir = test::temp_dir("gltf");
    MiniGltf g;
    const int pos = g.accessor(g.view(quad_positions()), kFloat, 4, "VEC3");
    auto scene_with = [&](const std::string& lights) {
        return "\"scene\":0,\"scenes\":[{\"nodes\":[0,1,2,3]}],\"nodes\":[{\"mesh\":0},"
               "{\"translation\":[1,2,3],\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}},"
               "{\"translation\":[0,5,0],\"rotation\":[-0.70710678,0,0,0.70710678],\"extensions\":{"
               "\"KHR_lights_punctual\":{\"light\":1}}},{\"extensions\":{\"KHR_lights_punctual\":{\"light\":2}}}],"
               "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":" +
               std::to_string(pos) +
               "}}]}],\"extensionsUsed\":[\"KHR_lights_punctual\"],\"extensions\":{"
               "\"KHR_lights_punctual\":{\"lights\":[" +
               lights + "]}}";
    };
    const std::string point =
        "{\"type\":\"point\",\"name\":\"lamp\",\"color\":[1,0.5,0.25],\"intensity\":683,\"range\":10}";
    const std::string directional = "{\"type\":\"directional\",\"intensity\":1366}";
    std::vector<std::string> notes;
    Scene s = load_gltf(g.write(dir, "lights",
                                scene_with(point +
                                           ",{\"type\":\"spot\",\"intensity\":6830,\"spot\":{"
                                           "\"innerConeAngle\":0.2,\"outerConeAngle\":0.4}}," +
                                           directional)),
                        &notes);
    for (const std::string& n : notes) EXPECT_EQ(n.find("KHR_lights_punctual"), std::string::npos) << n;
    ASSERT_EQ(s.lights.size(), 3u);
    const PunctualLight &lamp = s.lights[0], &spot = s.lights[1], &sun = s.lights[2];
    EXPECT_EQ(lamp.type, PunctualLight::Type::Point);
    EXPECT_EQ(lamp.name, "lamp");
    EXPECT_TRUE(lamp.position.isApprox(Vec3(1, 2, 3)));
    EXPECT_TRUE(lamp.intensity.isApprox(Color(1, 0.5f, 0.25f), 1e-6f));  // 683 cd -> 1 W/sr
    EXPECT_EQ(lamp.range, 10.0f);
    EXPECT_EQ(spot.type, PunctualLight::Type::Spot);
    EXPECT_TRUE(spot.direction.isApprox(Vec3(0, -1, 0), 1e-5f)) << spot.direction.transpose();
    EXPECT_NEAR(spot.cos_inner, std::cos(0.2), 1e-6);
    EXPECT_NEAR(spot.cos_outer, std::cos(0.4), 1e-6);
    EXPECT_TRUE(spot.intensity.isApprox(Color::Constant(10), 1e-6f));
    EXPECT_EQ(sun.type, PunctualLight::Type::Directional);
    EXPECT_TRUE(sun.direction.isApprox(Vec3(0, 0, -1)));
    EXPECT_TRUE(sun.intensity.isApprox(Color::Constant(2), 1e-6f));  // 1366 lux -> 2 W/m^2
    struct Case {
        std::string name, lights, expect;
    };
    const std::vector<Case> bad = {
        {"cone", point + ",{\"type\":\"spot\",\"spot\":{\"innerConeAngle\":0.5,\"outerConeAngle\":0.4}}," + directional,
         "light 1: spot cone angles inner 0.5 and outer 0.4 rad must satisfy 0 <= inner < outer <= pi / 2"},
        {"intensity", point + ",{\"type\":\"point\",\"intensity\":-1}," + directional,
         "light 1: intensity -1 is outside [0, 1e9] candela"},
        {"missing", point + "," + directional, "KHR_lights_punctual light 2 does not exist (the file has 2)"},
        {"kind", point + ",{\"type\":\"area\"}," + directional, "type 'area' is not point, spot or directional"},
    };
    for (const Case& c : bad) {
        std::string e = load_error(g.write(dir, c.name, scene_with(c.lights)));
        EXPECT_NE(e.find(c.name + ".gltf"), std::string::npos) << c.name << ": " << e;
        EXPECT_NE(e.find(c.expect), std::string::npos) << c.name << ": " << e;
    }
    fs::remove_all(dir);
}

// A quad with one material: `material` is its JSON object, `used` the extensionsUsed list's items.
struct OneMaterialQuad {
    MiniGltf g;
    int pos = g.accessor(g.view(quad_positions()), kFloat, 4, "VEC3");
    int idx = g.accessor(g.view(std::vector<uint16_t>{0, 1, 2, 0, 2, 3}), kUShort, 6, "SCALAR");
    std::string write(const std::string& dir, const std::string& name, const std::string& material,
                      const std::string& used) const {
        return g.write(dir, name,
                       one_node_scene("{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) +
                                          "},\"indices\":" + std::to_string(idx) + ",\"material\":0}]}",
                                      "\"materials\":[" + material + "],\"extensionsUsed\":[" + used + "]"));
    }
};

// EXT_texture_webp: the WebP image is used in preference to the core source (the fallback for
// viewers without WebP), decoded through OpenCV; a WebP source that does not exist is named.
TEST(GltfLoader, WebpTexturesAreReadWithTheirFallbackIgnored) {
    std::string dir = test::temp_dir("gltf");
    std::vector<uchar> webp, png;
    cv::Mat red(2, 2, CV_8UC3, cv::Scalar(0, 0, 255)), green(2, 2, CV_8UC3, cv::Scalar(0, 255, 0));  // BGR
    ASSERT_TRUE(cv::imencode(".webp", red, webp, {cv::IMWRITE_WEBP_QUALITY, 101}));                  // > 100: lossless
    ASSERT_TRUE(cv::imencode(".png", green, png));
    write_bytes(dir + "/red.webp", std::string(webp.begin(), webp.end()));
    write_bytes(dir + "/green.png", std::string(png.begin(), png.end()));
    const OneMaterialQuad quad;
    auto write = [&](const std::string& name, int webp_source) {
        return quad.write(
            dir, name,
            "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}],\"textures\":[{\"source\":0,"
            "\"extensions\":{\"EXT_texture_webp\":{\"source\":" +
                std::to_string(webp_source) + "}}}],\"images\":[{\"uri\":\"green.png\"},{\"uri\":\"red.webp\"}",
            "\"EXT_texture_webp\"");
    };
    Scene s = load_gltf(write("webp", 1));
    const Material* m = &s.materials.at(0);
    ASSERT_TRUE(m->base_color_texture.present());
    const Vec4 c = s.textures[size_t(m->base_color_texture.texture)]->evaluate(Vec2(0.5f, 0.5f));
    EXPECT_NEAR(c[0], 1.0f, 1e-3f) << "the WebP (red), not the PNG fallback (green)";
    EXPECT_NEAR(c[1], 0.0f, 1e-3f);
    EXPECT_FALSE(has_warning_containing(s, "EXT_texture_webp"));
    std::string e = load_error(write("webp_missing", 5));
    EXPECT_NE(e.find("EXT_texture_webp's source 5 does not exist (the file has 2 images)"), std::string::npos) << e;
    // Embedded as a data: URI (gltf-transform's output), which tinygltf leaves undecoded for WebP:
    // it was "missing texture file '.../data:image/webp;base64,...'".
    auto embedded = [&](const std::string& name, const std::string& uri) {
        return quad.write(
            dir, name,
            "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}],\"textures\":[{\"source\":0,"
            "\"extensions\":{\"EXT_texture_webp\":{\"source\":1}}}],\"images\":[{\"uri\":\"green.png\"},"
            "{\"uri\":\"" +
                uri + "\"}",
            "\"EXT_texture_webp\"");
    };
    s = load_gltf(embedded("webp_embedded",
                           "data:image/webp;base64," + tinygltf::base64_encode(webp.data(), unsigned(webp.size()))));
    m = &s.materials.at(0);
    EXPECT_NEAR(s.textures[size_t(m->base_color_texture.texture)]->evaluate(Vec2(0.5f, 0.5f))[0], 1.0f, 1e-3f);
    // Another format embedded is named as a file of it is; a data: URI that is not base64 as that.
    const std::string ktx = "\xabKTX 20\xbb\r\n\x1a\n" + std::string(64, '\0');
    e = load_error(embedded("ktx_embedded",
                            "data:image/ktx2;base64," +
                                tinygltf::base64_encode(reinterpret_cast<const unsigned char*>(ktx.data()),
                                                        unsigned(ktx.size()))));
    EXPECT_NE(e.find("glTF textures are PNG or JPEG, or WebP"), std::string::npos) << e;
    EXPECT_EQ(e.find("missing texture file"), std::string::npos) << e;
    e = load_error(embedded("not_base64", "data:image/png,notbase64"));
    EXPECT_NE(e.find("image 1: its data: URI 'data:image/png' is not base64"), std::string::npos) << e;
    // The canvas each kind of WebP header declares is checked before decoding: VP8X (24-bit sizes),
    // VP8L (lossless, 14-bit) and VP8 (lossy, 14-bit).
    auto riff = [](const std::string& chunk, const std::string& data) {
        std::string body = "WEBP" + chunk + std::string("\x20\0\0\0", 4) + data + std::string(32, '\0');
        const uint32_t size = uint32_t(body.size());
        return "RIFF" + std::string(reinterpret_cast<const char*>(&size), 4) + body;
    };
    const std::vector<std::pair<std::string, std::string>> huge = {
        {riff("VP8X", std::string("\0\0\0\0\x1f\x4e\0\x1f\x4e\0", 10)), "20000 x 20000"},
        {riff("VP8L", std::string("\x2f\xff\xff\xff\x0f", 5)), "16384 x 16384"},
        {riff("VP8 ", std::string("\0\0\0\x9d\x01\x2a\xff\x3f\xff\x3f", 10)), "16383 x 16383"}};
    for (const auto& [bytes, size] : huge) {
        write_bytes(dir + "/red.webp", bytes);
        e = load_error(write("webp_huge", 1));
        EXPECT_NE(e.find("image is " + size), std::string::npos) << e;
    }
    fs::remove_all(dir);
}

// A quad whose material `name` carries one extension object and one texture, t.png: sRGB 188
// (linear 0.5) with alpha 128 (0.5), for the extension's texture slots.
struct ExtensionMaterialQuad {
    ExtensionMaterialQuad(std::string dir_, std::string extension_, std::string name_)
        : dir(std::move(dir_)), extension(std::move(extension_)), name(std::move(name_)) {
        cv::Mat texel(1, 1, CV_8UC4, cv::Scalar(188, 188, 188, 128));
        EXPECT_TRUE(cv::imwrite(dir + "/t.png", texel));
    }
    std::string write(const std::string& file, const std::string& extension_json) const {
        return quad.write(dir, file,
                          "{\"name\":\"" + name + "\",\"extensions\":{\"" + extension + "\":" + extension_json +
                              "}}],\"textures\":[{\"source\":0}],\"images\":[{\"uri\":\"t.png\"}",
                          "\"" + extension + "\"");
    }
    std::string dir, extension, name;
    OneMaterialQuad quad;
};

Vec4 texel_of(const Scene& s, const TextureSlot& slot) {
    return s.textures[size_t(slot.texture)]->evaluate(Vec2(0.5f, 0.5f));
}

// KHR_materials_sheen: colour and roughness factors and both textures are read (the colour's as
// sRGB); a colour outside [0, 1] is refused by name.
TEST(GltfLoader, SheenIsReadAndBadColoursRefused) {
    std::string dir = test::temp_dir("gltf");
    const ExtensionMaterialQuad quad(dir, "KHR_materials_sheen", "velvet");
    auto write = [&](const std::string& name, const std::string& sheen) { return quad.write(name, sheen); };
    Scene s = load_gltf(write("sheen",
                              "{\"sheenColorFactor\":[1,0.5,0.25],\"sheenRoughnessFactor\":0.4,"
                              "\"sheenColorTexture\":{\"index\":0},\"sheenRoughnessTexture\":{\"index\":0}}"));
    const Material* m = material_named(s, "velvet");
    ASSERT_NE(m, nullptr);
    EXPECT_TRUE(m->sheen_color.isApprox(Color(1, 0.5f, 0.25f)));
    EXPECT_FLOAT_EQ(m->sheen_roughness, 0.4f);
    ASSERT_TRUE(m->sheen_color_texture.present() && m->sheen_roughness_texture.present());
    EXPECT_NEAR(texel_of(s, m->sheen_color_texture)[0], 0.5f, 0.01f) << "sRGB";
    EXPECT_NEAR(texel_of(s, m->sheen_roughness_texture)[3], 0.5f, 0.01f);
    EXPECT_FALSE(has_warning_containing(s, "KHR_materials_sheen"));
    const std::string e = load_error(write("sheen_bad", "{\"sheenColorFactor\":[1,2,0]}"));
    EXPECT_NE(e.find("KHR_materials_sheen sheenColorFactor 2 is outside [0, 1]"), std::string::npos) << e;
    fs::remove_all(dir);
}

// KHR_materials_pbrSpecularGlossiness replaces the metal-rough fallback: a dielectric with the diffuse
// colour and alpha as base, F0 the specular colour (specular colour x 0.04), roughness 1 - glossiness,
// the diffuse texture as base colour texture and the specular-glossiness texture as both the F0
// tint (sRGB RGB) and the glossiness (linear A); nothing is said to be ignored; bad values are named.
TEST(GltfLoader, SpecularGlossinessMaterialsAreMappedOntoMetalRough) {
    std::string dir = test::temp_dir("gltf");
    const ExtensionMaterialQuad quad(dir, "KHR_materials_pbrSpecularGlossiness", "old");
    auto write = [&](const std::string& name, const std::string& sg) { return quad.write(name, sg); };
    Scene s = load_gltf(write("sg",
                              "{\"diffuseFactor\":[0.5,0.25,0.125,0.8],\"specularFactor\":[0.2,0.1,0.05],"
                              "\"glossinessFactor\":0.7,\"diffuseTexture\":{\"index\":0},"
                              "\"specularGlossinessTexture\":{\"index\":0}}"));
    const Material* m = material_named(s, "old");
    ASSERT_NE(m, nullptr);
    EXPECT_TRUE(m->base_color.isApprox(Color(0.5f, 0.25f, 0.125f)));
    EXPECT_FLOAT_EQ(m->base_alpha, 0.8f);
    EXPECT_EQ(m->metallic, 0.0f);
    EXPECT_NEAR(m->roughness, 0.3f, 1e-6f);
    EXPECT_TRUE((m->specular_color * 0.04f).isApprox(Color(0.2f, 0.1f, 0.05f)));
    EXPECT_FALSE(m->metallic_roughness_texture.present());
    ASSERT_TRUE(m->base_color_texture.present() && m->specular_color_texture.present() &&
                m->glossiness_texture.present());
    EXPECT_NEAR(texel_of(s, m->base_color_texture)[0], 0.5f, 0.01f) << "sRGB";
    EXPECT_NEAR(texel_of(s, m->specular_color_texture)[0], 0.5f, 0.01f) << "sRGB";
    EXPECT_NEAR(texel_of(s, m->glossiness_texture)[3], 0.5f, 0.01f) << "linear";
    EXPECT_FALSE(has_warning_containing(s, "KHR_materials_pbrSpecularGlossiness"));
    // Shaded: roughness 1 - 0.7 x A, F0 tint x the texture's RGB, base x the diffuse texture.
    SurfaceHit hit;
    hit.geometric_normal = hit.shading_normal = Vec3(0, 1, 0);
    hit.texcoord[0] = Vec2(0.5f, 0.5f);
    hit.material = m;
    const ShadingPoint sp = evaluate_material(s, hit, Vec3(0, 1, 0));
    const float a = texel_of(s, m->glossiness_texture)[3], t = texel_of(s, m->specular_color_texture)[0];
    EXPECT_NEAR(sp.roughness, 1 - 0.7f * a, 1e-5f);
    EXPECT_EQ(sp.metallic, 0.0f);
    EXPECT_NEAR(sp.specular_color[0] * 0.04f, 0.2f * t, 1e-5f);
    EXPECT_NEAR(sp.base_color[1], 0.25f * t, 1e-5f);
    // Defaults: white diffuse, specular 1 (F0 1), glossiness 1 (roughness 0).
    Scene d = load_gltf(write("sg_default", "{}"));
    EXPECT_EQ(material_named(d, "old")->roughness, 0.0f);
    EXPECT_TRUE(material_named(d, "old")->base_color.isApprox(Color::Ones()));
    for (auto [json, says] : {std::pair<std::string, std::string>{"{\"diffuseFactor\":[1,1,1]}", "is not 4 numbers"},
                              {"{\"diffuseFactor\":[1,2,1,1]}", "diffuseFactor 2 is outside [0, 1]"},
                              {"{\"glossinessFactor\":-1}", "glossinessFactor -1 is outside [0, 1]"},
                              {"{\"specularFactor\":[1,1]}", "specularFactor is not 3 numbers"},
                              {"{\"specularGlossinessTexture\":{\"index\":-1}}", "refers to texture -1"}}) {
        const std::string e = load_error(write("sg_bad", json));
        EXPECT_NE(e.find(says), std::string::npos) << json << ": " << e;
    }
    fs::remove_all(dir);
}

// KHR_materials_anisotropy: strength, rotation and texture are read; shaded, the frame's tangent turns
// to the direction (the texture's RG, 45 degrees here, then the rotation, counter-clockwise towards
// the bitangent of the mesh's handedness) and the strength takes the texture's B; bad values named.
TEST(GltfLoader, AnisotropyTurnsTheShadingTangentToItsDirection) {
    std::string dir = test::temp_dir("gltf");
    const ExtensionMaterialQuad quad(dir, "KHR_materials_anisotropy", "brushed");
    auto write = [&](const std::string& name, const std::string& an) { return quad.write(name, an); };
    Scene s = load_gltf(write("aniso",
                              "{\"anisotropyStrength\":0.5,\"anisotropyRotation\":1.5707963,"
                              "\"anisotropyTexture\":{\"index\":0}}"));
    const Material* m = material_named(s, "brushed");
    ASSERT_NE(m, nullptr);
    EXPECT_FLOAT_EQ(m->anisotropy_strength, 0.5f);
    EXPECT_NEAR(m->anisotropy_rotation, 1.5707963f, 1e-6f);
    ASSERT_TRUE(m->anisotropy_texture.present());
    EXPECT_FALSE(has_warning_containing(s, "KHR_materials_anisotropy"));
    const float b = texel_of(s, m->anisotropy_texture)[2];
    EXPECT_NEAR(b, 188 / 255.0f, 0.01f) << "linear";
    for (float handedness : {1.0f, -1.0f}) {
        SurfaceHit hit;
        hit.geometric_normal = hit.shading_normal = Vec3(0, 0, 1);
        hit.tangent = Vec4(1, 0, 0, handedness);
        hit.texcoord[0] = Vec2(0.5f, 0.5f);
        hit.material = m;
        const ShadingPoint sp = evaluate_material(s, hit, Vec3(0, 0, 1));
        EXPECT_NEAR(sp.anisotropy, 0.5f * b, 1e-5f);
        // 45 + 90 degrees from the tangent, towards (0, handedness, 0).
        const Vec3 want(-std::sqrt(0.5f), handedness * std::sqrt(0.5f), 0);
        EXPECT_NEAR((sp.tangent - want).norm(), 0.0f, 1e-4f) << handedness << ": " << sp.tangent.transpose();
        EXPECT_NEAR(sp.bitangent.dot(sp.tangent), 0.0f, 1e-5f);
        EXPECT_NEAR((sp.tangent.cross(sp.bitangent) - sp.normal).norm(), 0.0f, 1e-5f);
    }
    for (auto [json, says] :
         {std::pair<std::string, std::string>{"{\"anisotropyStrength\":2}", "anisotropyStrength 2 is outside [0, 1]"},
          {"{\"anisotropyRotation\":\"a\"}", "anisotropyRotation is not a number"}}) {
        const std::string e = load_error(write("aniso_bad", json));
        EXPECT_NE(e.find(says), std::string::npos) << json << ": " << e;
    }
    fs::remove_all(dir);
}

// Metadata extensions (licence, authoring, closed meshes) change nothing drawn: no warning, not even
// when required; an unknown extension still gets one.
TEST(GltfLoader, MetadataExtensionsAreAcceptedSilently) {
    std::string dir = test::temp_dir("gltf");
    const ExtensionMaterialQuad xmp(dir, "KHR_xmp_json_ld", "licensed");
    Scene s = load_gltf(xmp.write("xmp", "{\"packet\":0}"));
    EXPECT_FALSE(has_warning_containing(s, "KHR_xmp_json_ld"));
    const ExtensionMaterialQuad unknown(dir, "EXT_made_up", "odd");
    Scene u = load_gltf(unknown.write("unknown", "{}"));
    EXPECT_TRUE(has_warning_containing(u, "EXT_made_up"));
    fs::remove_all(dir);
}

// KHR_materials_unlit (an empty object) marks the material unlit, and nothing is said to be ignored;
// a material without it is not.
TEST(GltfLoader, UnlitMaterialsAreRead) {
    std::string dir = test::temp_dir("gltf");
    const ExtensionMaterialQuad quad(dir, "KHR_materials_unlit", "baked");
    Scene s = load_gltf(quad.write("unlit", "{}"));
    const Material* m = material_named(s, "baked");
    ASSERT_NE(m, nullptr);
    EXPECT_TRUE(m->unlit);
    EXPECT_FALSE(has_warning_containing(s, "KHR_materials_unlit"));
    const ExtensionMaterialQuad plain(dir, "KHR_materials_sheen", "lit");
    Scene lit = load_gltf(plain.write("lit", "{\"sheenColorFactor\":[0,0,0]}"));
    ASSERT_NE(material_named(lit, "lit"), nullptr);
    EXPECT_FALSE(material_named(lit, "lit")->unlit);
    fs::remove_all(dir);
}

// KHR_materials_specular: factor, colour (above 1 allowed) and both textures are read, the
// colour texture as sRGB; a negative colour is refused by name and nothing is said to be ignored.
TEST(GltfLoader, SpecularColourAndTexturesAreRead) {
    std::string dir = test::temp_dir("gltf");
    const ExtensionMaterialQuad quad(dir, "KHR_materials_specular", "tinted");
    auto write = [&](const std::string& name, const std::string& specular) { return quad.write(name, specular); };
    Scene s = load_gltf(write("specular",
                              "{\"specularFactor\":0.8,\"specularColorFactor\":[2,1,0.5],"
                              "\"specularTexture\":{\"index\":0},\"specularColorTexture\":{\"index\":0}}"));
    const Material* m = material_named(s, "tinted");
    ASSERT_NE(m, nullptr);
    EXPECT_FLOAT_EQ(m->specular, 0.8f);
    EXPECT_TRUE(m->specular_color.isApprox(Color(2, 1, 0.5f)));
    ASSERT_TRUE(m->specular_texture.present() && m->specular_color_texture.present());
    EXPECT_NEAR(texel_of(s, m->specular_color_texture)[0], 0.5f, 0.01f) << "sRGB";
    EXPECT_NEAR(texel_of(s, m->specular_texture)[3], 0.5f, 0.01f);
    EXPECT_FALSE(has_warning_containing(s, "KHR_materials_specular"));
    const std::string e = load_error(write("specular_bad", "{\"specularColorFactor\":[1,-1,0]}"));
    EXPECT_NE(e.find("KHR_materials_specular specularColorFactor -1 is outside [0, "), std::string::npos) << e;
    fs::remove_all(dir);
}

// KHR_materials_ior: read into the material (water 1.33); the extension's 0 falls back to 1.5 with
// a warning; a negative IOR is refused by name.
TEST(GltfLoader, IorIsReadAndImpossibleValuesAreSaid) {
    std::string dir = test::temp_dir("gltf");
    const OneMaterialQuad quad;
    auto write = [&](const std::string& name, const std::string& ior) {
        return quad.write(dir, name,
                          "{\"name\":\"water\",\"extensions\":{\"KHR_materials_ior\":{\"ior\":" + ior + "}}}",
                          "\"KHR_materials_ior\"");
    };
    std::vector<std::string> notes;
    Scene water = load_gltf(write("water", "1.33"), &notes);
    ASSERT_EQ(water.materials.size(), 1u);
    EXPECT_FLOAT_EQ(water.materials[0].ior, 1.33f);
    EXPECT_TRUE(notes.empty()) << notes[0];
    Scene zero = load_gltf(write("zero", "0"), &notes);
    EXPECT_FLOAT_EQ(zero.materials[0].ior, 1.5f);
    ASSERT_FALSE(notes.empty());
    EXPECT_NE(notes.back().find("KHR_materials_ior ior 0 is below 1"), std::string::npos) << notes.back();
    std::string e = load_error(write("negative", "-2"));
    EXPECT_NE(e.find("negative.gltf"), std::string::npos) << e;
    EXPECT_NE(e.find("material 'water': KHR_materials_ior ior -2 is outside [1, 100]"), std::string::npos) << e;
    fs::remove_all(dir);
}

// KHR_materials_volume on thin glass: attenuationColor^(thickness / attenuationDistance) tints what
// passes (green bottle glass of a white base is green), said as rendered thin; bad values refused.
TEST(GltfLoader, VolumeAbsorptionTintsThinGlass) {
    std::string dir = test::temp_dir("gltf");
    const OneMaterialQuad quad;
    auto write = [&](const std::string& name, const std::string& volume) {
        return quad.write(
            dir, name,
            "{\"name\":\"bottle\",\"extensions\":{\"KHR_materials_transmission\":{\"transmissionFactor\":1},"
            "\"KHR_materials_volume\":" +
                volume + "}}",
            "\"KHR_materials_transmission\",\"KHR_materials_volume\"");
    };
    std::vector<std::string> notes;
    Scene s = load_gltf(write("bottle",
                              "{\"thicknessFactor\":0.01,\"attenuationDistance\":0.005,"
                              "\"attenuationColor\":[0.5,1,0.25]}"),
                        &notes);
    ASSERT_EQ(s.materials.size(), 1u);
    EXPECT_TRUE(s.materials[0].volume_tint.isApprox(Color(0.25f, 1, 0.0625f), 1e-6f))
        << s.materials[0].volume_tint.transpose();
    bool said = false;
    for (const std::string& n : notes)
        said = said || n.find("KHR_materials_volume is rendered thin") != std::string::npos;
    EXPECT_TRUE(said);
    // No thickness, or no attenuation: clear.
    EXPECT_TRUE(
        (load_gltf(write("thin", "{\"attenuationColor\":[0.5,1,0.25]}")).materials[0].volume_tint == 1.0f).all());
    std::string e = load_error(write("bad", "{\"thicknessFactor\":1,\"attenuationDistance\":0}"));
    EXPECT_NE(e.find("material 'bottle': KHR_materials_volume attenuationDistance 0 is not positive"),
              std::string::npos)
        << e;
    e = load_error(write("colour", "{\"thicknessFactor\":1,\"attenuationColor\":[2,1,1]}"));
    EXPECT_NE(e.find("attenuationColor 2 is outside [0, 1]"), std::string::npos) << e;
    fs::remove_all(dir);
}

TEST(GltfLoader, HostileInputIsRefusedAtItsRoot) {
    std::string root = test::temp_dir("gltf");
    std::string dir = root + "/asset";
    fs::create_directories(dir);
    MiniGltf g;
    int pos = g.accessor(g.view(quad_positions()), kFloat, 4, "VEC3");
    int zeros = g.accessor(-1, kFloat, size_t(1) << 28, "VEC3");  // no bufferView: 3.2 GB of zeros
    auto mesh = [](int p) { return "{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(p) + "}}]}"; };
    auto node_scene = [&](const std::string& node) {
        return "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[" + node + "],\"meshes\":[" + mesh(pos) + "]";
    };
    // A good file loads, with its scale.
    Scene ok = load_gltf(g.write(dir, "ok", node_scene("{\"mesh\":0,\"scale\":[2,2,2]}")));
    ASSERT_EQ(ok.instances.size(), 1u);
    EXPECT_FLOAT_EQ(ok.instances[0].transform.linear()(0, 0), 2.0f);
    // A node scaled to a point or a line (how animations hide objects) shows nothing: skipped with a
    // warning, the rest of the scene drawn (the whole file was refused as "singular").
    for (const char* hidden :
         {"\"scale\":[0,0,0]", "\"scale\":[0,0,1]", "\"matrix\":[0,0,0,0,0,0,0,0,0,0,0,0,1,2,3,1]"}) {
        std::vector<std::string> warnings;
        const Scene s = load_gltf(
            g.write(dir, "hidden",
                    "\"scene\":0,\"scenes\":[{\"nodes\":[0,1]}],\"nodes\":[{\"name\":\"gone\",\"mesh\":0," +
                        std::string(hidden) + "},{\"mesh\":0,\"translation\":[5,0,0]}],\"meshes\":[" + mesh(pos) + "]"),
            &warnings);
        ASSERT_EQ(s.instances.size(), 1u) << hidden;
        EXPECT_EQ(s.hidden_meshes, 1) << hidden;
        EXPECT_FLOAT_EQ(s.instances[0].transform.translation().x(), 5.0f) << hidden;
        bool said = false;
        for (const std::string& w : warnings)
            said |= w.find("node 'gone'") != std::string::npos && w.find("not drawn") != std::string::npos;
        EXPECT_TRUE(said) << hidden;
    }
    {  // A GPU instance scaled to 0 likewise (EXT_mesh_gpu_instancing: one hidden of two).
        MiniGltf gi = g;
        const int scales = gi.accessor(gi.view(std::vector<float>{1, 1, 1, 0, 0, 0}), kFloat, 2, "VEC3");
        std::vector<std::string> warnings;
        const Scene s =
            load_gltf(gi.write(dir, "hidden_instance",
                               "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0,\"extensions\":{"
                               "\"EXT_mesh_gpu_instancing\":{\"attributes\":{\"SCALE\":" +
                                   std::to_string(scales) + "}}}}],\"meshes\":[" + mesh(pos) +
                                   "],\"extensionsUsed\":[\"EXT_mesh_gpu_instancing\"]"),
                      &warnings);
        EXPECT_EQ(s.instances.size(), 1u);
        bool said = false;
        for (const std::string& w : warnings) said |= w.find("instance 1") != std::string::npos;
        EXPECT_TRUE(said);
    }
    {  // A light under a zero scale likewise (it was refused: "it shines nowhere").
        std::vector<std::string> warnings;
        const Scene s = load_gltf(
            g.write(dir, "hidden_light",
                    "\"scene\":0,\"scenes\":[{\"nodes\":[0,1]}],\"nodes\":[{\"mesh\":0},{\"scale\":[0,0,0],"
                    "\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}}],\"meshes\":[" +
                        mesh(pos) +
                        "],\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"directional\"}]}},"
                        "\"extensionsUsed\":[\"KHR_lights_punctual\"]"),
            &warnings);
        EXPECT_EQ(s.lights.size(), 0u);
        EXPECT_EQ(s.instances.size(), 1u);
        bool said = false;
        for (const std::string& w : warnings) said |= w.find("not used") != std::string::npos;
        EXPECT_TRUE(said);
    }

    struct Case {
        std::string name, body, expect;
    };
    std::vector<Case> cases = {
        {"scale0", node_scene("{\"mesh\":0,\"scale\":[0,1,1]}"), "node 0: its world transform is singular"},
        {"named", node_scene("{\"name\":\"flat\",\"mesh\":0,\"scale\":[1e-11,1e-11,1e-11]}"),
         "node 'flat': its world transform is singular"},
        {"overflow", node_scene("{\"mesh\":0,\"translation\":[1e300,0,0]}"), "not finite"},
        {"zeros", one_node_scene(mesh(zeros)), "without a bufferView"},
    };
    for (const Case& c : cases) {
        std::string e = load_error(g.write(dir, c.name, c.body));
        EXPECT_NE(e.find(c.name + ".gltf"), std::string::npos) << c.name << ": " << e;
        EXPECT_NE(e.find(c.expect), std::string::npos) << c.name << ": " << e;
    }
    // 256 levels of JSON load, 257 do not (the limit is measured, not guessed at by a crash).
    std::string base = read_text(dir + "/ok.gltf");
    for (int depth : {255, 257}) {
        std::string deep = std::string(size_t(depth - 2), '[') + "0" + std::string(size_t(depth - 2), ']');
        std::string json = base;
        json.replace(json.find("\"asset\":{"), 9, "\"asset\":{\"extras\":" + deep + ",");
        write_bytes(dir + "/deep" + std::to_string(depth) + ".gltf", json);
        std::string e = load_error(dir + "/deep" + std::to_string(depth) + ".gltf");
        if (depth <= 256) EXPECT_EQ(e, "") << depth;
        else EXPECT_NE(e.find("nested 257 levels deep"), std::string::npos) << e;
    }
    // The buffer outside the asset's folder is never read: by '..', or through a link.
    fs::copy_file(dir + "/ok.bin", root + "/outside.bin");
    fs::create_symlink(root + "/outside.bin", dir + "/link.bin");
    for (const std::string& uri : {std::string("../outside.bin"), root + "/outside.bin", std::string("link.bin")}) {
        std::string json = base;
        json.replace(json.find("\"ok.bin\""), 8, "\"" + uri + "\"");
        write_bytes(dir + "/escape.gltf", json);
        std::string e = load_error(dir + "/escape.gltf");
        EXPECT_NE(e.find("escape.gltf"), std::string::npos) << uri << ": " << e;
        EXPECT_TRUE(e.find("asset's folder") != std::string::npos || e.find("absolute") != std::string::npos)
            << uri << ": " << e;
    }
}

// The JSON of a .gltf and of a .glb's first chunk, read without buffers (animate --count-frames
// checks --camera with it); a .glb cut short, or text that is no JSON, gives nothing.
TEST(GltfJson, ReadsTheDocumentOfGltfAndGlbFiles) {
    const std::string dir = test::temp_dir("gltf_json");
    const std::string text = R"({"asset":{"version":"2.0"},"cameras":[{"type":"perspective"},{"type":"perspective"}]})";
    std::ofstream(dir + "/a.gltf") << text;
    std::string chunk = text;
    while (chunk.size() % 4) chunk += ' ';
    auto word = [](uint32_t v) { return std::string{char(v), char(v >> 8), char(v >> 16), char(v >> 24)}; };
    const std::string glb = "glTF" + word(2) + word(uint32_t(20 + chunk.size())) + word(uint32_t(chunk.size())) +
                            "JSON" + chunk;
    std::ofstream(dir + "/a.glb", std::ios::binary) << glb;
    std::ofstream(dir + "/cut.glb", std::ios::binary) << glb.substr(0, 30);
    std::ofstream(dir + "/not.gltf") << "glTF? no";
    for (const char* name : {"/a.gltf", "/a.glb"}) {
        const auto j = read_gltf_json(dir + name);
        ASSERT_TRUE(j.has_value()) << name;
        EXPECT_EQ((*j)["cameras"].size(), 2u) << name;
    }
    EXPECT_FALSE(read_gltf_json(dir + "/cut.glb").has_value());
    EXPECT_FALSE(read_gltf_json(dir + "/not.gltf").has_value());
    EXPECT_FALSE(read_gltf_json(dir + "/missing.gltf").has_value());
    fs::remove_all(dir);
}

}  // namespace
}  // namespace dynsky
