// A photograph import as a job: one all-sky photograph, several, or a folder of one camera's
// photographs into canonical sky EXRs (with previews and filled masks), as `dynsky sky import` runs
// it. The steps themselves live in sky/photo_import.h (geometry, masks, fill), sky/preset_import.h
// (a camera preset's decisions) and sky/hdr_recovery.h (calibration, the sun, north); this file
// decides which run, with what, and says what was found and done.
//
// Parameters (defaults as `sky import` gives them):
//   photos          one photograph, several, or one folder of them (required)
//   preset          "" or a camera preset (sky/photo_import.h camera_preset_names): geometry, masks,
//                   place and clock; every other field given overrides it
//   circle          the sky circle in photo pixels (none: the preset's, else found; a sequence's is
//                   found once for all its photographs)
//   lens, north_deg, tilt_deg, tilt_azimuth_deg   none: the preset's, else equidistant, 0, 0, 0
//   mirror          the photo is mirror-reversed (false)
//   find_north      north from the clipped sun (false); flatten_colour: a sequence's colour shading
//                   measured on its overcast photos and divided out (false)
//   mask, mask_layout   a non-sky mask file ("", photo layout)
//   no_preset_mask, detect_obstructions, keep_thin_objects, no_inpaint   (all false)
//   fill            none: texture for one photograph, smooth for a sequence but its last sky in time
//                   (where a moving sky made from the folder starts) texture
//   encoding        "auto" (the file's pixels decide), "srgb" or "linear"
//   time            ISO 8601 with a zone ("": the file name's, else the EXIF's; one photograph only)
//   utc_offset_hours, latitude_deg, longitude_deg, elevation_m   none: the preset's, else 0
//   hdr             "auto" (calibrated when time and place are known), "none" or "calibrated"
//   keep_colours    one scale for all channels (false); turbidity: 3
//   resolution      512; out: the .exr (a folder for a sequence); preview, filled_mask: "" or .png
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "sky/photo_import.h"

namespace dynsky {

struct PhotoImportJob {
    std::vector<std::string> photos;
    std::string preset;
    std::optional<SkyCircle> circle;
    bool auto_circle = false;  // find the circle even where the preset gives one
    std::optional<LensLaw> lens;
    std::optional<double> north_deg, tilt_deg, tilt_azimuth_deg;
    bool mirror = false, find_north = false, flatten_colour = false;
    std::string mask;
    MaskLayout mask_layout = MaskLayout::PhotoBlackIsNotSky;
    bool no_preset_mask = false, detect_obstructions = false, keep_thin_objects = false, no_inpaint = false;
    std::optional<PhotoImportParams::FillMethod> fill;
    std::string encoding = "auto";
    std::string time;
    std::optional<double> utc_offset_hours, latitude_deg, longitude_deg, elevation_m;
    std::string hdr = "auto";
    bool keep_colours = false;
    // A sequence's photographs trust the scale and colour fitted on their clear pixels by the median
    // clear share of the photographs within this many seconds either side (and of the two nearest
    // each side within twice it; HdrCalibrationParams::trusted_clear_fraction), not by their
    // own: a frame whose clear share spiked (the Mobotix's dawn, 07:03: 2x brighter than the minutes
    // around it) is calibrated as its neighbours are. 0: each photograph by its own share.
    double calibration_window_s = 150;
    double turbidity = 3.0;
    int resolution = 512;
    std::string out, preview, filled_mask;
};

// Runs the job: one sky per photograph (a sequence's into the folder `out` as STEM.exr, STEM.png and
// STEM.filled.png, under one sky circle, one north and one obstruction mask), printing what was
// found and done on stdout (the CLI's -q quiets its progress). Throws dynsky::Error naming the file
// and the problem; a sequence imports every photograph it can and then throws naming those it could
// not.
void run_photo_import(const PhotoImportJob& job);

}  // namespace dynsky
