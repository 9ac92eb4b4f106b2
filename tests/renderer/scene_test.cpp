#include "renderer/scene.h"

#include <gtest/gtest.h>

namespace dynsky {
namespace {

TEST(Scene, FramingCameraSeesTheWholeBoundingSphere) {
    Bounds3 b;
    b.extend(Vec3(-2, 0, -1));
    b.extend(Vec3(4, 3, 5));
    Camera cam = frame_bounds_camera(b, 16.0f / 9.0f);
    Vec3 eye = cam.camera_to_world.translation();
    Vec3 forward = -(cam.camera_to_world.linear() * Vec3::UnitZ());
    Vec3 to_center = b.center() - eye;
    // Looks at the centre...
    EXPECT_NEAR(forward.dot(to_center.normalized()), 1.0f, 1e-5f);
    // ...from outside the bounding sphere, with the sphere inside the vertical field of view.
    float radius = 0.5f * b.diagonal().norm();
    EXPECT_GT(to_center.norm(), radius);
    EXPECT_LE(std::asin(radius / to_center.norm()), cam.yfov / 2 + 1e-6f);
    // Camera frame is orthonormal and right-handed.
    Eigen::Matrix3f r = cam.camera_to_world.linear();
    EXPECT_NEAR((r.transpose() * r - Eigen::Matrix3f::Identity()).norm(), 0.0f, 1e-5f);
    EXPECT_NEAR(r.determinant(), 1.0f, 1e-5f);
}

// A model a few millimetres across (or a hundred micrometres) fills the view as a metre-sized one
// does: the same framing scaled down, not the view of a 1 mm sphere around it.
TEST(Scene, FramingCameraScalesWithTinyModels) {
    for (float size : {1.0f, 4e-3f, 1e-4f}) {
        Bounds3 b;
        b.extend(Vec3(-size, 0, -size));
        b.extend(Vec3(size, size, size));
        const Camera cam = frame_bounds_camera(b, 1.5f);
        const float distance = (cam.camera_to_world.translation() - b.center()).norm();
        EXPECT_NEAR(distance / (0.5f * b.diagonal().norm()), 1.05f / std::sin(cam.yfov / 2), 1e-3f) << size;
    }
}

}  // namespace
}  // namespace dynsky
