#include "renderer/accel.h"

#include <gtest/gtest.h>

#include <cmath>

#include "renderer/shapes.h"

namespace dynsky {
namespace {

void expect_vec3(const Vec3& got, const Vec3& want, float tol = 1e-5f) {
    EXPECT_NEAR((got - want).norm(), 0.0f, tol) << "got (" << got.transpose() << "), want (" << want.transpose() << ")";
}

// One triangle in the z = 0 plane, counter-clockwise seen from +z, with a UV and colour per corner.
TriangleMesh unit_triangle(int material = -1) {
    TriangleMesh m;
    m.material = material;
    m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
    m.texcoords[0] = {Vec2(0, 0), Vec2(1, 0), Vec2(0, 1)};
    m.colors = {Vec4(1, 0, 0, 1), Vec4(0, 1, 0, 1), Vec4(0, 0, 1, 1)};
    m.indices = {0, 1, 2};
    return m;
}

TEST(Accel, RayHitsATriangleAtTheRightDistanceWithInterpolatedAttributes) {
    Scene scene;
    add_mesh_instance(&scene, unit_triangle(), Eigen::Affine3f::Identity(), "triangle");
    Accel accel(scene);
    Ray ray{Vec3(0.25f, 0.5f, 2.0f), Vec3(0, 0, -1)};
    SurfaceHit hit;
    ASSERT_TRUE(accel.intersect(ray, &hit));
    EXPECT_NEAR(hit.t, 2.0f, 1e-6f);
    expect_vec3(hit.position, Vec3(0.25f, 0.5f, 0));
    expect_vec3(hit.geometric_normal, Vec3(0, 0, 1));  // CCW from +z faces +z
    expect_vec3(hit.shading_normal, Vec3(0, 0, 1));    // no vertex normals: the geometric one
    // Barycentrics (0.25, 0.5, 0.25 for corners 1, 2, 0): uv = (0.25, 0.5), colour = (0.25, 0.25, 0.5).
    EXPECT_NEAR(hit.texcoord[0].x(), 0.25f, 1e-6f);
    EXPECT_NEAR(hit.texcoord[0].y(), 0.5f, 1e-6f);
    EXPECT_NEAR(hit.color.x(), 0.25f, 1e-6f);
    EXPECT_NEAR(hit.color.y(), 0.25f, 1e-6f);
    EXPECT_NEAR(hit.color.z(), 0.5f, 1e-6f);
    EXPECT_EQ(hit.tangent, Vec4::Zero());  // the mesh has none
    EXPECT_EQ(hit.instance, 0);
    EXPECT_EQ(hit.primitive, 0);
    EXPECT_EQ(hit.triangle, 0);
    EXPECT_EQ(hit.material, &Scene::default_material());
    // From below: same distance, the normal still follows the winding (+z).
    ASSERT_TRUE(accel.intersect(Ray{Vec3(0.25f, 0.5f, -3.0f), Vec3(0, 0, 1)}, &hit));
    EXPECT_NEAR(hit.t, 3.0f, 1e-6f);
    expect_vec3(hit.geometric_normal, Vec3(0, 0, 1));
    float t = 0;
    ASSERT_TRUE(accel.intersect_raw(ray, &t));
    EXPECT_NEAR(t, 2.0f, 1e-6f);
}

// The tangent frame of a mirrored instance: t, n and the bitangent n x t w must follow the texture's
// u and v on the surface (M dP/du, M dP/dv) as they do unmirrored. Mirroring turns the frame's
// handedness; kept at the mesh's w, a normal map's green channel bent the other way on the mirrored
// half of a symmetric model (a node scaled -1 in x: 0.22 for 0.71 under a sky bright in the north).
TEST(Accel, MirroredInstancesKeepTheNormalMapsBitangentAlongV) {
    TriangleMesh m = unit_triangle();
    m.normals.assign(3, Vec3(0, 0, 1));
    m.tangents.assign(3, Vec4(1, 0, 0, 1));  // u along +x, v along +y: n x t = +y, w = 1
    for (const Vec3& scale : {Vec3(1, 1, 1), Vec3(-1, 1, 1), Vec3(1, -1, 1), Vec3(1, 1, -1), Vec3(-1, -1, -1)}) {
        Scene scene;
        Eigen::Affine3f transform = Eigen::Affine3f::Identity();
        transform.scale(scale);
        add_mesh_instance(&scene, m, transform, "triangle");
        Accel accel(scene);
        const Vec3 at = transform * Vec3(0.25f, 0.5f, 0);
        SurfaceHit hit;
        ASSERT_TRUE(accel.intersect(Ray{at + Vec3(0, 0, 2), Vec3(0, 0, -1)}, &hit));
        const Vec3 t = hit.tangent.head<3>(), b = hit.shading_normal.cross(t) * hit.tangent.w();
        expect_vec3(t, transform.linear() * Vec3(1, 0, 0));  // M dP/du
        expect_vec3(b, transform.linear() * Vec3(0, 1, 0));  // M dP/dv
    }
}

TEST(Accel, RaysThatPassBesideOrAwayMiss) {
    Scene scene;
    add_mesh_instance(&scene, unit_triangle(), Eigen::Affine3f::Identity(), "triangle");
    Accel accel(scene);
    SurfaceHit hit;
    float t;
    EXPECT_FALSE(accel.intersect(Ray{Vec3(0.6f, 0.6f, 2.0f), Vec3(0, 0, -1)}, &hit));  // beyond the hypotenuse
    EXPECT_FALSE(accel.intersect(Ray{Vec3(-0.1f, 0.5f, 2.0f), Vec3(0, 0, -1)}, &hit));
    EXPECT_FALSE(accel.intersect(Ray{Vec3(0.25f, 0.25f, 2.0f), Vec3(0, 0, 1)}, &hit));  // pointing away
    EXPECT_FALSE(accel.intersect(Ray{Vec3(0.25f, 0.25f, 2.0f), Vec3(1, 0, 0)}, &hit));  // parallel
    EXPECT_FALSE(accel.intersect_raw(Ray{Vec3(0.6f, 0.6f, 2.0f), Vec3(0, 0, -1)}, &t));
    EXPECT_FALSE(accel.occluded(Ray{Vec3(0.6f, 0.6f, 2.0f), Vec3(0, 0, -1)}));
}

TEST(Accel, BoxHitsRespectTheRaySegmentAndUnnormalisedDirections) {
    Scene scene;
    Material red;
    red.base_color = Color(1, 0, 0);
    scene.materials.push_back(red);
    // A 2 m cube centred 5 m down -z: its near face at z = -4, far face at z = -6.
    add_mesh_instance(&scene, make_box_mesh(Vec3(-1, -1, -1), Vec3(1, 1, 1), 0),
                      Eigen::Affine3f(Eigen::Translation3f(0, 0, -5)), "box");
    Accel accel(scene);
    const Bounds3 b = accel.bounds();
    expect_vec3(b.lo, Vec3(-1, -1, -6));
    expect_vec3(b.hi, Vec3(1, 1, -4));
    EXPECT_FALSE(accel.has_non_opaque_materials());

    SurfaceHit hit;
    ASSERT_TRUE(accel.intersect(Ray{Vec3(0.3f, -0.2f, 0), Vec3(0, 0, -1)}, &hit));
    EXPECT_NEAR(hit.t, 4.0f, 1e-5f);
    expect_vec3(hit.position, Vec3(0.3f, -0.2f, -4));
    expect_vec3(hit.geometric_normal, Vec3(0, 0, 1));  // outward
    expect_vec3(hit.shading_normal, Vec3(0, 0, 1));
    EXPECT_EQ(hit.material, &scene.materials[0]);
    EXPECT_NEAR(hit.tangent.head<3>().dot(Vec3(0, 0, 1)), 0.0f, 1e-6f);  // tangent lies in the face
    EXPECT_NEAR(hit.tangent.head<3>().norm(), 1.0f, 1e-6f);
    // t is in units of the direction's length: twice as long a direction, half the t.
    ASSERT_TRUE(accel.intersect(Ray{Vec3(0.3f, -0.2f, 0), Vec3(0, 0, -2)}, &hit));
    EXPECT_NEAR(hit.t, 2.0f, 1e-5f);
    expect_vec3(hit.position, Vec3(0.3f, -0.2f, -4));
    // tmax short of the box: nothing; tmin past the near face: the far face from inside.
    EXPECT_FALSE(accel.intersect(Ray{Vec3(0, 0, 0), Vec3(0, 0, -1), 0.0f, 3.9f}, &hit));
    ASSERT_TRUE(accel.intersect(Ray{Vec3(0, 0, 0), Vec3(0, 0, -1), 4.5f}, &hit));
    EXPECT_NEAR(hit.t, 6.0f, 1e-5f);
    expect_vec3(hit.geometric_normal, Vec3(0, 0, -1));  // the far face's outward normal
    EXPECT_FALSE(accel.intersect(Ray{Vec3(0, 0, 0), Vec3(0, 0, -1), 6.1f}, &hit));
    // A slanted ray into the +x face: from (4, 0.5, -1.5) along (-3, 0, -4) / 5 it passes the
    // near face's plane at x = 2.125 (beside the box) and meets x = 1 at z = -5.5, 5 m on.
    Vec3 origin(4, 0.5f, -1.5f), target(1, 0.5f, -5.5f);
    ASSERT_TRUE(accel.intersect(Ray{origin, (target - origin).normalized()}, &hit));
    EXPECT_NEAR(hit.t, 5.0f, 1e-5f);
    expect_vec3(hit.position, target, 1e-5f);
    expect_vec3(hit.geometric_normal, Vec3(1, 0, 0));
}

TEST(Accel, OcclusionQueriesSeeBlockersOnlyInsideTheSegment) {
    Scene scene;
    add_mesh_instance(&scene, make_box_mesh(Vec3(-1, -1, -1), Vec3(1, 1, 1)),
                      Eigen::Affine3f(Eigen::Translation3f(0, 0, -5)), "box");
    Accel accel(scene);
    const Vec3 o(0, 0, 0), d(0, 0, -1);
    EXPECT_TRUE(accel.occluded(Ray{o, d}));               // unbounded
    EXPECT_TRUE(accel.occluded(Ray{o, d, 0.0f, 4.1f}));   // reaches the near face
    EXPECT_FALSE(accel.occluded(Ray{o, d, 0.0f, 3.9f}));  // stops short
    EXPECT_FALSE(accel.occluded(Ray{o, d, 4.5f, 5.5f}));  // inside the box, between its faces
    EXPECT_TRUE(accel.occluded(Ray{o, d, 4.5f, 6.5f}));   // the far face
    EXPECT_FALSE(accel.occluded(Ray{o, d, 6.5f}));        // past the box
    EXPECT_FALSE(accel.occluded(Ray{o, Vec3(0, 0, 1)}));  // the other way
    EXPECT_FALSE(accel.occluded(Ray{o, Vec3(0, 1, 0)}));
}

TEST(Accel, InstancesShareAMeshUnderTheirOwnTransforms) {
    Scene scene;
    // One triangle mesh, two instances: one as is, one scaled by 2 in x and moved to z = -3.
    add_mesh_instance(&scene, unit_triangle(), Eigen::Affine3f::Identity(), "triangle");
    Instance second;
    second.mesh_group = 0;
    second.transform = Eigen::Translation3f(0, 0, -3) * Eigen::Scaling(2.0f, 1.0f, 1.0f);
    scene.instances.push_back(second);
    Accel accel(scene);
    SurfaceHit hit;
    // x = 1.5, y = 0.2 lies outside the first (x + y <= 1) but inside the second (x / 2 + y <= 1).
    ASSERT_TRUE(accel.intersect(Ray{Vec3(1.5f, 0.2f, 1), Vec3(0, 0, -1)}, &hit));
    EXPECT_EQ(hit.instance, 1);
    EXPECT_NEAR(hit.t, 4.0f, 1e-5f);
    expect_vec3(hit.position, Vec3(1.5f, 0.2f, -3));
    EXPECT_NEAR(hit.texcoord[0].x(), 0.75f, 1e-5f);  // local x = 0.75
    // Inside both: the nearer one.
    ASSERT_TRUE(accel.intersect(Ray{Vec3(0.2f, 0.2f, 1), Vec3(0, 0, -1)}, &hit));
    EXPECT_EQ(hit.instance, 0);
    EXPECT_NEAR(hit.t, 1.0f, 1e-5f);
    ASSERT_TRUE(accel.intersect(Ray{Vec3(0.2f, 0.2f, -1), Vec3(0, 0, -1)}, &hit));
    EXPECT_EQ(hit.instance, 1);
    EXPECT_NEAR(hit.t, 2.0f, 1e-5f);
}

TEST(Accel, NormalsTransformWithTheInverseTranspose) {
    // A triangle in the plane x + y = 1 (normal (1, 1, 0) / sqrt 2), with vertex normals, under a
    // scale of 2 in x: the plane becomes x / 2 + y = 1, normal (1/2, 1, 0) normalised, which the
    // plain linear map would get wrong ((2, 1, 0)).
    TriangleMesh m;
    m.positions = {Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 1, 1)};
    Vec3 n = Vec3(1, 1, 0).normalized();
    m.normals.assign(3, n);
    m.indices = {0, 1, 2};
    ASSERT_GT((m.positions[1] - m.positions[0]).cross(m.positions[2] - m.positions[0]).dot(n), 0) << "winding";
    Scene scene;
    add_mesh_instance(&scene, m, Eigen::Affine3f(Eigen::Scaling(2.0f, 1.0f, 1.0f)), "slanted");
    Accel accel(scene);
    SurfaceHit hit;
    // Along -x at y = 0.5, z = 0.25: the plane x / 2 + y = 1 is at x = 1.
    ASSERT_TRUE(accel.intersect(Ray{Vec3(5, 0.5f, 0.25f), Vec3(-1, 0, 0)}, &hit));
    EXPECT_NEAR(hit.t, 4.0f, 1e-5f);
    const Vec3 want = Vec3(0.5f, 1, 0).normalized();
    expect_vec3(hit.geometric_normal, want);
    expect_vec3(hit.shading_normal, want);
}

TEST(Accel, NonOpaqueMaterialsAreReported) {
    Scene scene;
    Material glass;
    glass.alpha_mode = AlphaMode::Blend;
    scene.materials.push_back(glass);
    add_mesh_instance(&scene, unit_triangle(0), Eigen::Affine3f::Identity(), "triangle");
    Accel accel(scene);
    EXPECT_TRUE(accel.has_non_opaque_materials());
    EXPECT_EQ(&accel.scene(), &scene);
}

TEST(Accel, AnEmptySceneHitsNothing) {
    Scene scene;
    Accel accel(scene);
    SurfaceHit hit;
    EXPECT_FALSE(accel.intersect(Ray{Vec3(0, 0, 0), Vec3(0, 0, -1)}, &hit));
    EXPECT_FALSE(accel.occluded(Ray{Vec3(0, 0, 0), Vec3(0, 0, -1)}));
    EXPECT_TRUE(accel.bounds().empty());
}

}  // namespace
}  // namespace dynsky
