// The import of one photograph by a camera preset (sky/photo_import.h's CameraPreset): every
// decision a preset makes, in one place, for `dynsky sky import --preset P`, the training-set
// builder and the evaluation of cloud models alike.
//
// Decisions: the preset's geometry; its mask file found beside the photo (find_preset_mask), else
// the preset's own obstruction geometry (the TSI's arm, housing and a shadow band at the sun's
// azimuth for the photo's time; the Mobotix's horizon profile), or detection of dark obstructions
// for what the geometry cannot place (a band without a time); the place; the time from the file
// name on the preset's clock; HDR calibration against the clear-sky model (sky/hdr_recovery.h)
// when the time is known.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "sky/hdr_recovery.h"
#include "sky/photo_import.h"
#include "sky/sun_position.h"

namespace dynsky {

struct PresetImportPlan {
    CameraPreset preset;
    PhotoImportParams params;  // preset geometry, resolution, mask or detection
    GeoLocation location;      // the preset's place
    std::string time;          // ISO 8601 from the file name ("" if none)
    bool mask_found = false;   // the preset's mask file lies beside the photo
    std::string obstructions;  // for people: where the not-sky pixels come from
};

// `time` (ISO 8601 with a zone) overrides the file name's, `place` the preset's site (--lat, --lon,
// --elevation); the band follows the sun at the time and place used. look_for_mask false: the
// preset's geometry even if a mask file lies beside the photo.
PresetImportPlan plan_preset_import(const std::string& preset, const std::string& photo, int resolution,
                                    const std::string& time = "", bool look_for_mask = true,
                                    const std::optional<GeoLocation>& place = std::nullopt);

// The HDR calibration of a planned import: the photo's time (from its file name unless overridden),
// the camera's place, sun search radius and typical colour.
HdrCalibrationParams hdr_calibration_params(const PresetImportPlan& plan);

// The HDR sky exactly as `dynsky sky import --preset P --res R` writes it, with the import's
// not-sky mask (1 = hidden by the arm, band or masts and filled in) when asked for.
SkyImage import_preset_photo(const std::string& path, const std::string& preset, int import_resolution,
                             std::vector<unsigned char>* not_sky = nullptr);

}  // namespace dynsky
