#include "sky/preset_import.h"

#include <sstream>

#include "sky/hdr_recovery.h"

namespace dynsky {

PresetImportPlan plan_preset_import(const std::string& preset, const std::string& photo, int resolution,
                                    const std::string& time, bool look_for_mask,
                                    const std::optional<GeoLocation>& place) {
    PresetImportPlan plan;
    plan.preset = camera_preset(preset);
    const CameraPreset& cam = plan.preset;
    plan.params = cam.params;
    plan.params.resolution = resolution;
    plan.params.mask_path = look_for_mask ? find_preset_mask(preset, photo) : "";
    plan.mask_found = !plan.params.mask_path.empty();
    plan.location = place.value_or(GeoLocation{cam.latitude_deg, cam.longitude_deg, cam.elevation_m});
    plan.time = time.empty() ? photo_time(photo, cam.filename_utc_offset_hours).iso : time;
    if (plan.mask_found) {
        plan.obstructions = "mask " + plan.params.mask_path;
        return plan;
    }
    // No mask file: the camera's own obstructions from its geometry.
    const bool has_geometry = !cam.fixed_not_sky_rects.empty() || cam.shadow_band || !cam.horizon_obstructions.empty();
    if (!has_geometry) {
        plan.params.detect_obstructions = true;
        plan.obstructions = "dark obstructions detected (no mask file)";
        return plan;
    }
    auto& rects = plan.params.not_sky_rects;
    rects.insert(rects.end(), cam.fixed_not_sky_rects.begin(), cam.fixed_not_sky_rects.end());
    plan.params.horizon_obstructions = cam.horizon_obstructions;
    plan.obstructions = "the preset's obstruction geometry (no mask file)";
    if (cam.shadow_band) {
        if (plan.time.empty()) {
            // The band follows the sun: without a time it is found in the photograph (the darkest
            // strip of its shape), else taken as a dark object.
            ShadowBand band = *cam.shadow_band;
            band.find_in_photo = true;
            plan.params.shadow_band = band;
            plan.obstructions += "; no time, so the shadow band is found in the photograph";
        } else {
            ShadowBand band = *cam.shadow_band;
            band.azimuth_deg = compute_sun_position(parse_utc_time(plan.time), plan.location).azimuth_deg;
            plan.params.shadow_band = band;
            std::ostringstream s;
            s.precision(4);
            s << "; shadow band at the sun's azimuth " << band.azimuth_deg << " deg";
            plan.obstructions += s.str();
        }
    }
    return plan;
}

HdrCalibrationParams hdr_calibration_params(const PresetImportPlan& plan) {
    HdrCalibrationParams hp;
    hp.time = parse_utc_time(plan.time);
    hp.location = plan.location;
    hp.sun_search_deg = plan.preset.sun_search_deg;
    hp.camera_colour = plan.preset.colour;
    return hp;
}

SkyImage import_preset_photo(const std::string& path, const std::string& preset, int import_resolution,
                             std::vector<unsigned char>* not_sky) {
    PresetImportPlan plan = plan_preset_import(preset, path, import_resolution);
    ImportedPhoto photo = import_photo(path, plan.params);
    SkyImage sky = photo.sky;
    if (!plan.time.empty() && photo.display_referred) sky = recover_hdr(photo, hdr_calibration_params(plan));
    if (not_sky) *not_sky = photo.not_sky;
    return sky;
}

}  // namespace dynsky
