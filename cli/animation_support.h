// What the rendering commands share: the frame size and the scene and camera (`render`, `animate`,
// `compare`), and the moving sky (input sky + medium-step model + sun clock -> SkyTimeline,
// motion/sky_timeline.h; `animate`, `compare`).
#pragma once

#include <CLI/CLI.hpp>

#include <string>

#include "renderer/accel.h"
#include "renderer/env_light.h"
#include "renderer/scene.h"
#include "motion/sky_timeline.h"

namespace dynsky::cli {

struct SceneOptions {
    std::string scene = "scenes/tower/tower.gltf";
    int camera = 0;
    float ground_albedo = 0.3f;
};

struct SkySourceOptions {
    std::string sky = "procedural";  // procedural[:SEED] | clear | FILE.exr
    std::string model = "auto";      // auto | procedural | flow | network:FOLDER
    double dt = 0.0;                 // Delta t of the medium steps, seconds; 0: the network's, else 10
    int sky_resolution = 1024;       // for skies made here (procedural, clear)
    std::string time;                // ISO 8601 UTC of t = 0 (the sun follows it)
    double latitude = 48.8566, longitude = 2.3522;
    double coverage = 0.5;           // procedural cloud cover
    double wind_from_deg = 270.0, wind_speed_mps = 12.0;
    double drift_deg_per_s = 0.25;   // flow model's first step, from a single sky
};

struct LoadedScene {
    Scene scene;
    Camera camera;
};

void add_scene_options(CLI::App* cmd, SceneOptions* o);
void add_sky_source_options(CLI::App* cmd, SkySourceOptions* o);

void parse_frame_size(const std::string& text, int* w, int* h);
// s as one word for /bin/sh (single quotes; a quote inside becomes '\'').
std::string shell_quote(const std::string& s);
LoadedScene load_scene(const SceneOptions& o, float aspect_ratio);
// Validates everything (files, ranges) before any rendering.
SkyTimeline make_sky_timeline(const SkySourceOptions& o);
// The UTC time of t = 0 (the default when --time is not given: 2026-06-21T16:00:00Z).
UtcTime start_time(const SkySourceOptions& o);

}  // namespace dynsky::cli
