// The frame stage: a lit scene under a moving sky, frame by frame, resumable (`dynsky animate`).
//
// Every frame is a pure function of (scene, sky source, step model, Delta t, frame time, seed): the
// medium steps are always computed from step 0 in order, and the path tracer's image depends only
// on its seed. So a frame range rendered alone, or a run resumed after being killed, gives the same
// pixels as one uninterrupted run. Frames go into a frame/frame_store.h folder; frames already
// complete there and made with the same settings (frame/frame_metadata.h FrameSettings) are kept,
// the others rendered again, saying which and why (force: every frame of the range is rendered).
// Temporaries left in the folder by a killed run are removed first. When every frame is complete:
// the contact sheet and, unless no_video, the MP4s (frame/video.h). Any failed write throws
// dynsky::Error naming the file (util/atomic_file.h).
#pragma once

#include <cstdint>
#include <limits>
#include <string>

#include "frame/frame_metadata.h"
#include "frame/scene_spec.h"
#include "frame/sky_source.h"

namespace dynsky {

// Parameters (defaults):
//   duration 4 s, fps 12     frame k shows the sky at t = k / fps; round(duration * fps) frames
//   spp 16, width x height 480 x 270, max_depth 8
//   out "animation"          the frame store's folder
//   frames ""                "A-B" or "A": render only those (numbered from 0); "" all
//   seed 0, seed_per_frame false   the same seed every frame (correlated noise, no flicker)
//   threads 0                worker threads (0: all cores)
//   aovs ""                  passes in each frame's EXR ("albedo,normal,depth,alpha")
//   clamp_indirect 0, filter_glossy 0   firefly remedies (renderer/integrator.h), off
//   exposure NaN             PNG exposure in stops; NaN: from the sky's irradiance at t = 0
//   exposure_follows_sun false   the PNGs' exposure follows the clear sky's light at each frame's
//                            sun (through sunrise or sunset), from that at t = 0; clouds do not move it
//   force false              render every frame of the range even if complete
//   no_video false, quiet false
//   timeline ""              a stored timeline's folder (frame/sky_source.h write_sky_timeline): the
//                            medium steps and flows are read from it instead of computed; the
//                            frames are the same bytes either way (docs/render-farm.md)
//   stage "all"              what this run does, for render farms (docs/render-farm.md):
//                              all     render the range, then the videos and contact sheet once
//                                      every frame is complete (a run on one machine)
//                              keys    only write the stored timeline into `timeline` (the whole
//                                      duration); no scene is read, no frame rendered
//                              frames  only render the range (a farm task): no videos, no contact
//                                      sheet; timings into timings_A-B.csv; only this range's own
//                                      temporaries are cleaned up (other tasks write beside it)
//                              encode  render nothing: every frame must be complete (else an
//                                      error naming those that are not); the videos and contact sheet
// The most frames one animation may have (as a procedural sequence): duration * fps is computed in
// double precision and checked against it, so a huge --duration cannot wrap into a short animation.
constexpr double kMaxAnimationFrames = 100000;

struct AnimationSettings {
    SceneSpec scene;
    SkySourceSpec sky;
    StepModelSpec model;
    double duration = 4.0;
    double fps = 12.0;
    int spp = 16;
    int width = 480, height = 270;
    std::string out = "animation";
    std::string frames;
    uint64_t seed = 0;
    bool seed_per_frame = false;
    // Play the glTF's animations along the frames: the frame at t seconds poses the scene at
    // scene.animation_time (0 when unset) + t; the file is loaded once and posed per frame
    // (renderer/gltf_loader.h AnimatedGltf), its BVH built per frame.
    bool play_scene_animation = false;
    int threads = 0;
    int max_depth = 8;
    std::string aovs;                             // extra EXR passes (renderer/integrator.h parse_aovs)
    float clamp_indirect = 0, filter_glossy = 0;  // firefly remedies, off (0) by default
    std::string sampler_pattern = "random";       // "random" or "sobol" (renderer/zsobol_sampler.h)
    float exposure = std::numeric_limits<float>::quiet_NaN();
    bool exposure_follows_sun = false;
    bool force = false;
    bool no_video = false;
    bool quiet = false;
    std::string timeline;
    std::string stage = "all";
};

struct AnimationReport {
    int total = 0, first = 0, last = 0;  // frames of the animation; the range asked for
    int rendered = 0, skipped = 0;       // by this run; kept because complete
    int replaced = 0;                    // of those rendered: had files that were damaged or of other settings
    bool complete = false;               // every frame of the animation is complete with these settings
    std::string settings;                // canonical_settings of this run (frame/frame_metadata.h)
};

// The settings frames of this animation are made with (the exposure as resolved, the model by name).
FrameSettings animation_frame_settings(const AnimationSettings& settings, const std::string& model_name, double dt,
                                       float png_exposure_ev);

// round(duration * fps), at least 1, after checking duration and fps (what --frames counts in).
int animation_frame_count(const AnimationSettings& settings);

// Checks the options before any work (render_animation starts with it); with inputs_exist, also
// that the scene, sky, previous frame, timeline and model named exist (what `--count-frames`
// checks for a farm script before anything is queued). Throws dynsky::Error naming the option.
void check_animation_settings(const AnimationSettings& settings, bool inputs_exist);

AnimationReport render_animation(const AnimationSettings& settings);

}  // namespace dynsky
