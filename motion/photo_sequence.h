// Sequences of all-sky photographs the cloud models are trained and scored on: the named ones in
// ../shared/skies (glossary: "photo sequence"), in time order, with their camera preset and cadence.
#pragma once

#include <string>
#include <vector>

namespace dynsky {

// The resolutions `sky evaluate` and `sky training-data` import photographs at (--import-res): the
// same range in both, so a training set can always be scored at its own resolution.
constexpr int kImportResolutionMin = 16, kImportResolutionMax = 4096;
// Throws dynsky::Error naming --import-res when `resolution` is outside that range.
void check_import_resolution(int resolution);

struct PhotoSequence {
    std::string name;    // the dataset's and split's name ("arm_tsi")
    std::string preset;  // camera preset of the import (sky/preset_import.h); empty: imported skies
    std::string folder;
    double dt = 0;                    // cadence: seconds between frames
    std::vector<std::string> photos;  // in time order
    std::vector<double> utc;          // their capture times (UTC seconds, utc_seconds); NaN where unknown
};

// A named sequence ("arm-tsi", "mobotix") in the shared data folder. Throws dynsky::Error for an
// unknown name, a missing folder, or frames whose times are not the sequence's cadence apart (a
// photograph missing from the folder: the file after the gap is named).
PhotoSequence named_photo_sequence(const std::string& name, const std::string& shared_dir);

// Any folder of photographs of one camera preset (JPEG/PNG in the folder or its images/ sub-folder),
// ordered by the times their file names carry (sky/photo_import.h time_from_file_name, on the
// preset's clock); or, with no preset, of skies already imported (EXR, any camera: `dynsky sky
// import` with that camera's options), ordered by the times their names carry or, failing that,
// the photograph's time the import recorded. The cadence is the median gap. Throws dynsky::Error naming the folder when it
// holds no photographs, a name carries no time, two photographs share a time, or the gaps are not
// all the cadence (mixed cadence or missing frames: the first offending pair is named).
PhotoSequence photo_sequence_from_folder(const std::string& folder, const std::string& preset);

// True when the folder of a sequence (its images/ sub-folder when it has one, as above) holds an
// EXR: skies already imported, which need no preset.
bool folder_holds_skies(const std::string& folder);

// The shared data folder beside the source tree (the tests' ../shared).
std::string default_shared_dir();

}  // namespace dynsky
