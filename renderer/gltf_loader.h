// glTF 2.0 (.gltf with its .bin/images, or .glb) to the renderer's Scene, through tinygltf.
//
// What is read: the default scene's node hierarchy (matrix or TRS), every triangle primitive
// (TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN; indexed or not; any accessor component type,
// normalised or not, sparse accessors), NORMAL (flat normals generated when missing, as the
// spec requires), TANGENT (generated from the normal texture's UV set when missing),
// TEXCOORD_0/1, COLOR_0; metallic-roughness materials with their textures, samplers and factors;
// perspective and orthographic cameras on nodes. Each glTF mesh becomes one MeshGroup, instanced by every node
// that uses it (and by every EXT_mesh_gpu_instancing instance).
// Supported extensions: KHR_texture_transform, KHR_materials_emissive_strength,
// KHR_materials_transmission (thin-walled), KHR_materials_clearcoat, KHR_materials_specular,
// KHR_materials_ior, KHR_materials_volume (thin), KHR_materials_sheen, KHR_lights_punctual,
// EXT_texture_webp, EXT_mesh_gpu_instancing, KHR_mesh_quantization, KHR_draco_mesh_compression
// (renderer/draco_mesh.h), EXT_meshopt_compression (renderer/meshopt_buffer.h). Skins and morph targets are
// posed as the file stands (the nodes' transforms, the weights given).
// Animations are sampled at a time given to load_gltf, else ignored with a warning.
// Ignored with a warning: points and lines, and any other extension listed in
// extensionsUsed. One listed in extensionsRequired that is not supported is
// an error. Values of the wrong JSON type are refused by their path (gltf_json_check.h).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "renderer/scene.h"

namespace dynsky {

// Loads a glTF 2.0 file. Warnings (what was ignored) go to Scene::warnings and, if given, are
// appended to *warnings. Throws dynsky::Error "PATH: problem" for a missing, truncated or
// malformed file, a missing buffer or texture file (named), out-of-range accessors or indices,
// or an unsupported required extension (named).
// animation_time (seconds, >= 0): the file's animations (all of them, in file order) are sampled
// at that time, held at their ends (STEP, LINEAR with slerped rotations, CUBICSPLINE), and drive
// the nodes' transforms and morph weights, skins included; negative (the default): the rest pose,
// with a warning that animations were not played. `animation`: only the animation of that name
// (else of that index) plays; empty: every one (with a warning when there are several: a file
// exported with several actions, Idle, Walk, Run, played all at once is none of them). An
// animation the file does not have is an error listing those it has.
Scene load_gltf(const std::string& path, std::vector<std::string>* warnings = nullptr, double animation_time = -1,
                const std::string& animation = "");

class GltfLoader;

// A glTF file loaded once and posed at any animation time (`dynsky animate --play-anim`): pose(t)
// gives what load_gltf(path, nullptr, t) gives, but the file is read, its buffers decoded and its
// materials and textures built once; each pose only evaluates the animations and builds what hangs
// on the nodes (meshes with their skins and morph targets, instances, cameras, lights), the
// textures shared with every other pose. Throws as load_gltf.
class AnimatedGltf {
  public:
    explicit AnimatedGltf(const std::string& path, const std::string& animation = "");
    ~AnimatedGltf();
    AnimatedGltf(const AnimatedGltf&) = delete;
    AnimatedGltf& operator=(const AnimatedGltf&) = delete;
    Scene pose(double animation_time);

  private:
    std::unique_ptr<GltfLoader> loader_;
};

// KHR_texture_transform as a matrix on (u, v, 1): T(offset) * R(rotation) * S(scale), with R
// rotating the UVs counter-clockwise by `rotation` radians as the extension text and its worked
// example define it (u axis towards -v), i.e. R = [cos sin; -sin cos].
Eigen::Matrix3f texture_transform_matrix(const Vec2& offset, float rotation, const Vec2& scale);

}  // namespace dynsky
