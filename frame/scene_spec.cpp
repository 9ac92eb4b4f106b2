#include "frame/scene_spec.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "renderer/builtin_scene.h"
#include "renderer/gltf_json_check.h"
#include "renderer/gltf_loader.h"
#include "util/data_path.h"
#include "util/error.h"
#include "util/parse.h"

namespace dynsky {

namespace {

// --camera against a file's cameras array (counted as in the file, placed on a node or not).
void check_camera_index(const SceneSpec& o, size_t file_cameras) {
    if (file_cameras == 0 && o.camera != 0)
        throw Error(o.scene + ": --camera " + std::to_string(o.camera) + " asked for, but the file has no cameras");
    if (file_cameras > 0 && (o.camera < 0 || o.camera >= int(file_cameras)))
        throw Error(o.scene + ": --camera " + std::to_string(o.camera) + " is out of range (the file has " +
                    std::to_string(file_cameras) + " camera(s), numbered from 0)");
}

}  // namespace

void check_scene_camera(const SceneSpec& o) {
    if (o.scene == "builtin") return;
    const std::optional<nlohmann::json> j = read_gltf_json(resolve_user_path(o.scene));
    if (!j || !j->is_object()) return;  // the loader names what is wrong with it
    const auto it = j->find("cameras");
    check_camera_index(o, it != j->end() && it->is_array() ? it->size() : 0);
}

LoadedScene load_scene(const SceneSpec& o, float aspect_ratio, bool print_warnings) {
    if (!(o.ground_albedo >= 0 && o.ground_albedo <= 1)) throw Error("--ground-albedo must be in [0, 1]");
    LoadedScene out;
    if (o.scene == "builtin") {
        out.scene = make_builtin_scene();
        out.path = o.scene;
        if (!o.animation.empty() && print_warnings)
            std::fprintf(stderr, "dynsky: warning: the built-in scene has no animations: --animation %s does nothing\n",
                         o.animation.c_str());
    } else {
        out.path = resolve_user_path(o.scene);  // shipped scenes work from any folder
        std::error_code ec;
        if (!std::filesystem::exists(out.path, ec)) throw_file_error(o.scene, missing_user_path_text(o.scene));
        out.scene = load_gltf(out.path, nullptr, o.animation_time, o.animation);
        if (print_warnings)
            for (const std::string& w : out.scene.warnings) std::fprintf(stderr, "dynsky: warning: %s\n", w.c_str());
    }
    choose_camera(o, aspect_ratio, &out, print_warnings);
    return out;
}

LoadedScene pose_scene(const SceneSpec& o, AnimatedGltf& file, const std::string& path, float aspect_ratio,
                       bool print_warnings) {
    if (!(o.ground_albedo >= 0 && o.ground_albedo <= 1)) throw Error("--ground-albedo must be in [0, 1]");
    LoadedScene out;
    out.path = path;
    out.scene = file.pose(std::max(0.0, o.animation_time));
    if (print_warnings)
        for (const std::string& w : out.scene.warnings) std::fprintf(stderr, "dynsky: warning: %s\n", w.c_str());
    choose_camera(o, aspect_ratio, &out, print_warnings);
    return out;
}

void choose_camera(const SceneSpec& o, float aspect_ratio, LoadedScene* loaded, bool print_warnings) {
    LoadedScene& out = *loaded;
    if (out.scene.instances.empty()) {
        // Animations hide objects by scaling them to 0 (a pop-in starts so): a pose where every
        // mesh is hidden is the sky and the ground from the file's camera, not an error that
        // stopped an animation at its first frame. Without a camera nothing says where to look.
        const bool hidden = out.scene.hidden_meshes > 0;
        const bool placed = !out.scene.cameras.empty() || !o.look_at.empty();
        if (!hidden || !placed)
            throw Error(o.scene + ": the scene has no triangles to render" +
                        (hidden ? " at animation time " + number_text(o.animation_time) +
                                      " s (every mesh hidden by a scale of 0) and no camera to look from"
                                : std::string()));
        if (print_warnings)
            std::fprintf(stderr,
                         "dynsky: warning: %s: every mesh is hidden at animation time %s s (a scale of 0): the "
                         "frame shows the sky and the ground only\n",
                         o.scene.c_str(), number_text(o.animation_time).c_str());
    }
    if (out.scene.cameras.empty() && o.camera == 0) {
        out.camera = frame_bounds_camera(out.scene.world_bounds(), aspect_ratio);
    } else if (out.scene.cameras.empty() && out.scene.file_camera_names.empty()) {
        throw Error(o.scene + ": --camera " + std::to_string(o.camera) + " asked for, but the file has no cameras");
    } else if (out.scene.file_camera_names.empty()) {
        if (o.camera < 0 || o.camera >= int(out.scene.cameras.size()))
            throw Error(o.scene + ": --camera " + std::to_string(o.camera) + " is out of range (the scene has " +
                        std::to_string(out.scene.cameras.size()) + " camera(s), numbered from 0)");
        out.camera = out.scene.cameras[size_t(o.camera)];
    } else {
        // glTF cameras are numbered as in the file's cameras array (counting only those placed on a
        // node, camera 1 of three of which two were placed rendered the third).
        const std::vector<std::string>& names = out.scene.file_camera_names;
        check_camera_index(o, names.size());
        auto it = std::find_if(out.scene.cameras.begin(), out.scene.cameras.end(),
                               [&](const Camera& c) { return c.file_index == o.camera; });
        // Camera 0 (the default) placed nowhere, or any under --look-at (which replaces it): the
        // first camera placed, as when cameras were counted by their nodes.
        if (it == out.scene.cameras.end() && (o.camera == 0 || !o.look_at.empty())) it = out.scene.cameras.begin();
        if (it == out.scene.cameras.end())
            throw Error(o.scene + ": --camera " + std::to_string(o.camera) + " ('" + names[size_t(o.camera)] +
                        "') is not placed on any node of the scene, or was skipped (see the warnings): nothing "
                        "says where it looks from");
        out.camera = *it;
    }
    // The file's camera frames another aspect than the image: its vertical extent is kept (glTF's
    // yfov, ymag), so the image shows more or less to the sides than the camera frames. Said, with
    // the size that frames it as the file does (the camera's aspectRatio and xmag were silently
    // ignored).
    if (print_warnings && o.look_at.empty() && out.camera.aspect_ratio > 0 && aspect_ratio > 0 &&
        std::abs(out.camera.aspect_ratio / aspect_ratio - 1) > 0.01) {
        const int height = std::max(1, int(std::lround(960 / out.camera.aspect_ratio)));
        std::fprintf(stderr,
                     "dynsky: warning: camera '%s' frames an aspect of %.3g (%s) but the image's is %.3g: its "
                     "vertical extent is kept, so the image shows %s to the sides than the camera; give --res "
                     "960x%d (or any size of aspect %.3g) to frame it as the file does\n",
                     out.camera.name.c_str(), out.camera.aspect_ratio,
                     out.camera.orthographic ? "xmag / ymag" : "aspectRatio", aspect_ratio,
                     aspect_ratio > out.camera.aspect_ratio ? "more" : "less", height, out.camera.aspect_ratio);
    }
    if (!o.look_at.empty() && o.look_at.size() != 6)
        throw Error("--look-at takes 6 numbers, eye_x,eye_y,eye_z,target_x,target_y,target_z (got " +
                    std::to_string(o.look_at.size()) + ")");
    if (o.fov_deg != 0 && !(o.fov_deg > 0 && o.fov_deg < 180))
        throw Error("--fov " + std::to_string(o.fov_deg) + " must be in (0, 180) degrees");
    if (!o.look_at.empty()) {
        const auto& v = o.look_at;
        float yfov = out.camera.orthographic ? Camera().yfov : out.camera.yfov;
        const Eigen::Vector3d& shift = out.scene.origin_shift;  // in the file's coordinates
        out.camera = look_at_camera(Vec3(float(v[0] - shift[0]), float(v[1] - shift[1]), float(v[2] - shift[2])),
                                    Vec3(float(v[3] - shift[0]), float(v[4] - shift[1]), float(v[5] - shift[2])), yfov);
    }
    if (o.fov_deg != 0) {
        if (out.camera.orthographic) throw Error(o.scene + ": --fov given, but the camera is orthographic");
        out.camera.yfov = float(o.fov_deg * kPiD / 180);
    }
}

}  // namespace dynsky
