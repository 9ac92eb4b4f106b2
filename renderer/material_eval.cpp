#include "renderer/material_eval.h"

namespace dynsky {

Vec3 lifted_shading_normal(const Vec3& ng, const Vec3& wo, const Vec3& ns) {
    const float threshold = std::min(0.9f * ng.dot(wo), 0.01f);
    auto valid = [&](const Vec3& n) {
        const float cos_o = n.dot(wo);
        return cos_o > 1e-4f && ng.dot(2 * cos_o * n - wo) >= threshold;
    };
    if (valid(ns)) return ns;
    // Along the arc from ns to ng (ng itself is valid: its reflection leaves at ng.wo), the
    // normal nearest ns that is, by bisection.
    auto between = [&](float s) { return Vec3((1 - s) * ns + s * ng).normalized(); };
    float lo = 0, hi = 1;
    for (int k = 0; k < 20; ++k) {
        const float mid = 0.5f * (lo + hi);
        (valid(between(mid)) ? hi : lo) = mid;
    }
    return between(hi);
}

ShadingPoint evaluate_material(const Scene& scene, const SurfaceHit& hit, const Vec3& wo) {
    const Material& m = *hit.material;
    ShadingPoint sp;
    auto tex = [&](const TextureSlot& slot) {
        return scene.textures[size_t(slot.texture)]->evaluate(texture_uv(slot, hit));
    };

    sp.base_color = m.base_color * hit.color.head<3>().array();
    if (m.base_color_texture.present()) sp.base_color *= tex(m.base_color_texture).head<3>().array();
    sp.metallic = m.metallic, sp.roughness = m.roughness, sp.specular = m.specular;
    if (m.metallic_roughness_texture.present()) {
        Vec4 t = tex(m.metallic_roughness_texture);
        sp.roughness *= t.y(), sp.metallic *= t.z();
    }
    if (m.glossiness_texture.present()) sp.roughness = 1 - m.glossiness * tex(m.glossiness_texture).w();
    if (m.specular_texture.present()) sp.specular *= tex(m.specular_texture).w();
    sp.specular_color = m.specular_color;
    if (m.specular_color_texture.present()) sp.specular_color *= tex(m.specular_color_texture).head<3>().array();
    sp.transmission = m.transmission;
    sp.ior = m.ior;
    sp.transmission_tint = m.volume_tint;
    if (m.transmission > 0 && m.transmission_texture.present()) sp.transmission *= tex(m.transmission_texture).x();
    if (m.clearcoat > 0) {
        sp.clearcoat = m.clearcoat, sp.clearcoat_roughness = m.clearcoat_roughness;
        if (m.clearcoat_texture.present()) sp.clearcoat *= tex(m.clearcoat_texture).x();
        if (m.clearcoat_roughness_texture.present()) sp.clearcoat_roughness *= tex(m.clearcoat_roughness_texture).y();
    }
    if ((m.sheen_color > 0).any()) {
        sp.sheen_color = m.sheen_color, sp.sheen_roughness = m.sheen_roughness;
        if (m.sheen_color_texture.present()) sp.sheen_color *= tex(m.sheen_color_texture).head<3>().array();
        if (m.sheen_roughness_texture.present()) sp.sheen_roughness *= tex(m.sheen_roughness_texture).w();
    }
    sp.emission = m.emissive;
    if (m.emissive_texture.present() && (m.emissive > 0).any())
        sp.emission *= tex(m.emissive_texture).head<3>().array();
    // occlusion_texture is not applied: a path tracer computes occlusion itself, and glTF defines
    // it as a rasteriser's approximation of exactly that.

    // Two-sided shading: put both normals on the viewer's side. Single-sided glTF materials are
    // only culled by rasterisers; seen from behind they would otherwise render black.
    Vec3 ng = hit.geometric_normal, ns = hit.shading_normal;
    if (ng.dot(wo) < 0) ng = -ng;
    if (ns.dot(ng) < 0) ns = -ns;

    Vec3 t;
    float handedness = 1;
    if (hit.tangent.head<3>().squaredNorm() > 0) {
        t = hit.tangent.head<3>();
        handedness = hit.tangent.w();
    } else {
        Vec3 b;
        orthonormal_basis(ns, &t, &b);
    }
    // Gram-Schmidt against the interpolated normal.
    t = (t - ns * ns.dot(t));
    if (t.squaredNorm() < 1e-12f) {
        Vec3 b;
        orthonormal_basis(ns, &t, &b);
    }
    t.normalize();
    Vec3 b = ns.cross(t) * handedness;
    if (hit.shading_normal.dot(ns) < 0) b = -b;  // flipped frame keeps the texture's orientation

    if (m.normal_texture.present() && hit.tangent.head<3>().squaredNorm() > 0) {
        Vec4 c = tex(m.normal_texture);
        Vec3 nt(2 * c.x() - 1, 2 * c.y() - 1, 2 * c.z() - 1);
        nt.x() *= m.normal_texture.scale, nt.y() *= m.normal_texture.scale;
        Vec3 n = (nt.x() * t + nt.y() * b + nt.z() * ns);
        if (n.squaredNorm() > 0) {
            n.normalize();
            if (n.dot(ng) > 0) ns = n;  // a mapped normal facing away from the surface is ignored
        }
    }
    ns = lifted_shading_normal(ng, wo, ns);
    sp.geometric_normal = ng;
    sp.normal = ns;
    sp.tangent = (t - ns * ns.dot(t));
    if (sp.tangent.squaredNorm() < 1e-12f) {
        Vec3 bb;
        orthonormal_basis(ns, &sp.tangent, &bb);
    }
    sp.tangent.normalize();
    sp.bitangent = ns.cross(sp.tangent);
    if (m.anisotropy_strength > 0) {
        // The direction in the texture's tangent frame (its bitangent keeps the mesh's handedness),
        // turned by the rotation; the shading frame's tangent is then that direction.
        float dx = std::cos(m.anisotropy_rotation), dy = std::sin(m.anisotropy_rotation);
        sp.anisotropy = m.anisotropy_strength;
        if (m.anisotropy_texture.present()) {
            const Vec4 a = tex(m.anisotropy_texture);
            float tx = 2 * a.x() - 1, ty = 2 * a.y() - 1;
            const float len = std::hypot(tx, ty);
            if (len > 0) tx /= len, ty /= len;
            else tx = 1, ty = 0;
            const float rx = dx * tx - dy * ty, ry = dy * tx + dx * ty;
            dx = rx, dy = ry;
            sp.anisotropy *= a.z();
        }
        const float sign = (b.dot(sp.bitangent) < 0) ? -1.0f : 1.0f;
        const Vec3 along = (dx * sp.tangent + dy * sign * sp.bitangent).normalized();
        sp.tangent = along;
        sp.bitangent = ns.cross(along);
    }
    return sp;
}

}  // namespace dynsky
