// Ray tracing on Embree 3: each glTF mesh (MeshGroup) is one Embree scene built once; every node
// that uses it is an Embree instance of it. Alpha MASK/BLEND is resolved by the caller (the
// integrator) by continuing rays, so no filter callbacks run inside traversal.
#pragma once

#include <embree3/rtcore.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "renderer/scene.h"

namespace dynsky {

struct Ray {
    Vec3 origin, direction;  // direction need not be unit
    float tmin = 0, tmax = std::numeric_limits<float>::infinity();
};

// Float epsilons of the coordinates' magnitude bounding the error of a hit's position (accel.cpp).
constexpr float kHitPositionErrorUlps = 32;

// Everything the integrator needs at a hit, in world space.
struct SurfaceHit {
    float t = 0;
    Vec3 position;
    // A bound on the float error of `position` along each axis: rays leaving the surface start this
    // far off it (offset_ray_origin), whatever the scene's size and distance from the origin.
    float position_error = 0;
    Vec3 geometric_normal;            // unit, from the triangle's winding (front side per glTF CCW)
    Vec3 shading_normal;              // unit, interpolated vertex normal
    Vec4 tangent = Vec4(0, 0, 0, 0);  // xyz unit, w handedness; zero if the mesh has none
    Vec2 texcoord[2] = {Vec2::Zero(), Vec2::Zero()};
    Vec4 color = Vec4::Ones();
    const Material* material = nullptr;
    int instance = -1, primitive = -1, triangle = -1;
};

class Accel {
  public:
    explicit Accel(const Scene& scene);
    ~Accel();
    Accel(const Accel&) = delete;
    Accel& operator=(const Accel&) = delete;

    // all_attributes false (the integrator): texture coordinates only for materials with textures and
    // tangents only for normal-mapped ones (zero otherwise), and the geometric normal from Embree's,
    // so a hit reads no more of the mesh than its shading needs (the loads of unused vertex
    // attributes miss the cache and evict the BVH).
    bool intersect(const Ray& ray, SurfaceHit* hit, bool all_attributes = true) const;
    // Closest hits of n rays at once, through Embree's stream API with the coherent flag (for camera
    // rays, which Embree then traverses as packets). Each record is set up by setup_ray_hit first.
    void intersect_coherent(RTCRayHit* rays, unsigned n) const;
    static void setup_ray_hit(const Ray& ray, RTCRayHit* rh);
    // The SurfaceHit of a record that intersect_coherent filled (false: the ray missed); as intersect.
    bool surface_hit(const Ray& ray, const RTCRayHit& rh, SurfaceHit* hit, bool all_attributes = true) const;
    // Starts loading the mesh data surface_hit(..., false) will read for this record (a batch of
    // hits then waits on memory once, not once per hit).
    void prefetch(const RTCRayHit& rh) const;
    // Closest hit distance only (for benchmarks of raw traversal).
    bool intersect_raw(const Ray& ray, float* t) const;
    bool occluded(const Ray& ray) const;
    // Any material with alpha (MASK, BLEND) or transmission: shadow rays may pass its surfaces.
    bool has_non_opaque_materials() const { return has_non_opaque_; }
    const Scene& scene() const { return scene_; }
    Bounds3 bounds() const { return bounds_; }

  private:
    bool trace_closest(const Ray& ray, RTCRayHit* rh) const;
    // Whether surface_hit reads the index buffer of a hit on mesh (with per-triangle record `corners`).
    bool reads_indices(const TriangleMesh& mesh, const Material& material, int64_t corners, bool all_attributes) const;
    const Scene& scene_;
    RTCDevice device_ = nullptr;
    RTCScene top_ = nullptr;
    std::vector<RTCScene> mesh_scenes_;
    std::vector<Eigen::Matrix3f> normal_matrices_;  // per instance: inverse transpose of the linear part
    std::vector<float> handedness_;                 // per instance: -1 where it mirrors (det < 0), else 1
    // Per instance: its translation, and the largest world-space size of its stored coordinates
    // (|linear| x the mesh's largest |object-space coordinate|): what Embree's rounding in the
    // instance's own space scales with (SurfaceHit::position_error).
    std::vector<Vec3> instance_translation_;
    std::vector<float> instance_extent_;
    // The three vertex normals of every triangle (9 floats, primitives of all meshes one after the
    // other; corner_first_[group][primitive] is a primitive's first triangle, -1 without normals):
    // a hit then reads one record instead of the index buffer and three scattered normals. On huge
    // pages where the system allows it (fewer TLB misses on large scenes).
    struct FreeDeleter {
        void operator()(float* p) const;
    };
    std::unique_ptr<float[], FreeDeleter> corner_normals_;
    std::vector<std::vector<int64_t>> corner_first_;
    bool has_non_opaque_ = false;
    Bounds3 bounds_;
};

}  // namespace dynsky
