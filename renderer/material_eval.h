// Evaluating a glTF material at a hit: textures, vertex colour, normal mapping, shading frame.
#pragma once

#include "renderer/accel.h"

namespace dynsky {

struct ShadingPoint {
    Color base_color = Color::Ones();
    float metallic = 1, roughness = 1, specular = 1;
    Color specular_color = Color::Ones();          // KHR_materials_specular's F0 tint
    float transmission = 0;                        // KHR_materials_transmission (thin-walled)
    float clearcoat = 0, clearcoat_roughness = 0;  // KHR_materials_clearcoat
    Color sheen_color = Color::Zero();             // KHR_materials_sheen (black: none)
    float sheen_roughness = 0;
    float anisotropy = 0;                     // KHR_materials_anisotropy strength (the frame's tangent
                                              // is then its direction)
    float ior = 1.5f;                         // KHR_materials_ior
    Color transmission_tint = Color::Ones();  // KHR_materials_volume's absorption (Material::volume_tint)
    Color emission = Color::Zero();
    Vec3 geometric_normal;            // flipped to the side of wo
    Vec3 normal, tangent, bitangent;  // shading frame (normal-mapped), on the side of wo

    Vec3 to_local(const Vec3& w) const { return Vec3(w.dot(tangent), w.dot(bitangent), w.dot(normal)); }
    Vec3 to_world(const Vec3& w) const { return w.x() * tangent + w.y() * bitangent + w.z() * normal; }
};

// uv of a texture slot at a hit, through its KHR_texture_transform.
inline Vec2 texture_uv(const TextureSlot& slot, const SurfaceHit& hit) {
    const Vec2& uv = hit.texcoord[slot.texcoord == 1 ? 1 : 0];
    Eigen::Vector3f t = slot.uv_transform * Eigen::Vector3f(uv.x(), uv.y(), 1.0f);
    return Vec2(t.x(), t.y());
}

// The shading normal ns (on ng's side) bent towards the geometric normal ng just enough that wo's
// mirror reflection about it leaves the surface (at least min(0.9 ng.wo, 0.01) above it), as Cycles
// bends it: a normal tilted far from the geometric one (smooth shading of coarse meshes, strong
// normal maps) reflected glossy paths below the surface, which ended there, and mirror-like rims
// rendered black (NormalTangentMirrorTest: a black ring over half of each normal-mapped dome). ns
// unchanged where it is valid.
Vec3 lifted_shading_normal(const Vec3& ng, const Vec3& wo, const Vec3& ns);

// wo: world direction towards the viewer (unit).
ShadingPoint evaluate_material(const Scene& scene, const SurfaceHit& hit, const Vec3& wo);

}  // namespace dynsky
