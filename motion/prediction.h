// `dynsky sky predict`: K recursive medium steps of a cloud model from one sky, written as
// OUT/step_NNNN.exr (glossary: a "step" is a medium step; frames are what animations show), with
// optional previews and a CSV of per-step statistics (mean luminance, the [0, 1] form's mean / min
// / max, cloud cover, high-frequency energy, non-finite pixels; step 0 = the input).
#pragma once

#include <optional>
#include <string>

#include "motion/flow.h"

namespace dynsky {

// Parameters (defaults): model "" (the shipped advect-residual model; "advect": pure advection;
// "paper": the FlowNet + CloudNet of networks/models/arm_tsi; or a model folder), in (the sky),
// out (a folder), steps 1, every 1 (write every M-th step and the last), stats "" (no CSV),
// preview false. Motion (advect-residual and advect only): previous (a frame before `in`,
// previous_dt seconds before it; 0: one model step) or a wind; with neither, the default wind
// (motion/flow.h Wind{}).
struct PredictionOptions {
    std::string model, in, out, stats;
    int steps = 1, every = 1;
    int resolution = 0;   // --sky-res: the input (and --prev) taken at N x N; 0: its own (a lat-long's height,
                          // at most kMovingLatlongLimit)
    double turn_deg = 0;  // --sky-turn: the input (and --prev) turned about the zenith
    bool preview = false, quiet = false;
    std::string previous;
    double previous_dt = 0;
    std::optional<Wind> wind;
};

void write_prediction(const PredictionOptions& o);

}  // namespace dynsky
