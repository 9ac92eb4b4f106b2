// The scene of a render (glossary: "scene spec"): a glTF file or the built-in scene, which camera,
// and the ground model's albedo; loaded with its camera (or one framing the bounds).
#pragma once

#include <string>
#include <vector>

#include "renderer/gltf_loader.h"
#include "renderer/scene.h"

namespace dynsky {

struct SceneSpec {
    std::string scene = "scenes/tower/tower.gltf";  // .gltf/.glb or "builtin"
    int camera = 0;                                 // index in the glTF file's cameras array
    float ground_albedo = 0.3f;                     // the Lambertian ground below the horizon
    // Camera overrides: look_at = {eye x, y, z, target x, y, z} (world frame, metres; empty: none)
    // replaces the camera by a perspective one there, +Y up; fov_deg (0: none) sets the vertical
    // field of view of the camera in use (the chosen, framing or look-at one; perspective only).
    std::vector<double> look_at;
    double fov_deg = 0;
    // The glTF's animations sampled at this time in seconds (held at their ends), posing nodes,
    // skins and morph targets; negative: the rest pose.
    double animation_time = -1;
    // Which of the file's animations plays: its name or index; empty: every one.
    std::string animation;
};

struct LoadedScene {
    Scene scene;
    Camera camera;
    std::string path;  // the file loaded: the spec's, or the shipped scene of that relative name (util/data_path.h)
};

// Validates the spec, loads the scene (a relative path not found from the working folder is
// looked up among the shipped data, util/data_path.h resolve_user_path) (warnings to stderr) and picks the camera; a file without
// cameras gets one framing its bounds at aspect_ratio. Throws dynsky::Error naming the file.
LoadedScene load_scene(const SceneSpec& spec, float aspect_ratio, bool print_warnings = true);

// The same for a glTF file already loaded (path: the file it was loaded from), posed at
// spec.animation_time (0 when negative): what load_scene gives, without reading the file again
// (animate --play-anim poses one file per frame); the file's warnings printed when asked.
LoadedScene pose_scene(const SceneSpec& spec, AnimatedGltf& file, const std::string& path, float aspect_ratio,
                       bool print_warnings = false);

// The camera of a loaded scene as the spec asks (its glTF camera, one framing the bounds, the
// look-at and field-of-view overrides); throws for a scene without triangles or a bad camera.
void choose_camera(const SceneSpec& spec, float aspect_ratio, LoadedScene* loaded, bool print_warnings = true);

// What choose_camera refuses of --camera, from the glTF's JSON alone (no geometry read): for
// `animate --count-frames`, which checks a run before a farm queues it.
void check_scene_camera(const SceneSpec& spec);

}  // namespace dynsky
