#include "renderer/mesh_attributes.h"

#include <gtest/gtest.h>

#include "renderer/gltf_loader.h"
#include "tests/test_support.h"

namespace dynsky {
namespace {

// A quad in a tilted plane: P(u, v) = origin + u * a - v * b, so dP/du = a and dP/dv = -b
// (glTF v runs down the image, so the image's "up" is +b). Two triangles, counter-clockwise
// seen from a x b.
TriangleMesh tilted_quad(const Vec3& a, const Vec3& b, bool mirror_u = false) {
    TriangleMesh m;
    const Vec3 origin(0.3f, -0.2f, 1.0f);
    const Vec2 uvs[4] = {Vec2(0, 1), Vec2(1, 1), Vec2(1, 0), Vec2(0, 0)};
    for (const Vec2& uv : uvs) {
        m.positions.push_back(origin + uv.x() * a - uv.y() * b);
        m.texcoords[0].push_back(mirror_u ? Vec2(1 - uv.x(), uv.y()) : uv);
    }
    m.indices = {0, 1, 2, 0, 2, 3};
    return m;
}

TEST(MeshAttributes, FlatNormalsGiveEachTriangleItsOwnVerticesAndFaceNormal) {
    // Two triangles folded along the shared edge 0-2: their normals differ.
    TriangleMesh m;
    m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
    m.texcoords[0] = {Vec2(0, 0), Vec2(1, 0), Vec2(0, 1), Vec2(1, 1)};
    m.indices = {0, 1, 2, 0, 2, 3};
    generate_flat_normals(m);
    ASSERT_EQ(m.positions.size(), 6u);
    ASSERT_EQ(m.texcoords[0].size(), 6u);
    EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 3, 4, 5}));
    EXPECT_EQ(m.positions[4], Vec3(0, 1, 0));
    EXPECT_EQ(m.texcoords[0][5], Vec2(1, 1));
    // (1,0,0) x (0,1,0) = +Z; (0,1,0) x (0,0,1) = +X.
    for (int i = 0; i < 3; ++i) EXPECT_NEAR((m.normals[size_t(i)] - Vec3::UnitZ()).norm(), 0.0f, 1e-6f);
    for (int i = 3; i < 6; ++i) EXPECT_NEAR((m.normals[size_t(i)] - Vec3::UnitX()).norm(), 0.0f, 1e-6f);
}

TEST(MeshAttributes, SmoothNormalsAreAreaWeighted) {
    // Vertex 0 is shared by a triangle of area 2 in the z = 0 plane (normal +Z) and one of area
    // 0.5 in the x = 0 plane (normal +X): the normal is (0.5, 0, 2) normalised.
    TriangleMesh m;
    m.positions = {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), Vec3(0, 0, 1), Vec3(0, 1, 0)};
    m.indices = {0, 1, 2, 0, 4, 3};
    generate_smooth_normals(m);
    EXPECT_NEAR((m.normals[0] - Vec3(0.5f, 0, 2).normalized()).norm(), 0.0f, 1e-6f);
    EXPECT_NEAR((m.normals[1] - Vec3::UnitZ()).norm(), 0.0f, 1e-6f);
    EXPECT_NEAR((m.normals[3] - Vec3::UnitX()).norm(), 0.0f, 1e-6f);
    // An unused vertex still gets a unit normal.
    m.positions.push_back(Vec3(5, 5, 5));
    generate_smooth_normals(m);
    EXPECT_NEAR(m.normals[5].norm(), 1.0f, 1e-6f);
}

TEST(MeshAttributes, TangentsFollowDpDuAndAreOrthogonalToNormals) {
    const Vec3 a = Vec3(1, 0.2f, 0.1f), b = Vec3(-0.1f, 0.3f, 1.2f);  // not orthogonal, not unit
    TriangleMesh m = tilted_quad(a, b);
    generate_smooth_normals(m);
    generate_tangents(m, 0);
    ASSERT_EQ(m.tangents.size(), 4u);
    for (size_t i = 0; i < 4; ++i) {
        Vec3 t = m.tangents[i].head<3>(), n = m.normals[i];
        EXPECT_NEAR(t.norm(), 1.0f, 1e-5f);
        EXPECT_NEAR(t.dot(n), 0.0f, 1e-5f);
        // On a plane the normal is exact, so the tangent is dP/du itself, normalised...
        EXPECT_NEAR((t - a.normalized()).norm(), 0.0f, 1e-5f);
        // ...and the bitangent cross(n, t) * w points along -dP/dv = b (the image's up).
        EXPECT_EQ(m.tangents[i].w(), 1.0f);
        EXPECT_GT((n.cross(t) * m.tangents[i].w()).dot(b), 0.0f);
    }
}

TEST(MeshAttributes, MirroredUvsFlipTheHandedness) {
    const Vec3 a = Vec3::UnitX(), b = Vec3::UnitY();
    TriangleMesh m = tilted_quad(a, b, /*mirror_u=*/true);
    generate_smooth_normals(m);
    generate_tangents(m, 0);
    for (const Vec4& t : m.tangents) {
        EXPECT_NEAR((t.head<3>() + a).norm(), 0.0f, 1e-5f);  // u now grows along -a
        EXPECT_EQ(t.w(), -1.0f);
    }
}

TEST(MeshAttributes, TangentsWithoutUvsAreStillAUnitFrame) {
    TriangleMesh m = tilted_quad(Vec3::UnitX(), Vec3::UnitY());
    m.texcoords[0].clear();
    generate_tangents(m, 0);  // also generates the missing normals
    ASSERT_EQ(m.normals.size(), 4u);
    for (size_t i = 0; i < 4; ++i) {
        EXPECT_NEAR(m.tangents[i].head<3>().norm(), 1.0f, 1e-5f);
        EXPECT_NEAR(m.tangents[i].head<3>().dot(m.normals[i]), 0.0f, 1e-5f);
        EXPECT_EQ(std::abs(m.tangents[i].w()), 1.0f);
    }
}

// The authored (MikkTSpace) TANGENTs of NormalTangentMirrorTest, whose UVs are mirrored on half
// the model: the generated tangents must agree in direction and, above all, in handedness.
TEST(MeshAttributes, GeneratedTangentsAgreeWithAuthoredOnesOnMirroredUvs) {
    DYNSKY_REQUIRE_SHARED();
    Scene s = load_gltf(test::shared_path("scenes/NormalTangentMirrorTest/NormalTangentMirrorTest.glb"));
    size_t vertices = 0, same_w = 0, aligned = 0, negative_w = 0;
    for (const MeshGroup& g : s.meshes)
        for (const TriangleMesh& authored : g.primitives) {
            TriangleMesh m = authored;
            m.tangents.clear();
            generate_tangents(m, 0);
            for (size_t i = 0; i < m.tangents.size(); ++i) {
                ++vertices;
                negative_w += authored.tangents[i].w() < 0;
                same_w += m.tangents[i].w() == authored.tangents[i].w();
                aligned += m.tangents[i].head<3>().dot(authored.tangents[i].head<3>()) > 0.9f;
            }
        }
    ASSERT_GT(vertices, 1000u);
    // The file really has both handednesses (80 of its 2770 vertices are mirrored).
    EXPECT_GT(negative_w, 0u);
    EXPECT_LT(negative_w, vertices);
    EXPECT_GT(double(same_w) / double(vertices), 0.99);
    EXPECT_GT(double(aligned) / double(vertices), 0.95);
}

}  // namespace
}  // namespace dynsky
