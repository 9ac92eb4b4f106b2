// The frame stage: a lit scene under a moving sky, frame by frame, resumable (`dynsky animate`).
//
// Every frame is a pure function of (scene, sky source, step model, Delta t, frame time, seed): the
// medium steps are always computed from step 0 in order, and the path tracer's image depends only
// on its seed. So a frame range rendered alone, or a run resumed after being killed, gives the same
// pixels as one uninterrupted run. Frames go into a frame/frame_store.h folder; frames already
// complete there are kept. When every frame exists: the contact sheet and, unless no_video, the
// MP4s (frame/video.h).
#pragma once

#include <cstdint>
#include <limits>
#include <string>

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
//   exposure NaN             PNG exposure in stops; NaN: from the sky's irradiance at t = 0
//   no_video false, quiet false
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
    int threads = 0;
    int max_depth = 8;
    float exposure = std::numeric_limits<float>::quiet_NaN();
    bool no_video = false;
    bool quiet = false;
};

struct AnimationReport {
    int total = 0, first = 0, last = 0;  // frames of the animation; the range asked for
    int rendered = 0, skipped = 0;       // by this run; kept because complete
    bool complete = false;               // every frame of the animation exists
};

AnimationReport render_animation(const AnimationSettings& settings);

}  // namespace dynsky
