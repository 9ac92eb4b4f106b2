#include "sky/preset_import.h"

#include "sky/hdr_recovery.h"

namespace dynsky {

PresetImportPlan plan_preset_import(const std::string& preset, const std::string& photo, int resolution) {
    PresetImportPlan plan;
    plan.preset = camera_preset(preset);
    plan.params = plan.preset.params;
    plan.params.resolution = resolution;
    plan.params.mask_path = find_preset_mask(preset, photo);
    plan.mask_found = !plan.params.mask_path.empty();
    if (!plan.mask_found) plan.params.detect_obstructions = true;
    plan.location = GeoLocation{plan.preset.latitude_deg, plan.preset.longitude_deg, plan.preset.elevation_m};
    plan.time = time_from_file_name(photo, plan.preset.filename_utc_offset_hours);
    return plan;
}

SkyImage import_preset_photo(const std::string& path, const std::string& preset, int import_resolution,
                             std::vector<unsigned char>* not_sky) {
    PresetImportPlan plan = plan_preset_import(preset, path, import_resolution);
    ImportedPhoto photo = import_photo(path, plan.params);
    SkyImage sky = photo.sky;
    if (!plan.time.empty() && photo.display_referred) {
        HdrCalibrationParams hp;
        hp.time = parse_utc_time(plan.time);
        hp.location = plan.location;
        hp.sun_search_deg = plan.preset.sun_search_deg;
        sky = recover_hdr(photo, hp);
    }
    if (not_sky) *not_sky = photo.not_sky;
    return sky;
}

}  // namespace dynsky
