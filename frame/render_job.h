// One image of a glTF scene (or the built-in plaza) under a sky: what `dynsky render` runs. The
// sky is a file (a canonical fisheye or a 2:1 lat-long HDRI), one made here ('clear',
// 'procedural[:SEED]' at --time, --lat, --lon) or, with none of these given, the built-in clear
// sky. Everything is checked before a pixel is traced; the EXR and the PNG beside it are written
// together or not at all, with the settings that made them in the EXR's header.
//
// Parameters (the defaults of `dynsky render`):
//   scene          "builtin"           a .gltf/.glb or the built-in plaza, with camera options
//   sky            ""                  "" built-in clear sky (Paris 2026-06-21 16:00 UTC, T 3)
//   out            render.exr          .exr (+ tone-mapped .png beside it) or .png
//   resolution     960x540             WIDTHxHEIGHT
//   spp, seed      64, 0               samples per pixel; the same seed gives the same image on any thread count
//   max_depth      8                   bounces
//   sampler        the path tracer's   sky importance sampler (renderer/sky_sampler.h)
//   noise_threshold, time_limit 0      adaptive sampling, seconds (0: off)
//   clamp_indirect, filter_glossy 0    Cycles' firefly remedies (0: off, unbiased)
#pragma once

#include <cstdint>
#include <limits>
#include <string>

#include "frame/scene_spec.h"
#include "frame/sky_source.h"
#include "renderer/sky_sampler.h"

namespace dynsky {

// The built-in plaza with the default camera options: render's default scene.
inline SceneSpec builtin_scene() {
    SceneSpec spec;
    spec.scene = "builtin";
    return spec;
}

struct RenderJob {
    SceneSpec scene = builtin_scene();  // the scene and camera options every command shares
    std::string sky;
    std::string out = "render.exr";
    std::string resolution = "960x540";
    int spp = 64;
    uint64_t seed = 0;
    int threads = 0;
    int max_depth = 8;
    float exposure = std::numeric_limits<float>::quiet_NaN();  // NaN: automatic
    bool quiet = false;
    std::string sampler = sky_sampler_name(path_tracer_sky_sampler());
    std::string aovs, region;
    float noise_threshold = 0, clamp_indirect = 0, filter_glossy = 0;
    double time_limit = 0;
    std::string sampler_pattern = "random";
    std::string override_material = "none";
    SkySourceSpec generated;  // --sky clear|procedural[:SEED] with --sky-res, --time, --lat, --lon
};

// Renders and writes job.out (and its PNG). Throws dynsky::Error naming the option or file at fault.
void run_render_job(const RenderJob& job);

}  // namespace dynsky
