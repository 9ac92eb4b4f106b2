// Sequences of all-sky photographs the cloud models are trained and scored on: the named ones in
// ../shared/skies (glossary: "photo sequence"), in time order, with their camera preset and cadence.
#pragma once

#include <string>
#include <vector>

namespace dynsky {

struct PhotoSequence {
    std::string name;    // the dataset's and split's name ("arm_tsi")
    std::string preset;  // camera preset of the import (sky/preset_import.h)
    std::string folder;
    double dt = 0;                    // cadence: seconds between frames
    std::vector<std::string> photos;  // in time order
};

// A named sequence ("arm-tsi", "mobotix") in the shared data folder. Throws dynsky::Error for an
// unknown name or a missing folder.
PhotoSequence named_photo_sequence(const std::string& name, const std::string& shared_dir);

// The shared data folder beside the source tree (the tests' ../shared).
std::string default_shared_dir();

}  // namespace dynsky
