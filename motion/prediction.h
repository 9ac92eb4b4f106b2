// `dynsky sky predict`: K recursive medium steps of a cloud model from one sky, written as
// OUT/step_NNNN.exr (glossary: a "step" is a medium step; frames are what animations show), with
// optional previews and a CSV of per-step statistics (mean luminance, the [0, 1] form's mean / min
// / max, cloud cover, high-frequency energy, non-finite pixels; step 0 = the input).
#pragma once

#include <string>

namespace dynsky {

struct PredictionOptions {
    std::string model, in, out, stats;
    int steps = 1, every = 1;
    bool preview = false, quiet = false;
};

void write_prediction(const PredictionOptions& o);

}  // namespace dynsky
