// The renderer's scene: plain data filled by a loader (renderer/gltf_loader.h) or built in code,
// then handed to the ray-tracing accelerator (renderer/accel.h). Units: metres, world frame of
// ../shared/CONVENTIONS.md (+Y up).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "renderer/texture.h"
#include "util/math.h"

namespace dynsky {

// A texture slot of a material: which texture, which UV set, and KHR_texture_transform.
struct TextureSlot {
    int texture = -1;  // index into Scene::textures, -1 for none
    int texcoord = 0;  // TEXCOORD_n
    // uv' = uv_transform * (u, v, 1): glTF's KHR_texture_transform (offset, rotation, scale).
    Eigen::Matrix3f uv_transform = Eigen::Matrix3f::Identity();
    float scale = 1.0f;  // normalTexture.scale or occlusionTexture.strength
    bool present() const { return texture >= 0; }
};

enum class AlphaMode { Opaque, Mask, Blend };

// Single-precision ray tracing resolves nothing of a scene or camera placed farther out (the ray
// offsets, the BVH): 1e10 m already rendered differently, 1e20 as sky alone, and a camera at 1e20 m
// made rays Embree rejects. Geometry, cameras and --look-at points must lie within this of the origin.
inline constexpr double kMaxSceneCoordinate = 1e8;  // metres

// glTF 2.0 metallic-roughness material (core spec, plus KHR_materials_emissive_strength, _specular
// (its factor), _transmission and _clearcoat).
struct Material {
    std::string name;
    Color base_color = Color::Ones();
    float base_alpha = 1.0f;
    TextureSlot base_color_texture;  // sRGB RGBA
    float metallic = 1.0f, roughness = 1.0f;
    TextureSlot metallic_roughness_texture;  // linear: G roughness, B metallic
    float specular = 1.0f;                   // KHR_materials_specular specularFactor (0: pure Lambert base)
    TextureSlot specular_texture;            // linear A x specular
    Color specular_color = Color::Ones();    // KHR_materials_specular specularColorFactor (F0 tint)
    TextureSlot specular_color_texture;      // sRGB RGB x specular_color
    float ior = 1.5f;                        // KHR_materials_ior: the dielectric's F0 = ((ior - 1) / (ior + 1))^2
    // KHR_materials_transmission, thin-walled (no KHR_materials_volume): the share of the dielectric
    // base that passes straight through the surface, tinted by the base colour, instead of
    // scattering diffusely (bsdf.h MetalRoughBsdf::transmitted).
    float transmission = 0.0f;
    TextureSlot transmission_texture;  // linear R
    // KHR_materials_volume, rendered thin: what passes is tinted once by the slab's absorption,
    // attenuationColor^(thicknessFactor / attenuationDistance) (no refraction, no node scale).
    Color volume_tint = Color::Ones();
    // KHR_materials_clearcoat: a clear dielectric layer over the material (bsdf.h set_clearcoat).
    float clearcoat = 0.0f, clearcoat_roughness = 0.0f;
    TextureSlot clearcoat_texture;            // linear R x clearcoat
    TextureSlot clearcoat_roughness_texture;  // linear G x clearcoat_roughness
    // KHR_materials_sheen: a layer of micro-fibres (velvet, cloth) over the base, under the coat
    // (bsdf.h set_sheen). Black: none.
    Color sheen_color = Color::Zero();
    float sheen_roughness = 0.0f;
    TextureSlot sheen_color_texture;      // sRGB RGB x sheen_color
    TextureSlot sheen_roughness_texture;  // linear A x sheen_roughness
    // KHR_materials_pbrSpecularGlossiness (older exports): roughness = 1 - glossiness x this texture's
    // A (linear), replacing roughness where present; the rest of the model maps onto the fields
    // above (gltf_loader.cpp read_specular_glossiness).
    float glossiness = 1.0f;
    TextureSlot glossiness_texture;
    // KHR_materials_anisotropy: the specular lobe stretched along a direction in the tangent plane,
    // the tangent turned by rotation (radians, counter-clockwise towards the bitangent), or by the
    // texture's RG (a direction in tangent space, [0, 1] for [-1, 1]) then turned; strength times
    // the texture's B (linear). 0: isotropic.
    float anisotropy_strength = 0.0f, anisotropy_rotation = 0.0f;
    TextureSlot anisotropy_texture;
    TextureSlot normal_texture;      // linear, tangent space, scale in slot.scale
    TextureSlot occlusion_texture;   // linear R, strength in slot.scale
    Color emissive = Color::Zero();  // already multiplied by emissive_strength
    TextureSlot emissive_texture;    // sRGB
    AlphaMode alpha_mode = AlphaMode::Opaque;
    float alpha_cutoff = 0.5f;
    bool double_sided = false;
    // KHR_materials_unlit (lighting baked into the base colour): the camera sees the base colour as
    // a surface of that albedo in the open under the sky (base x E_sky / pi, as the ground is
    // shown), and every other ray passes through: it neither reflects, lights nor shadows the scene
    // (as Blender's glTF importer makes it, which emits the base colour at strength 1 instead).
    bool unlit = false;
};

// One triangle primitive (glTF mesh primitive), in its mesh's local frame. Triangles only:
// strips and fans are converted, and non-indexed primitives get 0..n-1 indices, by the loader.
struct TriangleMesh {
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;       // per vertex, unit; generated when missing
    std::vector<Vec4> tangents;      // xyz unit, w = handedness +-1; generated when missing
    std::vector<Vec2> texcoords[2];  // TEXCOORD_0 and TEXCOORD_1 (empty when absent)
    std::vector<Vec4> colors;        // COLOR_0 (empty when absent), multiplies base colour
    std::vector<uint32_t> indices;   // 3 per triangle
    int material = -1;               // index into Scene::materials, -1 for the glTF default
    size_t triangle_count() const { return indices.size() / 3; }
};

// A glTF mesh: primitives built once and instanced by every node that uses it.
struct MeshGroup {
    std::string name;
    std::vector<TriangleMesh> primitives;
};

struct Instance {
    int mesh_group = -1;
    Eigen::Affine3f transform = Eigen::Affine3f::Identity();  // local to world
};

struct Camera {
    std::string name;
    Eigen::Affine3f camera_to_world = Eigen::Affine3f::Identity();  // camera looks down -Z, +Y up
    float yfov = 0.8f;                                              // radians (perspective)
    float aspect_ratio = 0.0f;                                      // 0: take it from the image resolution
    // glTF orthographic camera: parallel rays along -Z over a view half ymag metres tall (the
    // image's aspect decides the width, as it does for perspective cameras; an xmag / ymag other than
    // the image's aspect is warned about: frame/scene_spec.cpp choose_camera).
    bool orthographic = false;
    float ymag = 1.0f;
    int file_index = -1;  // its index in the glTF file's cameras array (-1: not from a file)
};

// A perspective camera at eye looking at target, +Y up (a straight up or down view takes +Z as up).
// Throws dynsky::Error when eye and target coincide or yfov is not in (0, pi).
Camera look_at_camera(const Vec3& eye, const Vec3& target, float yfov);

struct Bounds3 {
    Vec3 lo = Vec3::Constant(std::numeric_limits<float>::infinity());
    Vec3 hi = Vec3::Constant(-std::numeric_limits<float>::infinity());
    void extend(const Vec3& p) { lo = lo.cwiseMin(p), hi = hi.cwiseMax(p); }
    bool empty() const { return !(lo.x() <= hi.x()); }
    Vec3 center() const { return 0.5f * (lo + hi); }
    Vec3 diagonal() const { return hi - lo; }
};

// A KHR_lights_punctual light, in world space and radiometric units (the sky's: W, m, sr). glTF
// gives candela (point, spot) and lux (directional) for its linear RGB colour, so radiometric =
// colour x photometric / kLumensPerWatt (Blender's glTF exporter converts with the same 683).
struct PunctualLight {
    enum class Type { Point, Spot, Directional };
    Type type = Type::Point;
    std::string name;
    Vec3 position = Vec3::Zero();        // point and spot
    Vec3 direction = Vec3(0, 0, -1);     // where the light shines (the node's -Z), unit; spot, directional
    Color intensity = Color::Zero();     // W/sr (point, spot) or W/m^2 at normal incidence (directional)
    float range = 0;                     // > 0: the spec's smooth cut-off at this distance; 0: none
    float cos_inner = 1, cos_outer = 0;  // spot cone: full inside inner, none outside outer
};

struct Scene {
    std::string source;  // file it came from
    // A file's coordinates are the scene's + origin_shift: a scene its nodes place far from the
    // origin is moved near it when loaded (renderer/gltf_loader.cpp), by whole metres.
    Eigen::Vector3d origin_shift = Eigen::Vector3d::Zero();
    std::vector<MeshGroup> meshes;
    std::vector<Instance> instances;
    std::vector<Material> materials;
    std::vector<std::shared_ptr<Texture>> textures;
    std::vector<Camera> cameras;  // glTF cameras (perspective and orthographic), in file order
    // The names of the file's cameras array, placed on a node or not (--camera N is its N-th).
    std::vector<std::string> file_camera_names;
    std::vector<PunctualLight> lights;      // KHR_lights_punctual, one per node that holds one
    std::vector<std::string> warnings;      // e.g. extensions used but not supported
    int hidden_meshes = 0;                  // meshes (or their instances) scaled to 0: not drawn
    std::vector<std::string> source_files;  // the files it was read from (glTF, buffers, images): never outputs

    Bounds3 world_bounds() const;
    size_t triangle_count() const;  // counting every instance
    // The default glTF material (white, metallic 1, roughness 1) for primitives without one.
    static const Material& default_material();
    const Material& material(int index) const { return index < 0 ? default_material() : materials[size_t(index)]; }
};

// Every surface a Lambertian of its base colour (textures and vertex colours kept; no emission), as
// tools/cycles/render_cycles.py --override-material lambert does in Cycles (render --override-material).
void override_materials_lambert(Scene* scene);

// A camera that frames the scene's bounds from the south-east, above (used when a file has none).
Camera frame_bounds_camera(const Bounds3& bounds, float aspect_ratio);

}  // namespace dynsky
