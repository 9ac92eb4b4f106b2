// The evaluation protocol of cloud models: a model's recursive rollout against persistence and
// Farneback extrapolation (motion/metrics.h) on the held-out (last, in time) frames of a photo
// sequence (motion/photo_sequence.h), all from the same frames in one run: MSE, PSNR and SSIM per
// horizon as a markdown table, and a histogram of cloud motion (real vs rollout vs FlowNet).
#pragma once

#include <string>

namespace dynsky {

struct EvaluationOptions {
    std::string model, sequence, shared, horizons = "1,2,3,6", report = "docs/networks-evaluation.md",
                                         histogram = "docs/networks-flow-histogram.png";
    int import_resolution = 0, limit = 0;
    bool quiet = false;
};

void evaluate_cloud_model(const EvaluationOptions& o);

}  // namespace dynsky
