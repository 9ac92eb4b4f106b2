// Geometry built in code: for tests (furnaces, MIS checks) and built-in scenes.
#pragma once

#include "renderer/scene.h"

namespace dynsky {

// Unit-radius UV sphere centred at the origin, with exact normals, UVs and tangents.
TriangleMesh make_sphere_mesh(int segments = 64, int rings = 32, int material = -1);
// A square of side `size` in the XZ plane at y = 0, facing +Y, with UVs and tangents.
TriangleMesh make_ground_quad_mesh(float size, int material = -1);
// Axis-aligned box from lo to hi, outward faces.
TriangleMesh make_box_mesh(const Vec3& lo, const Vec3& hi, int material = -1);

// Adds a mesh group with one primitive and one instance of it; returns the instance index.
int add_mesh_instance(Scene* scene, TriangleMesh mesh, const Eigen::Affine3f& transform, const std::string& name);

}  // namespace dynsky
