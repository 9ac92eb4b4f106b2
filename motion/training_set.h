// One sequence of a cloud-model training set (networks/dataset.py drives it through `dynsky sky
// training-data`): frames in the networks' form at N (motion/network_form.h), seen-sky and cloud
// masks, the clear background of each frame's sun (motion/network_form.h clear_background; zero and
// sun (0, 0, 0) when the sun is unknown), Farneback flow frame k -> k+1 (at the import resolution, area-averaged to N) and, for
// procedural sequences, the exact flow, as .npy files (util/npy.h) plus meta.json
// (networks/data.py documents the arrays).
#pragma once

#include <string>

#include "motion/network_form.h"

namespace dynsky {

struct TrainingSetOptions {
    // Exactly one of sequence (a named photo sequence) and procedural (a `dynsky sky procedural` folder).
    std::string sequence, procedural, shared, out;
    int resolution = 128, import_resolution = 256;
    NetworkFormParams form;
    std::string cloud_rule = "rb";
    bool quiet = false;
};

// Writes OUT/images.npy, valid.npy, cloud.npy, background.npy, sun.npy, flow_farneback.npy, [flow_exact.npy,] meta.json.
// Throws dynsky::Error before writing anything when the options or inputs are bad.
void build_training_sequence(const TrainingSetOptions& o);

}  // namespace dynsky
