#include "renderer/accel.h"

#include <cstdlib>
#include <cstring>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "util/error.h"

namespace dynsky {

static void embree_error(void*, RTCError code, const char* message) {
    // Embree reports through this callback; surfacing it beats silent empty images.
    std::fprintf(stderr, "dynsky: Embree error %d: %s\n", int(code), message ? message : "");
}

Accel::Accel(const Scene& scene) : scene_(scene) {
    device_ = rtcNewDevice("threads=0");
    if (!device_)
        throw Error("Embree: could not create a device (error " + std::to_string(int(rtcGetDeviceError(nullptr))) +
                    ")");
    rtcSetDeviceErrorFunction(device_, embree_error, nullptr);

    for (const Material& m : scene.materials)
        if (m.alpha_mode != AlphaMode::Opaque || m.transmission > 0 || m.unlit) has_non_opaque_ = true;

    mesh_scenes_.resize(scene.meshes.size(), nullptr);
    for (size_t g = 0; g < scene.meshes.size(); ++g) {
        RTCScene ms = rtcNewScene(device_);
        rtcSetSceneBuildQuality(ms, RTC_BUILD_QUALITY_HIGH);
        const MeshGroup& group = scene.meshes[g];
        for (size_t p = 0; p < group.primitives.size(); ++p) {
            const TriangleMesh& mesh = group.primitives[p];
            RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
            // Copies (not shared buffers): Embree wants padding past the last vertex.
            auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                  3 * sizeof(float), mesh.positions.size()));
            for (size_t k = 0; k < mesh.positions.size(); ++k)
                std::memcpy(v + 3 * k, mesh.positions[k].data(), 3 * sizeof(float));
            auto* idx = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                       3 * sizeof(uint32_t), mesh.triangle_count()));
            std::memcpy(idx, mesh.indices.data(), mesh.triangle_count() * 3 * sizeof(uint32_t));
            rtcCommitGeometry(geom);
            rtcAttachGeometryByID(ms, geom, unsigned(p));
            rtcReleaseGeometry(geom);
        }
        rtcCommitScene(ms);
        mesh_scenes_[g] = ms;
    }

    // Per-triangle corner normals (see accel.h), on transparent huge pages when available.
    corner_first_.resize(scene.meshes.size());
    int64_t triangles = 0;
    for (size_t g = 0; g < scene.meshes.size(); ++g)
        for (const TriangleMesh& mesh : scene.meshes[g].primitives) {
            corner_first_[g].push_back(mesh.normals.empty() ? -1 : triangles);
            if (!mesh.normals.empty()) triangles += int64_t(mesh.triangle_count());
        }
    if (triangles > 0) {
        constexpr size_t kHuge = size_t(1) << 21;
        const size_t used = size_t(triangles) * 9 * sizeof(float);
        // Huge-page granules only where they pay (a small scene's records fit the cache anyway).
        const size_t align = used >= kHuge ? kHuge : 64;
        const size_t bytes = (used + align - 1) / align * align;
        corner_normals_.reset(static_cast<float*>(std::aligned_alloc(align, bytes)));
        if (!corner_normals_) throw Error("out of memory for the corner normals");
#if defined(MADV_HUGEPAGE)
        if (align == kHuge) madvise(corner_normals_.get(), bytes, MADV_HUGEPAGE);  // advice: refused is fine
#endif
        for (size_t g = 0; g < scene.meshes.size(); ++g)
            for (size_t p = 0; p < scene.meshes[g].primitives.size(); ++p) {
                const TriangleMesh& mesh = scene.meshes[g].primitives[p];
                if (corner_first_[g][p] < 0) continue;
                float* out = corner_normals_.get() + 9 * corner_first_[g][p];
                for (size_t k = 0; k < mesh.indices.size(); ++k)
                    std::memcpy(out + 3 * k, mesh.normals[mesh.indices[k]].data(), 3 * sizeof(float));
            }
    }

    std::vector<float> group_extent(scene.meshes.size(), 0.0f);
    for (size_t g = 0; g < scene.meshes.size(); ++g)
        for (const TriangleMesh& mesh : scene.meshes[g].primitives)
            for (const Vec3& p : mesh.positions) group_extent[g] = std::max(group_extent[g], p.cwiseAbs().maxCoeff());
    instance_extent_.resize(scene.instances.size());
    instance_translation_.resize(scene.instances.size());
    top_ = rtcNewScene(device_);
    normal_matrices_.resize(scene.instances.size());
    handedness_.resize(scene.instances.size());
    for (size_t i = 0; i < scene.instances.size(); ++i) {
        const Instance& inst = scene.instances[i];
        RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(geom, mesh_scenes_[size_t(inst.mesh_group)]);
        Eigen::Matrix4f m = inst.transform.matrix();
        rtcSetGeometryTransform(geom, 0, RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR, m.data());
        rtcCommitGeometry(geom);
        rtcAttachGeometryByID(top_, geom, unsigned(i));
        rtcReleaseGeometry(geom);
        normal_matrices_[i] = inst.transform.linear().inverse().transpose();
        handedness_[i] = inst.transform.linear().determinant() < 0 ? -1.0f : 1.0f;
        instance_extent_[i] = inst.transform.linear().cwiseAbs().rowwise().sum().maxCoeff() *
                              group_extent[size_t(inst.mesh_group)];
        instance_translation_[i] = inst.transform.translation();
    }
    rtcCommitScene(top_);
    RTCBounds b;
    rtcGetSceneBounds(top_, &b);
    if (b.lower_x <= b.upper_x) {
        bounds_.extend(Vec3(b.lower_x, b.lower_y, b.lower_z));
        bounds_.extend(Vec3(b.upper_x, b.upper_y, b.upper_z));
    }
}

void Accel::FreeDeleter::operator()(float* p) const { std::free(p); }

Accel::~Accel() {
    if (top_) rtcReleaseScene(top_);
    for (RTCScene s : mesh_scenes_)
        if (s) rtcReleaseScene(s);
    if (device_) rtcReleaseDevice(device_);
}

static void setup_ray(const Ray& ray, RTCRay* r) {
    r->org_x = ray.origin.x(), r->org_y = ray.origin.y(), r->org_z = ray.origin.z();
    r->dir_x = ray.direction.x(), r->dir_y = ray.direction.y(), r->dir_z = ray.direction.z();
    r->tnear = ray.tmin, r->tfar = ray.tmax;
    r->mask = 0xFFFFFFFFu, r->flags = 0, r->time = 0, r->id = 0;
}

bool Accel::trace_closest(const Ray& ray, RTCRayHit* rh) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    setup_ray(ray, &rh->ray);
    rh->hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh->hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(top_, &ctx, rh);
    return rh->hit.geomID != RTC_INVALID_GEOMETRY_ID;
}

bool Accel::intersect_raw(const Ray& ray, float* t) const {
    RTCRayHit rh;
    if (!trace_closest(ray, &rh)) return false;
    *t = rh.ray.tfar;
    return true;
}

void Accel::setup_ray_hit(const Ray& ray, RTCRayHit* rh) {
    setup_ray(ray, &rh->ray);
    rh->hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh->hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

void Accel::intersect_coherent(RTCRayHit* rays, unsigned n) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    rtcIntersect1M(top_, &ctx, rays, n, sizeof(RTCRayHit));
}

bool Accel::intersect(const Ray& ray, SurfaceHit* hit, bool all_attributes) const {
    RTCRayHit rh;
    if (!trace_closest(ray, &rh)) return false;
    return surface_hit(ray, rh, hit, all_attributes);
}

static bool has_textures(const Material& m) {
    return m.base_color_texture.present() || m.metallic_roughness_texture.present() || m.normal_texture.present() ||
           m.emissive_texture.present() || m.occlusion_texture.present();
}

bool Accel::reads_indices(const TriangleMesh& mesh, const Material& material, int64_t corners,
                          bool all_attributes) const {
    // The index buffer only when some attribute needs it (the corner normals serve the rest).
    return all_attributes || has_textures(material) || !mesh.colors.empty() || (!mesh.normals.empty() && corners < 0);
}

void Accel::prefetch(const RTCRayHit& rh) const {
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return;
    const Instance& instance = scene_.instances[size_t(rh.hit.instID[0])];
    const TriangleMesh& mesh = scene_.meshes[size_t(instance.mesh_group)].primitives[rh.hit.geomID];
    const int64_t corners = corner_first_[size_t(instance.mesh_group)][rh.hit.geomID];
    const uint32_t tri = rh.hit.primID;
    if (reads_indices(mesh, scene_.material(mesh.material), corners, false)) {
        __builtin_prefetch(&mesh.indices[3 * size_t(tri)]);
    } else if (corners >= 0) {
        const float* c = corner_normals_.get() + 9 * (corners + int64_t(tri));
        __builtin_prefetch(c), __builtin_prefetch(c + 8);  // 36 bytes: may straddle two lines
    }
}

bool Accel::surface_hit(const Ray& ray, const RTCRayHit& rh, SurfaceHit* hit, bool all_attributes) const {
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;

    int inst = int(rh.hit.instID[0]);
    const Instance& instance = scene_.instances[size_t(inst)];
    const TriangleMesh& mesh = scene_.meshes[size_t(instance.mesh_group)].primitives[rh.hit.geomID];
    uint32_t tri = rh.hit.primID;
    float b1 = rh.hit.u, b2 = rh.hit.v, b0 = 1 - b1 - b2;
    const Material& material = scene_.material(mesh.material);
    const bool textured = has_textures(material);
    const int64_t corners = corner_first_[size_t(instance.mesh_group)][rh.hit.geomID];
    const bool indexed = reads_indices(mesh, material, corners, all_attributes);
    uint32_t i0 = 0, i1 = 0, i2 = 0;
    if (indexed) i0 = mesh.indices[3 * tri], i1 = mesh.indices[3 * tri + 1], i2 = mesh.indices[3 * tri + 2];

    hit->t = rh.ray.tfar;
    hit->position = ray.origin + hit->t * ray.direction;
    // o + t d carries the rounding of t and of the sum: a few float epsilons of |o| + t |d| along
    // each axis; Embree's t that of the vertices and the ray in the instance's own space, whose
    // coordinates are |o - T|, |p - T| and the mesh's extent in world units (geometry stored 3 km
    // out and placed back by its node, or a triangle a kilometre across: an audit's rays re-hit
    // their own triangle 28 % of the time with |o| + t |d| alone). kHitPositionErrorUlps of the
    // largest leave a wide margin (pbrt-v4 bounds the barycentric form by gamma(7), 7 epsilons)
    // and stay far below any feature a scene's float positions resolve. A fixed 1e-4 x max(1, |p|)
    // before started shadow rays 1 m off the surface 10 km from the origin (shadows gone, a closed
    // room lit from outside) and 0.1 mm off a model authored in millimetres (contact shadows cut).
    const Vec3& translation = instance_translation_[size_t(inst)];
    const float own = std::max({(ray.origin - translation).cwiseAbs().maxCoeff(),
                                (hit->position - translation).cwiseAbs().maxCoeff(), instance_extent_[size_t(inst)]});
    hit->position_error = kHitPositionErrorUlps * std::numeric_limits<float>::epsilon() *
                          std::max(ray.origin.cwiseAbs().maxCoeff() + hit->t * ray.direction.cwiseAbs().maxCoeff(),
                                   own);
    hit->instance = inst, hit->primitive = int(rh.hit.geomID), hit->triangle = int(tri);
    hit->material = &material;

    const Eigen::Matrix3f& nm = normal_matrices_[size_t(inst)];
    Vec3 ng;
    if (all_attributes) {
        const Vec3 &p0 = mesh.positions[i0], &p1 = mesh.positions[i1], &p2 = mesh.positions[i2];
        ng = nm * (p1 - p0).cross(p2 - p0);
    } else {
        // Embree's normal (object space for instances; its sign does not matter, shading puts the
        // normals on the viewer's side).
        ng = nm * Vec3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
    }
    float len = ng.norm();
    hit->geometric_normal = len > 0 ? Vec3(ng / len) : Vec3(0, 1, 0);
    if (!mesh.normals.empty() && !indexed) {
        const float* c = corner_normals_.get() + 9 * (corners + int64_t(tri));
        Vec3 ns = nm * (b0 * Vec3(c[0], c[1], c[2]) + b1 * Vec3(c[3], c[4], c[5]) + b2 * Vec3(c[6], c[7], c[8]));
        float l = ns.norm();
        hit->shading_normal = l > 0 ? Vec3(ns / l) : hit->geometric_normal;
    } else if (!mesh.normals.empty()) {
        Vec3 ns = nm * (b0 * mesh.normals[i0] + b1 * mesh.normals[i1] + b2 * mesh.normals[i2]);
        float l = ns.norm();
        hit->shading_normal = l > 0 ? Vec3(ns / l) : hit->geometric_normal;
    } else {
        hit->shading_normal = hit->geometric_normal;
    }
    if (!mesh.tangents.empty() && (all_attributes || material.normal_texture.present())) {
        Vec4 t = b0 * mesh.tangents[i0] + b1 * mesh.tangents[i1] + b2 * mesh.tangents[i2];
        Vec3 tw = instance.transform.linear() * t.head<3>();
        float l = tw.norm();
        // A mirroring instance turns the frame's handedness: the bitangent n x t w it gives would
        // point against the object's own (the normal map's green channel flipped on a mirrored half).
        const float w = (mesh.tangents[i0].w() < 0 ? -1.0f : 1.0f) * handedness_[size_t(inst)];
        hit->tangent = l > 0 ? Vec4(tw.x() / l, tw.y() / l, tw.z() / l, w) : Vec4::Zero();
    } else {
        hit->tangent = Vec4::Zero();
    }
    for (int k = 0; k < 2; ++k) {
        const auto& uv = mesh.texcoords[k];
        hit->texcoord[k] = uv.empty() || !(all_attributes || textured) ? Vec2::Zero()
                                                                       : Vec2(b0 * uv[i0] + b1 * uv[i1] + b2 * uv[i2]);
    }
    hit->color = mesh.colors.empty() ? Vec4::Ones()
                                     : Vec4(b0 * mesh.colors[i0] + b1 * mesh.colors[i1] + b2 * mesh.colors[i2]);
    return true;
}

bool Accel::occluded(const Ray& ray) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay r;
    setup_ray(ray, &r);
    rtcOccluded1(top_, &ctx, &r);
    return r.tfar < 0;  // Embree sets tfar = -inf on a hit
}

}  // namespace dynsky
