#include "sky/photo_import_job.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>

#include <Eigen/Geometry>

#include "sky/hdr_recovery.h"
#include "sky/preset_import.h"
#include "sky/sky_image.h"
#include "sky/sun_position.h"
#include "util/parse.h"
#include "util/image_input.h"
#include "util/atomic_file.h"
#include "util/error.h"
#include "util/exposure.h"
#include "util/file_hash.h"
#include "util/frame_names.h"
#include "util/image.h"
#include "util/math.h"
#include "util/progress.h"

namespace dynsky {

namespace {

// The header key that records what made a sequence's sky (import_settings_key).
constexpr const char* kImportSettingsKey = "dynsky:import_settings";

// One photograph's import: the job, and what a sequence found for all its photographs.
struct OnePhoto : PhotoImportJob {
    explicit OnePhoto(const PhotoImportJob& job) : PhotoImportJob(job) {}
    std::string photo;
    std::string circle_origin;                            // how the circle given came about ("" : "given")
    std::optional<std::array<int, 2>> circle_photo_size;  // the sequence's photos' size, when its circle is used
    std::optional<PhotoImportParams::ColourShading> colour_shading;  // a sequence's, measured on it
    std::optional<double> north_found;             // a sequence's north, found from the sun on its photographs
    std::optional<double> trusted_clear_fraction;  // imposed: the sequence's smoothed over time
    std::optional<Vec3d> sun_in_photo;             // imposed: on the sequence's sun track
    // A sequence's: the clipped suns found far from the clock's, said once for all (photo -> its
    // offset in degrees and the warning a single import prints).
    std::map<std::string, std::pair<double, std::string>>* far_suns = nullptr;
    bool say_preview = true;  // false: a sequence says its previews' exposure once for all
};

// The header keys of a calibrated sky's own clear share and, where one was imposed, that one: what
// a sequence's smoothing reads (HdrCalibrationParams::trusted_clear_fraction).
constexpr const char* kClearFractionKey = "dynsky:clear_fraction";
constexpr const char* kTrustedClearFractionKey = "dynsky:trusted_clear_fraction";
// ... and where the clock puts the sun, where the photograph shows it, and where a sequence's sun
// track put it (direction_text): what a sequence's sun track is fitted to.
constexpr const char* kSunClockKey = "dynsky:sun_clock";
constexpr const char* kSunSeenKey = "dynsky:sun_seen";
constexpr const char* kSunTrackKey = "dynsky:sun_track";

std::string direction_text(const Vec3d& d) {
    char t[120];
    std::snprintf(t, sizeof t, "%.9g %.9g %.9g", d.x(), d.y(), d.z());
    return t;
}

std::optional<Vec3d> parse_direction(const std::string& text) {
    std::istringstream in(text);
    Vec3d d;
    if (!(in >> d.x() >> d.y() >> d.z()) || !(d.norm() > 0.5 && d.norm() < 2)) return std::nullopt;
    return d.normalized();
}

// What one photograph's import is given: geometry and masks, the place, its time, and whether it is
// calibrated.
struct ImportPlan {
    PhotoImportParams params;
    double sun_search = 3;
    std::optional<CameraColour> camera_colour;
    std::string obstructions, time;
    bool calibrate = false;
    UtcTime utc;
    GeoLocation where;
};

ImportPlan plan_import(const OnePhoto& o, bool verbose) {
    ImportPlan plan;
    PhotoImportParams& params = plan.params;
    check_extension("--out", o.out, ".exr");
    if (!o.preview.empty()) check_extension("--preview", o.preview, ".png");
    if (!o.filled_mask.empty()) check_extension("--filled-mask", o.filled_mask, ".png");
    check_outputs_are_not_inputs({o.out, o.preview, o.filled_mask}, {o.photo, o.mask});
    for (const std::string& f : {o.out, o.preview, o.filled_mask})  // before any work, not after the sky
        if (!f.empty()) check_output_file(f);
    if (!o.preview.empty() && !o.filled_mask.empty() &&
        std::filesystem::weakly_canonical(o.preview) == std::filesystem::weakly_canonical(o.filled_mask))
        throw Error("--filled-mask " + o.filled_mask + ": the same file as --preview (one would replace the other)");
    check_sky_resolution(o.resolution);
    if (o.hdr != "auto" && o.hdr != "none" && o.hdr != "calibrated")
        throw Error("--hdr '" + o.hdr + "': use none, calibrated or auto");

    double lat = o.latitude_deg.value_or(0), lon = o.longitude_deg.value_or(0), elevation = o.elevation_m.value_or(0),
           utc_offset = o.utc_offset_hours.value_or(0);
    double& sun_search = plan.sun_search;
    std::optional<CameraColour>& camera_colour = plan.camera_colour;
    bool have_location = o.latitude_deg && o.longitude_deg;
    std::string& obstructions = plan.obstructions;
    if (!o.preset.empty()) {
        // The preset's decisions (sky/preset_import.h), then the options that override them.
        const CameraPreset preset = camera_preset(o.preset);
        lat = o.latitude_deg.value_or(preset.latitude_deg);
        lon = o.longitude_deg.value_or(preset.longitude_deg);
        elevation = o.elevation_m.value_or(preset.elevation_m);
        utc_offset = o.utc_offset_hours.value_or(preset.filename_utc_offset_hours);
        sun_search = preset.sun_search_deg;
        camera_colour = preset.colour;
        have_location = true;
        // The shadow band follows the sun at the time used (given, or the file name's on its clock).
        std::string band_time = o.time.empty() ? photo_time(o.photo, utc_offset).iso : o.time;
        if (o.mask.empty()) {
            PresetImportPlan plan = plan_preset_import(o.preset, o.photo, o.resolution, band_time, !o.no_preset_mask,
                                                       GeoLocation{lat, lon, elevation});
            params = plan.params;
            obstructions = plan.obstructions;
        } else {
            params = preset.params;  // a mask given replaces the preset's own obstructions
        }
    }
    params.resolution = o.resolution;
    params.encoding = o.encoding;
    // A circle given (--center, --radius) or searched for (--auto-circle) is not the preset's: the
    // preset's photo size no longer applies (another camera under a preset was refused even so).
    if (o.circle || o.auto_circle) params.circle_photo_size.reset();
    if (o.circle) params.circle = o.circle;
    if (o.circle_photo_size) params.circle_photo_size = o.circle_photo_size, params.circle_source = "the sequence";
    if (o.auto_circle) params.circle.reset();
    if (o.lens) params.lens = *o.lens;
    if (o.north_deg) params.north_deg = *o.north_deg;
    if (o.north_found) params.north_deg = *o.north_found;
    if (o.colour_shading) params.colour_shading = o.colour_shading;
    if (o.mirror) params.mirrored = true;
    if (o.tilt_deg) params.tilt_deg = *o.tilt_deg;
    if (o.tilt_azimuth_deg) params.tilt_azimuth_deg = *o.tilt_azimuth_deg;
    if (!o.mask.empty()) params.mask_path = o.mask, params.mask_layout = o.mask_layout;
    if (o.detect_obstructions) params.detect_obstructions = true;
    if (o.keep_thin_objects) params.detect_thin_obstructions = false;
    if (o.no_inpaint) params.inpaint = false;
    params.fill_method = o.fill.value_or(PhotoImportParams::FillMethod::Texture);

    // Time: given, or the photograph's (its file name's, else its EXIF's: sky/photo_import.h
    // photo_time); one without a zone is on a clock --utc-offset hours ahead of UTC, which presets
    // know; without a preset or --utc-offset such a time is not guessed.
    std::string& time = plan.time;
    time = o.time;
    if (time.empty()) {
        const PhotoTime found = photo_time(o.photo, utc_offset);
        time = found.iso;
        if (!time.empty() && !found.zone_in_file && o.preset.empty() && !o.utc_offset_hours) {
            if (verbose)
                std::printf(
                    "note: %s: its %s gives a time without a zone (%s): give --utc-offset HOURS (or --time) "
                    "to use it\n",
                    o.photo.c_str(), found.source.c_str(), time.substr(0, 19).c_str());
            time.clear();
        }
    }
    plan.calibrate = o.hdr == "calibrated" || (o.hdr == "auto" && have_location && !time.empty());
    plan.where = GeoLocation{lat, lon, elevation};
    if (plan.calibrate) {
        if (time.empty())
            throw_file_error(o.photo, "--hdr calibrated needs the photo's time: give --time (ISO 8601 with a zone)");
        if (!have_location) throw Error("--hdr calibrated needs the place: give --lat and --lon (or a --preset)");
        plan.utc = parse_utc_time(time);
        validate_location(plan.where);
    }
    if (o.find_north && !o.north_found && !plan.calibrate)
        throw Error(
            "--find-north needs the photo's time and place (--time or a time in its name, --lat and --lon), "
            "for the sun it turns the photograph by");
    return plan;
}

// What decides one photograph's sky, for a sequence import that resumes: every option, what the
// sequence found (circle, north, obstruction mask, colour shading), and the photograph and the
// masks it reads by content, as a hash. A field added to PhotoImportJob or OnePhoto belongs here.
std::string import_settings_key(const OnePhoto& o) {
    std::ostringstream s;
    s << std::setprecision(17);
    auto number = [&](const char* name, const std::optional<double>& v) {
        s << name << '=';
        if (v) s << *v;
        s << ';';
    };
    // calibration=2: the skies carry the headers a sequence's smoothing and sun track read (skies of
    // an earlier version, without them, are imported again).
    s << "calibration=2;preset=" << o.preset << ";auto_circle=" << o.auto_circle << ";mirror=" << o.mirror
      << ";flatten_colour=" << o.flatten_colour << ";find_north=" << o.find_north
      << ";no_preset_mask=" << o.no_preset_mask << ";detect_obstructions=" << o.detect_obstructions
      << ";keep_thin_objects=" << o.keep_thin_objects << ";no_inpaint=" << o.no_inpaint
      << ";fill=" << (o.fill ? int(*o.fill) : -1) << ";encoding=" << o.encoding << ";time=" << o.time
      << ";hdr=" << o.hdr << ";keep_colours=" << o.keep_colours << ";turbidity=" << o.turbidity
      << ";resolution=" << o.resolution << ";lens=" << (o.lens ? lens_law_name(*o.lens) : "")
      << ";mask_layout=" << int(o.mask_layout) << ";circle_origin=" << o.circle_origin << ";";
    if (o.circle) s << "circle=" << o.circle->center_x << ',' << o.circle->center_y << ',' << o.circle->radius << ';';
    if (o.circle_photo_size)
        s << "circle_photo=" << (*o.circle_photo_size)[0] << 'x' << (*o.circle_photo_size)[1] << ';';
    if (o.colour_shading) {
        const auto& c = *o.colour_shading;
        s << "shading=" << c.rg2 << ',' << c.rg4 << ',' << c.bg2 << ',' << c.bg4 << ',' << c.max_radius << ';';
    }
    number("north", o.north_deg), number("north_found", o.north_found), number("tilt", o.tilt_deg);
    number("tilt_azimuth", o.tilt_azimuth_deg), number("utc_offset", o.utc_offset_hours);
    number("lat", o.latitude_deg), number("lon", o.longitude_deg), number("elevation", o.elevation_m);
    s << "photo=" << describe_file(o.photo) << ';';
    if (!o.mask.empty()) s << "mask=" << describe_file(o.mask) << ';';
    const ImportPlan plan = plan_import(o, false);  // a preset's mask file beside the photo, the time it reads
    if (!plan.params.mask_path.empty() && plan.params.mask_path != o.mask)
        s << "photo_mask=" << describe_file(plan.params.mask_path) << ';';
    s << "photo_time=" << plan.time;
    return hash_text(s.str());
}

// One photograph into one sky (o.photo, o.out, o.preview, o.filled_mask); `verbose`: the lines
// saying what was found and done (a sequence's import says it once for all). settings_key (a
// sequence's): recorded in the sky's header, so a resumed import knows it.
void import_one(const OnePhoto& o, bool verbose, const std::string& settings_key = "") {
    ImportPlan plan = plan_import(o, verbose);
    PhotoImportParams& params = plan.params;
    const bool calibrate = plan.calibrate;
    const UtcTime& utc = plan.utc;
    const GeoLocation& where = plan.where;
    const std::string& time = plan.time;
    const double sun_search = plan.sun_search;
    const std::optional<CameraColour>& camera_colour = plan.camera_colour;
    std::string obstructions = plan.obstructions;

    ImportedPhoto imported = import_photo(o.photo, params);
    if (o.find_north && !o.north_found) {
        // The photograph turned so that the sun it shows sits at the computed sun's azimuth.
        if (const std::optional<NorthFromSun> found = north_from_seen_sun(imported, utc, where)) {
            params.north_deg = found->north_deg;
            imported = import_photo(o.photo, params);
            if (verbose)
                std::printf(
                    "north: %.1f deg clockwise from the photo's top, found from the clipped sun (zenith %.1f deg, "
                    "computed %.1f; it lay %.1f deg from the computed sun before)\n",
                    found->north_deg, found->seen_zenith_deg, found->sun_zenith_deg, found->moved_deg);
        } else {
            std::fprintf(stderr,
                         "dynsky: warning: %s: --find-north: no clipped sun at the computed sun's height (%.1f deg up; "
                         "overcast, the sun hidden, a tilted camera or the wrong lens law?): north stays %.1f deg\n",
                         o.photo.c_str(), compute_sun_position(utc, where).elevation_deg(), params.north_deg);
        }
    }
    if (imported.exif_orientation != 1 && verbose)
        std::printf(
            "EXIF orientation %d: the photograph is turned as viewers show it before anything else "
            "(--center, --north and masks refer to that view)\n",
            imported.exif_orientation);
    const SkyCircle& c = imported.geometry.circle;
    if (imported.circle_detected && !imported.circle_caution.empty())  // even with -q: the sky may be cut wrong
        std::fprintf(stderr, "dynsky: warning: %s: %s\n", o.photo.c_str(), imported.circle_caution.c_str());
    if (verbose)
        std::printf("sky circle: centre (%.1f, %.1f) px, radius %.1f px (%s); lens %s, north %.1f deg, %s%s\n",
                    c.center_x, c.center_y, c.radius,
                    imported.circle_detected  ? "found"
                    : o.circle_origin.empty() ? "given"
                                              : o.circle_origin.c_str(),
                    lens_law_name(imported.geometry.lens), imported.geometry.north_deg,
                    imported.geometry.mirrored ? "mirrored" : "not mirrored",
                    imported.geometry.tilt_deg != 0
                        ? (", tilt " + std::to_string(imported.geometry.tilt_deg) + " deg").c_str()
                        : "");
    long long filled = 0, disc = 0;
    for (int j = 0; j < o.resolution; ++j)
        for (int i = 0; i < o.resolution; ++i)
            if (imported.sky.in_disc(i, j)) {
                ++disc;
                filled += imported.not_sky[size_t(j) * o.resolution + i];
            }
    // How the values were taken: the file's pixels decide (--encoding auto), so say what was decided.
    std::string why = " (--encoding)";
    if (o.encoding == "auto")
        why = imported.pixel_type.empty() ? ""
                                          : " (" + imported.pixel_type + " pixels; --encoding " +
                                                (imported.display_referred ? "linear" : "srgb") + " if they are not)";
    if (verbose)
        std::printf("values: %s%s\n",
                    !imported.display_referred     ? "linear, taken as they are"
                    : imported.encoding_gamma <= 0 ? "sRGB-encoded, decoded to linear"
                                                   : ("gamma " + number_text(imported.encoding_gamma, 4) +
                                                      "-encoded (its header), decoded to linear")
                                                         .c_str(),
                    why.c_str());
    if (imported.display_referred && verbose)
        std::printf("saturation: %s\n",
                    imported.clip_level < 1.0
                        ? ("clipped at encoded level " + std::to_string(imported.clip_level)).c_str()
                        : "no clipping plateau found");
    if (obstructions.empty() && !params.mask_path.empty()) obstructions = "mask " + params.mask_path;
    if (params.shadow_band && params.shadow_band->find_in_photo) {
        char found[160];
        if (imported.shadow_band_found)
            std::snprintf(found, sizeof found,
                          ": at azimuth %.1f deg, its strip %.0f %% of the sky beside it in brightness and colour",
                          imported.shadow_band_found->azimuth_deg, 100 * imported.shadow_band_found->contrast);
        else
            std::snprintf(found, sizeof found, ": none darker than %.0f %% of the sky beside it, dark objects filled",
                          100 * kShadowBandContrast);
        obstructions += found;
        if (!imported.shadow_band_found)
            std::fprintf(stderr,
                         "dynsky: warning: %s: no shadow band found in the photograph; give --time (the band is at "
                         "the sun)\n",
                         o.photo.c_str());
    }
    if (verbose)
        std::printf("not-sky pixels filled: %.1f%% of the disc%s%s\n", disc ? 100.0 * filled / disc : 0.0,
                    obstructions.empty() ? "" : (" (" + obstructions + ")").c_str(),
                    params.inpaint ? "" : " (left black: --no-inpaint)");

    SkyImage sky = imported.sky;
    std::map<std::string, std::string> calibration_strings;
    std::string unit = "relative linear units (decoded photo values)";
    if (calibrate) {
        if (!imported.display_referred) {
            // Its own radiance, but where the sun is follows from the time and place: recorded, as a
            // calibrated sky records it (the moving sky and the frame stage look for it there).
            const SunPosition sun = compute_sun_position(utc, where);
            if (sun.elevation_deg() > 0) sky.sun_direction = sun.direction().cast<float>();
            if (o.hdr == "calibrated")  // asked for, not done: say so even with -q
                std::fprintf(stderr,
                             "dynsky: warning: %s: --hdr calibrated: its values are linear (an HDR file, or --encoding "
                             "linear) and are kept at their own scale; calibration against the clear sky is for "
                             "display-encoded photographs\n",
                             o.photo.c_str());
            if (verbose)
                std::printf(
                    "HDR input: kept at its own scale (no calibration); time %s, sun at azimuth %.1f deg, "
                    "elevation %.1f deg%s\n",
                    format_utc_time(utc).c_str(), sun.azimuth_deg, sun.elevation_deg(),
                    sky.sun_direction ? " (recorded)" : " (below the horizon: not recorded)");
        } else {
            HdrCalibrationParams hp;
            hp.time = utc;
            hp.location = where;
            hp.turbidity = o.turbidity;
            hp.sun_search_deg = sun_search;
            hp.camera_colour = camera_colour;
            hp.white_balance = !o.keep_colours;
            hp.trusted_clear_fraction = o.trusted_clear_fraction;
            hp.sun_in_photo = o.sun_in_photo;
            HdrCalibrationReport report;
            sky = recover_hdr(imported, hp, &report);
            calibration_strings[kClearFractionKey] = number_text(report.clear_fraction, 9);
            if (o.trusted_clear_fraction)
                calibration_strings[kTrustedClearFractionKey] = number_text(*o.trusted_clear_fraction, 9);
            calibration_strings[kSunClockKey] = direction_text(report.clock_sun);
            if (report.seen_sun) calibration_strings[kSunSeenKey] = direction_text(*report.seen_sun);
            if (o.sun_in_photo) calibration_strings[kSunTrackKey] = direction_text(*o.sun_in_photo);
            if (verbose) std::printf("time %s; %s\n", format_utc_time(utc).c_str(), report.summary().c_str());
            if (std::string w = report.sun_offset_warning(); !w.empty()) {
                if (o.far_suns && !report.sun_elsewhere) (*o.far_suns)[o.photo] = {report.sun_offset_deg, w};
                else std::fprintf(stderr, "dynsky: warning: %s: %s\n", o.photo.c_str(), w.c_str());
            }
            unit = "W m^-2 sr^-1 (calibrated against the clear-sky model)";
        }
    } else {
        if (verbose)
            std::printf("HDR: none (%s)\n",
                        o.hdr == "none"    ? "--hdr none: the photograph's own values, uncalibrated"
                        : !time.empty()    ? "no place: give --lat/--lon or a --preset for calibrated radiance"
                        : o.preset.empty() ? "give --time with --lat/--lon or a --preset for calibrated radiance"
                                           : "the photograph's name and EXIF carry no time: give --time for calibrated "
                                             "radiance");
    }
    std::ostringstream source;
    source << sky.source;
    if (!time.empty()) source << " time=" << time;
    sky.source = source.str();
    ImageMetadata extra;
    if (!settings_key.empty()) extra.strings[kImportSettingsKey] = settings_key;
    for (const auto& [key, value] : calibration_strings) extra.strings[key] = value;
    save_sky(o.out, sky, "", extra);
    if (!o.filled_mask.empty()) {
        // 255 where the import filled the sky in (arm, band, masts, unseen), 0 elsewhere: what
        // evaluations, training and the moving sky leave out. Written after the sky, and the sky
        // removed when it cannot be: a photograph that failed left its mask alone, and a sky without
        // its mask reads as seen everywhere.
        Image m(o.resolution, o.resolution, 1);
        for (size_t p = 0; p < imported.not_sky.size(); ++p) m.pixels[p] = imported.not_sky[p] ? 1.0f : 0.0f;
        try {
            write_image(o.filled_mask, m);
        } catch (const Error&) {
            std::error_code ec;
            std::filesystem::remove(o.out, ec);
            throw;
        }
    }
    if (verbose) std::printf("wrote %s (%dx%d fisheye, %s)\n", o.out.c_str(), o.resolution, o.resolution, unit.c_str());
    if (!o.preview.empty()) write_display_preview(o.preview, sky_to_image(sky), verbose && o.say_preview);
}

// Every photograph's time, before anything is written: a sequence some of whose photographs have a
// time and others none (a name without a zone, no EXIF) made skies calibrated against the sun
// (W m^-2 sr^-1) beside skies in the photographs' own units, 40 x apart on a test, and ordered them
// wrongly; the warning named the first photograph only.
// Returns each photograph's planned time ("" for one whose plan fails: named by its own import).
std::vector<std::string> refuse_mixed_times(const PhotoImportJob& o, const std::vector<std::string>& photos,
                                            const std::vector<std::string>& outputs) {
    std::vector<std::string> timeless, times(photos.size());
    size_t timed = 0;
    for (size_t i = 0; i < photos.size(); ++i) {
        OnePhoto probe(o);
        probe.photo = photos[i], probe.out = outputs[i], probe.preview.clear(), probe.filled_mask.clear();
        try {
            times[i] = plan_import(probe, false).time;
            if (times[i].empty()) timeless.push_back(photos[i]);
            else ++timed;
        } catch (const Error&) {
            // Named by its own import below.
        }
    }
    if (timed == 0 || timeless.empty()) return times;
    std::string listed;
    for (size_t k = 0; k < timeless.size() && k < 4; ++k) listed += (k ? ", " : "") + timeless[k];
    if (timeless.size() > 4) listed += ", ...";
    throw Error(std::to_string(timeless.size()) + " of " + std::to_string(photos.size()) +
                " photographs have no time the import can use (" + listed +
                ": a time without a zone in the name or EXIF, or none) and the others have one: their skies "
                "would be in the photographs' own units beside skies calibrated against the sun, and out of "
                "order. Give --utc-offset HOURS (the camera clock's offset from UTC), or import them apart");
}

// Every photograph's encoding, before anything is written: HDR files (float pixels: their own
// linear scale) among display-encoded photographs (calibrated against the sun) gave skies 100 x
// apart in one sequence, without a word. Unreadable files are named by their own import.
void refuse_mixed_encodings(const std::vector<std::string>& photos, const std::string& encoding) {
    if (encoding != "auto") return;  // one encoding for all, as asked
    std::string linear, encoded;
    for (const std::string& p : photos) {
        ImageFileInput in(p);
        if (!in) continue;
        // As the import decides it (is_display_encoded), from the header alone.
        Image header;
        header.file_pixel_type = in->spec().format.c_str();
        header.metadata.strings["oiio:ColorSpace"] = in->spec().get_string_attribute("oiio:ColorSpace");
        std::string& kind = is_display_encoded(header, p, encoding) ? encoded : linear;
        if (kind.empty()) kind = p;
        if (!linear.empty() && !encoded.empty())
            throw Error(linear + " holds linear (HDR) pixels and " + encoded +
                        " display-encoded ones: their skies would be in different units in one sequence (the "
                        "HDR file's own scale beside skies calibrated against the sun). Import them apart");
    }
}

// Each photograph's clear share smoothed over time: the median of the photographs' own within
// window_s either side (and the two nearest on each side within two windows), so that a frame whose clear
// share spiked takes its neighbours' while a lasting change (the sky clearing) stays where it
// happened. `seconds` in any order; photographs without a share get none.
std::vector<std::optional<double>> smooth_over_time(const std::vector<double>& seconds,
                                                    const std::vector<std::optional<double>>& values, double window_s) {
    std::vector<size_t> order;
    for (size_t i = 0; i < values.size(); ++i)
        if (values[i]) order.push_back(i);
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return seconds[a] < seconds[b]; });
    std::vector<std::optional<double>> out(values.size());
    const size_t count = order.size();
    for (size_t k = 0; k < count; ++k) {
        // Within the window, or among the two nearest each side if those lie within two windows
        // (photographs hours apart are not neighbours).
        const double t = seconds[order[k]];
        size_t lo = k, hi = k;
        while (lo > 0 &&
               (t - seconds[order[lo - 1]] <= window_s || (k - lo < 2 && t - seconds[order[lo - 1]] <= 2 * window_s)))
            --lo;
        while (hi + 1 < count &&
               (seconds[order[hi + 1]] - t <= window_s || (hi - k < 2 && seconds[order[hi + 1]] - t <= 2 * window_s)))
            ++hi;
        std::vector<double> v;
        for (size_t q = lo; q <= hi; ++q) v.push_back(*values[order[q]]);
        out[order[k]] = middle_mean(std::move(v));
    }
    return out;
}

// Whether two clear shares calibrate alike: the same trust in the clear pixels' scale and colour
// (HdrCalibrationParams' ramps) within 0.01.
bool same_trust(double a, double b) {
    const HdrCalibrationParams p;
    return std::abs(trust_ramp(a, p.min_clear_fraction, p.full_clear_fraction) -
                    trust_ramp(b, p.min_clear_fraction, p.full_clear_fraction)) < 0.01 &&
           std::abs(trust_ramp(a, p.min_white_balance_fraction, p.full_white_balance_fraction) -
                    trust_ramp(b, p.min_white_balance_fraction, p.full_white_balance_fraction)) < 0.01 &&
           (a >= p.min_white_balance_fraction) == (b >= p.min_white_balance_fraction);
}

// The photograph whose sky skies_in_time_order will put last: the latest planned time (the last in
// natural order among equal times), or the last in natural order where not every photograph has a
// time. Imported once, with the texture fill, instead of smoothly and then again.
size_t last_photo_in_time(const std::vector<std::string>& outputs, const std::vector<std::string>& times) {
    std::vector<size_t> order(outputs.size());
    for (size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) { return natural_less(outputs[a], outputs[b]); });
    const bool all_timed = std::none_of(times.begin(), times.end(), [](const std::string& t) { return t.empty(); });
    if (!all_timed) return order.back();
    try {
        size_t last = order.front();
        for (size_t k : order)
            if (utc_seconds(times[k]) >= utc_seconds(times[last])) last = k;
        return last;
    } catch (const Error&) {
        return order.back();  // a time that does not parse: checked against the written skies anyway
    }
}

// The image files of a folder, in name order as people number them (a sequence's frames are named
// by their time; "img 9" before "img 10").
std::vector<std::string> photos_in_folder(const std::string& folder) {
    std::vector<std::string> out;
    for (const auto& e : std::filesystem::directory_iterator(folder)) {
        const std::string path = e.path().string(), ext = file_extension(path);
        if (!e.is_regular_file() || is_hidden_file(path) ||
            (path.size() >= 11 && path.compare(path.size() - 11, 11, ".filled.png") == 0) ||
            e.path().filename() == kSequenceObstructionsName)
            continue;
        for (const char* known : {".jpg", ".jpeg", ".png", ".tif", ".tiff", ".exr", ".hdr", ".heic", ".heif", ".webp"})
            if (ext == known) out.push_back(path);
    }
    std::sort(out.begin(), out.end(), natural_less);
    if (out.empty())
        throw_file_error(folder,
                         "no photographs in this folder (.jpg, .jpeg, .png, .tif, .tiff, .exr, .hdr, .heic, .webp)");
    return out;
}

}  // namespace

void run_photo_import(const PhotoImportJob& o) {
    namespace fs = std::filesystem;
    if (o.photos.empty()) throw Error("no photograph to import");
    const bool sequence = o.photos.size() > 1 || fs::is_directory(o.photos.front());
    if (!sequence) {
        if (o.flatten_colour)
            throw Error(
                "--flatten-colour measures a camera's colour shading on its overcast photographs: give a "
                "sequence (several photographs or a folder)");
        if (o.calibration_window_s != PhotoImportJob{}.calibration_window_s)
            std::fprintf(stderr,
                         "dynsky: warning: --calibration-window smooths a sequence's calibrations over time; one "
                         "photograph is calibrated on its own: ignored\n");
        OnePhoto one(o);
        one.photo = o.photos.front();
        import_one(one, true);
        return;
    }
    // A sequence: one sky per photograph in the folder -o, under the same sky circle, so frames
    // imported one by one do not wobble against each other (sky/photo_import.h
    // find_sequence_sky_circle). Each sky's filled mask and preview lie beside it, named as
    // `sky evaluate --photos` and people look for them.
    std::vector<std::string> photos;
    for (const std::string& p : o.photos) {
        if (fs::is_directory(p)) {
            if (o.photos.size() > 1)
                throw Error(p + ": a folder among several photographs: give one folder, or the photographs");
            photos = photos_in_folder(p);
        } else {
            photos.push_back(p);
        }
    }
    if (file_extension(o.out) == ".exr")
        throw Error("--out " + o.out +
                    ": with several photographs -o, --out is the folder their skies go to (STEM.exr each)");
    if (!o.preview.empty() || !o.filled_mask.empty())
        throw Error(std::string(o.preview.empty() ? "--filled-mask" : "--preview") +
                    ": with several photographs each sky's preview and filled mask are written beside it "
                    "(STEM.png, STEM.filled.png)");
    std::vector<std::string> outputs;
    for (const std::string& p : photos) {
        const std::string stem = fs::path(p).stem().string();
        outputs.push_back((fs::path(o.out) / (stem + ".exr")).string());
    }
    for (size_t i = 1; i < photos.size(); ++i)
        for (size_t j = 0; j < i; ++j)
            if (outputs[i] == outputs[j])
                throw Error(photos[i] + " and " + photos[j] + " would both become " + outputs[i] +
                            " (the same name): rename one");
    check_outputs_are_not_inputs(outputs, photos);
    // One --time for a sequence stamped every sky with it, without a word: `sky predict` and
    // `sky evaluate` then refused the skies as taken at the same moment.
    if (!o.time.empty() && photos.size() > 1)
        throw Error("--time " + o.time + " would give all " + std::to_string(photos.size()) + " photographs (" +
                    photos.front() +
                    ", ...) the same time: a sequence takes each photograph's own, from its file name or EXIF "
                    "(docs/sky-import.md lists the names understood; --utc-offset for a clock without a zone). "
                    "Leave out --time, or import one photograph at a time");
    const std::vector<std::string> planned_times = refuse_mixed_times(o, photos, outputs);
    refuse_mixed_encodings(photos, o.encoding);
    // Held alone while it is written (two imports into one folder mixed their skies and previews).
    const OutputFolder out_folder(o.out);
    remove_stale_temporaries(o.out);  // of a killed run into the same folder

    OnePhoto each(o);
    // A sequence's hidden pixels are filled smoothly unless asked otherwise: the texture fill takes
    // seconds a frame and differs from frame to frame.
    if (!o.fill) each.fill = PhotoImportParams::FillMethod::Smooth;
    if (!o.circle && (o.preset.empty() || o.auto_circle || !camera_preset(o.preset).params.circle)) {
        PhotoImportParams search = o.preset.empty() ? PhotoImportParams{} : camera_preset(o.preset).params;
        search.encoding = o.encoding;
        const SequenceSkyCircle found = find_sequence_sky_circle(photos, search);
        const SkyCircle& c = found.circle;
        std::printf(
            "sky circle: centre (%.1f, %.1f) px, radius %.1f px, the median of %d of %d photographs spread over the "
            "sequence (each within %.1f px of centre, %.1f px of radius); used for every photograph\n",
            c.center_x, c.center_y, c.radius, found.found, found.tried, found.centre_spread_px, found.radius_spread_px);
        for (const std::string& e : found.not_found) std::fprintf(stderr, "dynsky: warning: %s\n", e.c_str());
        // The median holds against a few dark frames; a caution most frames share (an elliptical
        // outline: every frame of the camera) holds for the circle used.
        if (!found.cautions.empty() && 2 * found.cautions.size() >= size_t(found.found))
            std::fprintf(stderr, "dynsky: warning: %zu of the %d photographs whose circle was found say: %s\n",
                         found.cautions.size(), found.found, found.cautions.front().c_str());
        each.circle = c;
        each.auto_circle = false;
        each.circle_origin = "the sequence's";
        each.circle_photo_size = found.photo_size;
    }
    if (o.detect_obstructions && o.preset.empty() && o.mask.empty()) {
        // One obstruction mask for the sequence (sky/photo_import.h find_sequence_obstructions),
        // written beside the skies, used by every import instead of finding them frame by frame.
        PhotoImportParams search;
        search.encoding = o.encoding;
        const SkyCircle circle = *each.circle;
        Image percentile;
        const std::vector<unsigned char> hidden = find_sequence_obstructions(photos, circle, search, 15, &percentile);
        Image mask(percentile.width, percentile.height, 1);
        long long in_circle = 0, hidden_in_circle = 0;
        for (int y = 0; y < mask.height; ++y)
            for (int x = 0; x < mask.width; ++x) {
                const size_t p = size_t(y) * mask.width + x;
                mask.pixels[p] = hidden[p] ? 0.0f : 1.0f;
                if (std::hypot(x - circle.center_x, y - circle.center_y) <= circle.radius)
                    ++in_circle, hidden_in_circle += hidden[p];
            }
        const std::string mask_path = (fs::path(o.out) / kSequenceObstructionsName).string();
        write_image(mask_path, mask);
        std::printf(
            "obstructions: found once for the sequence, on the 80th percentile of %zu photographs spread over "
            "it: %.1f%% of the sky circle (%s, black = not sky); used for every photograph\n",
            std::min<size_t>(photos.size(), 15), in_circle ? 100.0 * hidden_in_circle / in_circle : 0.0,
            mask_path.c_str());
        each.mask = mask_path;
        each.mask_layout = MaskLayout::PhotoBlackIsNotSky;
        each.detect_obstructions = false;
        each.keep_thin_objects = true;  // found on the percentile with the rest
    } else if (o.preset.empty() && o.mask.empty())
        std::printf(
            "note: rooftops, trees and masts at the horizon are left in the skies (thin ones aside): "
            "--detect-obstructions finds them once for the whole sequence\n");
    if (o.flatten_colour) {
        // The camera's colour shading, measured on the sequence's overcast photos and divided out of
        // every one (sky/photo_import.h find_sequence_colour_shading).
        PhotoImportParams probe = o.preset.empty() ? PhotoImportParams{} : camera_preset(o.preset).params;
        probe.encoding = o.encoding;
        if (each.circle) probe.circle = each.circle;
        if (!each.mask.empty()) probe.mask_path = each.mask, probe.mask_layout = MaskLayout::PhotoBlackIsNotSky;
        if (o.lens) probe.lens = *o.lens;
        if (const std::optional<SequenceColourShading> found = find_sequence_colour_shading(photos, probe)) {
            const auto& c = found->shading;
            const double r2 = 0.81;
            std::printf(
                "colour shading: log(R/G) %+.3f and log(B/G) %+.3f at 81 deg against the zenith, measured on "
                "%d overcast of %d photographs (fit within %.3f); divided out of every photograph\n",
                c.rg2 * r2 + c.rg4 * r2 * r2, c.bg2 * r2 + c.bg4 * r2 * r2, found->overcast, found->tried,
                found->rms_fit);
            each.colour_shading = c;
        } else {
            std::fprintf(stderr,
                         "dynsky: warning: --flatten-colour: fewer than 3 overcast photographs among those looked at "
                         "(a clear sky's colour changes towards the horizon by itself): the colours are kept\n");
        }
    }
    if (o.find_north) {
        // One north for the sequence: found from the sun on up to 25 photographs spread over it (at
        // 128 px), and agreed on (consensus_north).
        std::vector<double> norths;
        const int count = int(photos.size()), tries = std::min(count, 25);
        for (int k = 0; k < tries; ++k) {
            OnePhoto probe = each;
            const size_t at = spread_index(k, tries, count);
            probe.photo = photos[at], probe.out = outputs[at], probe.preview.clear(), probe.filled_mask.clear();
            probe.resolution = 128;
            try {
                const ImportPlan plan = plan_import(probe, false);
                const std::optional<NorthFromSun> f = north_from_seen_sun(import_photo(probe.photo, plan.params),
                                                                          plan.utc, plan.where);
                if (f) norths.push_back(f->north_deg);
            } catch (const Error&) {
                // No time, unreadable: this one says nothing about north (the import below names it).
            }
        }
        if (norths.empty()) {
            std::fprintf(
                stderr,
                "dynsky: warning: --find-north: none of %d photographs spread over the sequence shows a clipped "
                "sun at the computed sun's height: north stays %.1f deg\n",
                tries, o.north_deg.value_or(0.0));
        } else if (norths.size() == 1 && tries > 1) {
            std::fprintf(stderr,
                         "dynsky: warning: --find-north: only 1 of %d photographs spread over the sequence shows a "
                         "clipped sun at the computed sun's height: too little to trust (glare can look like it); "
                         "north stays %.1f deg; give --north DEG\n",
                         tries, o.north_deg.value_or(0.0));
        } else if (const ConsensusNorth north = consensus_north(norths, tries); !north.agreed) {
            std::fprintf(stderr,
                         "dynsky: warning: --find-north: the photographs disagree on north (%d of the %zu that show "
                         "a clipped sun within 10 deg of %.1f deg): north stays %.1f deg; give --north DEG\n",
                         north.near, norths.size(), north.north_deg, o.north_deg.value_or(0.0));
        } else {
            std::printf(
                "north: %.1f deg clockwise from the photos' top, found from the clipped sun on %zu of %d "
                "photographs spread over the sequence (%d within %.1f deg of it); used for every photograph\n",
                north.north_deg, norths.size(), tries, north.near, north.spread_deg);
            each.north_found = north.north_deg;
        }
        each.find_north = false;
    }
    std::vector<std::string> failed;
    auto has_failed = [&](size_t i) { return std::find(failed.begin(), failed.end(), photos[i]) != failed.end(); };
    size_t kept = 0;
    bool said = false;
    std::map<std::string, std::pair<double, std::string>> far_suns;
    each.far_suns = &far_suns;
    size_t suns_seen = 0;  // photographs whose clipped sun was found (their skies' dynsky:sun_seen)
    each.say_preview = false;
    // Photograph i's files, and whether they are whole and made with `key` (a stopped import goes on
    // where it stopped: long sequences lost every finished sky to an interruption).
    auto take = [&](size_t i) {
        each.photo = photos[i];
        each.out = outputs[i];
        each.preview = (fs::path(o.out) / (fs::path(photos[i]).stem().string() + ".png")).string();
        each.filled_mask = filled_mask_path(outputs[i]);
    };
    auto made_with = [&](const std::string& key) {
        return made_earlier_with({each.out, each.filled_mask, each.preview}, kImportSettingsKey, key);
    };
    auto key_with_fill = [&](PhotoImportParams::FillMethod fill) {
        OnePhoto other = each;
        other.fill = fill;
        return import_settings_key(other);
    };
    // The earlier sky's preview and mask go first: the sky is written first and carries the key, so
    // a run stopped after it left the earlier import's preview beside it, kept on resume.
    auto import_again = [&](const std::string& key, bool verbose) {
        std::error_code gone;
        fs::remove(each.preview, gone), fs::remove(each.filled_mask, gone);
        import_one(each, verbose, key);
    };
    // The last sky in time is filled with the sky's texture (below); guessed here from the planned
    // times so that it is imported once, checked against the written skies after.
    const size_t texture_at =  // photos.size(): none (a fill was asked for, or a single photograph)
        !o.fill && photos.size() >= 2 ? last_photo_in_time(outputs, planned_times) : photos.size();
    ProgressBar progress((long long)photos.size(), "importing " + std::to_string(photos.size()) + " photographs");
    for (size_t i = 0; i < photos.size(); ++i) {
        take(i);
        each.fill = o.fill            ? o.fill
                    : i == texture_at ? PhotoImportParams::FillMethod::Texture
                                      : PhotoImportParams::FillMethod::Smooth;
        try {
            const std::string key = import_settings_key(each);
            // Kept also when made with the texture fill: the sequence's last sky (below).
            if (made_with(key) || (!o.fill && made_with(key_with_fill(PhotoImportParams::FillMethod::Texture)))) {
                ++kept;
                progress.advance();
                continue;
            }
            // The first imported says what it found and did, as a single import does; the rest as it.
            import_again(key, !said);
            said = true;
        } catch (const Error& e) {
            // One unreadable frame does not lose the others: reported, the run exits 1 at the end.
            std::fprintf(stderr, "dynsky: error: %s\n", e.what());
            failed.push_back(photos[i]);
        }
        progress.advance();
    }
    progress.finish();
    // Where a moving sky made from the folder starts (its last sky in time: `animate --sky FOLDER`,
    // `sky predict --sky FOLDER`) the hidden pixels are filled with the sky's own texture, as a single
    // import fills them: the smooth fill of a TSI's shadow band (pale streaks) rode the wind across
    // every predicted step. The others keep the smooth fill, the same from frame to frame.
    if (!o.fill && photos.size() - failed.size() >= 2) {
        std::vector<std::string> written;
        for (size_t i = 0; i < photos.size(); ++i)
            if (!has_failed(i)) written.push_back(outputs[i]);
        const std::string last = skies_in_time_order(written).back();
        const size_t i = size_t(std::find(outputs.begin(), outputs.end(), last) - outputs.begin());
        take(i);
        each.fill = PhotoImportParams::FillMethod::Texture;
        try {
            const std::string key = import_settings_key(each);
            if (!made_with(key)) import_again(key, false);
            std::printf(
                "%s, the sequence's last sky (where a moving sky made from the folder starts), is filled with "
                "the sky's own texture (as --fill texture); the others smoothly\n",
                last.c_str());
        } catch (const Error& e) {
            std::fprintf(stderr, "dynsky: error: %s\n", e.what());
            failed.push_back(photos[i]);
        }
    }
    // What one photograph's calibration cannot know, from the sequence's skies (read from their
    // headers, so a resumed import does it as a whole one does); the skies concerned are imported
    // again with it:
    //  - the clear shares smoothed over time (PhotoImportJob::calibration_window_s): a sky whose own
    //    share would trust its clear pixels otherwise than its neighbours' takes their median;
    //  - the sun track (fit_sun_track): where the photographs show the sun along one turn of the
    //    clock's, the sun of every sky within that stretch of track is put on it (the sun where the
    //    photograph shows it, also where a cloud hides it: the Mobotix's skies flipped 9-38 degrees
    //    between neighbours).
    if (photos.size() >= 3) {
        std::vector<double> seconds(photos.size(), 0.0);
        std::vector<std::optional<double>> own(photos.size()), applied(photos.size());
        std::vector<std::optional<Vec3d>> clock(photos.size()), seen(photos.size()), tracked(photos.size());
        std::vector<bool> imposed_share(photos.size(), false);
        bool timed = true;
        auto share = [](const std::string& text) -> std::optional<double> {
            char* end = nullptr;
            const double v = std::strtod(text.c_str(), &end);
            if (text.empty() || *end || !(v >= 0 && v <= 1)) return std::nullopt;
            return v;
        };
        for (size_t i = 0; i < photos.size(); ++i) {
            if (has_failed(i)) continue;
            try {
                seconds[i] = utc_seconds(planned_times[i]);
            } catch (const Error&) {
                timed = false;  // no times (uncalibrated skies) or one that does not parse: nothing to order
            }
            const std::vector<std::string> h = image_header_strings(outputs[i],
                                                                    {kClearFractionKey, kTrustedClearFractionKey,
                                                                     kSunClockKey, kSunSeenKey, kSunTrackKey});
            own[i] = share(h[0]);
            applied[i] = h[1].empty() ? own[i] : share(h[1]);
            imposed_share[i] = !h[1].empty();
            clock[i] = parse_direction(h[2]), seen[i] = parse_direction(h[3]), tracked[i] = parse_direction(h[4]);
        }
        std::vector<std::optional<double>> smoothed(photos.size());
        if (timed && o.calibration_window_s > 0) smoothed = smooth_over_time(seconds, own, o.calibration_window_s);
        std::vector<Vec3d> clock_seen, seen_suns;
        std::vector<size_t> seen_at;
        for (size_t i = 0; i < photos.size(); ++i)
            if (clock[i] && seen[i])
                clock_seen.push_back(*clock[i]), seen_suns.push_back(*seen[i]), seen_at.push_back(i);
        suns_seen = seen_suns.size();
        std::optional<SunTrack> track = timed ? fit_sun_track(clock_seen, seen_suns) : std::nullopt;
        if (track && track->median_offset_deg < 3) track.reset();  // the clock's sun is where they show it
        // The track holds between the first and the last photograph whose sun is on it, and the turn
        // fades out over kTrackFadeS beyond them (a part of it, by slerp): beyond, nothing shows where
        // the track goes (put on it, the Mobotix's sunrise sun went below the horizon and its skies
        // 2x darker), and a hard end made the sun step 10 degrees between two skies.
        constexpr double kTrackFadeS = 1800;
        double track_from = 0, track_to = 0;
        if (track) {
            bool any = false;
            for (size_t k = 0; k < seen_at.size(); ++k) {
                if (!track->taken[k]) continue;
                const double t = seconds[seen_at[k]];
                track_from = any ? std::min(track_from, t) : t, track_to = any ? std::max(track_to, t) : t, any = true;
            }
        }
        auto turn_share = [&](double t) {
            return std::clamp(1 - std::max(track_from - t, t - track_to) / kTrackFadeS, 0.0, 1.0);
        };
        std::vector<size_t> redo;
        size_t differ = 0, moved = 0;
        std::vector<std::optional<Vec3d>> on_track(photos.size());
        for (size_t i = 0; i < photos.size(); ++i) {
            bool again = false;
            if (smoothed[i] && applied[i]) {
                again = !same_trust(*smoothed[i], *applied[i]);
                if (!same_trust(*smoothed[i], *own[i])) ++differ;
            } else if (imposed_share[i]) {
                again = true;  // a share an earlier run imposed, none now (--calibration-window 0)
            }
            const double share = track ? turn_share(seconds[i]) : 0.0;
            const Eigen::Quaterniond turn = track
                                                ? Eigen::Quaterniond::Identity().slerp(share,
                                                                                       Eigen::Quaterniond(track->turn))
                                                : Eigen::Quaterniond::Identity();
            if (share > 0 && clock[i] && clock[i]->y() > 0 &&
                (turn * *clock[i]).y() > 0.02) {  // the sun up, on the stretch of track seen or its fade
                on_track[i] = (turn * *clock[i]).normalized();
                ++moved;
                if (!tracked[i] || tracked[i]->dot(*on_track[i]) < std::cos(0.5 * kPiD / 180)) again = true;
            } else if (tracked[i]) {
                again = true;  // on a track an earlier run found
            }
            if (again) redo.push_back(i);
        }
        ProgressBar progress_again((long long)redo.size(), "importing " + std::to_string(redo.size()) +
                                                               " skies again with the sequence's calibration");
        for (size_t i : redo) {
            take(i);
            each.fill = o.fill ? o.fill
                        : made_with(key_with_fill(PhotoImportParams::FillMethod::Texture))
                            ? PhotoImportParams::FillMethod::Texture
                            : PhotoImportParams::FillMethod::Smooth;
            each.trusted_clear_fraction = smoothed[i];
            each.sun_in_photo = on_track[i];
            try {
                import_again(import_settings_key(each), false);
            } catch (const Error& e) {
                std::fprintf(stderr, "dynsky: error: %s\n", e.what());
                failed.push_back(photos[i]);
            }
            progress_again.advance();
        }
        progress_again.finish();
        each.trusted_clear_fraction.reset(), each.sun_in_photo.reset();
        if (differ)
            std::printf(
                "calibration: %zu skies whose clear share differed from the photographs' around them (the median "
                "within %g s either side, --calibration-window) are calibrated with that share, as their "
                "neighbours are\n",
                differ, o.calibration_window_s);
        if (track)
            std::printf(
                "sun: %d of the photographs show it %.1f deg (median) from where the clock puts it, along one turn of "
                "%.1f deg of the clock's track (within %.1f deg, median; %d taken): the sun of every sky from the first "
                "to the last of them is put on that track, seen or hidden, the turn fading out over 30 minutes "
                "either side (%zu skies). The camera is not level or not turned as its north says (--tilt, --tilt-azimuth, --north)\n",
                track->seen, track->median_offset_deg, track->turn_deg, track->median_residual_deg, track->used, moved);
    }
    each.far_suns = nullptr;
    if (far_suns.size() == 1) {
        std::fprintf(stderr, "dynsky: warning: %s: %s\n", far_suns.begin()->first.c_str(),
                     far_suns.begin()->second.second.c_str());
    } else if (!far_suns.empty()) {
        double least = 180, most = 0;
        for (const auto& [photo, far] : far_suns) least = std::min(least, far.first), most = std::max(most, far.first);
        // A few among many: the others' suns agree with the clock, so the time, place and north are
        // likely right (an audit's synthetic camera, all three exact, was told to turn its north
        // by 17-32 degrees for 2 of 20 frames whose clipped sun was a sunlit cloud edge).
        const bool few = 4 * far_suns.size() <= suns_seen;
        std::fprintf(stderr,
                     "dynsky: warning: %zu of the %zu photographs show the clipped sun %.1f-%.1f deg from the sun "
                     "computed for their time and place%s; the first, %s: %s\n",
                     far_suns.size(), photos.size(), least, most,
                     few ? " (the others' agree with it: more likely sunlit cloud edges near the sun taken for it "
                           "than a wrong time, place or north)"
                         : "",
                     far_suns.begin()->first.c_str(), far_suns.begin()->second.second.c_str());
    }
    // The previews at one exposure, the median of the calibrated skies' own, each within 2 stops of
    // its own (exposure_median): each at its own hid the sequence's brightness changes (a frame 2x
    // too bright looked like its neighbours), one for all turned noon white beside a night frame.
    // Skies in a photograph's own units (uncalibrated) keep their own: their levels say nothing.
    {
        std::vector<size_t> calibrated;
        std::vector<float> own_ev(photos.size(), 0.0f), evs;
        for (size_t i = 0; i < photos.size(); ++i) {
            if (has_failed(i)) continue;
            try {
                const Image sky = read_image(outputs[i]);
                const auto units = sky.metadata.strings.find("dynsky:units");
                own_ev[i] = exposure_median(sky);
                if (own_ev[i] != 0 && units != sky.metadata.strings.end() && units->second == kAbsoluteRadiance)
                    calibrated.push_back(i), evs.push_back(own_ev[i]);
            } catch (const Error&) {
                // Said by its import; its preview stays as it was.
            }
        }
        if (calibrated.size() >= 2) {
            const float ev = median(evs);
            constexpr float kMaxShiftEv = 2;
            size_t shifted = 0;
            ProgressBar previews((long long)calibrated.size(), "previews at one exposure");
            for (size_t i : calibrated) {
                take(i);
                const float own = own_ev[i], used = std::clamp(ev, own - kMaxShiftEv, own + kMaxShiftEv);
                shifted += used != ev;
                write_image(each.preview, tonemap_to_display(read_image(outputs[i]), used));
                previews.advance();
            }
            previews.finish();
            std::printf(
                "previews: one exposure for the sequence, %+.2f EV (the median of the skies' own, %+.2f to "
                "%+.2f), so its brightness changes show%s\n",
                ev, *std::min_element(evs.begin(), evs.end()), *std::max_element(evs.begin(), evs.end()),
                shifted ? (" (" + std::to_string(shifted) + " kept within 2 stops of their own)").c_str() : "");
        } else {
            std::printf(
                "previews: each at its own exposure (the median luminance; skies in the photographs' own "
                "units)\n");
        }
    }
    std::printf("imported %zu of %zu photographs into %s%s (STEM.exr, STEM.png, STEM.filled.png)%s\n",
                photos.size() - failed.size(), photos.size(), o.out.c_str(), o.out.back() == '/' ? "" : "/",
                kept ? (": " + std::to_string(kept) +
                        " of them kept from an earlier run with the same photographs and "
                        "settings (remove them to import them again)")
                           .c_str()
                     : "");
    // Skies an earlier import left for photographs no longer given: a folder read as a sequence takes
    // them too (`sky predict --sky FOLDER` moved on from one). Said, not removed: they may be wanted.
    std::vector<std::string> others;
    std::set<std::string> ours;
    for (const std::string& f : outputs) ours.insert(fs::path(f).filename().string());
    for (const auto& e : fs::directory_iterator(o.out)) {
        const std::string path = e.path().string(), name = e.path().filename().string();
        if (!e.is_regular_file() || is_hidden_file(path) || file_extension(path) != ".exr" || ours.count(name))
            continue;  // hidden: a temporary a stopped import left, never read as a sky
        if (!image_header_strings(path, {kImportSettingsKey}).front().empty()) others.push_back(name);
    }
    std::sort(others.begin(), others.end(), natural_less);
    if (!others.empty())
        std::fprintf(stderr,
                     "dynsky: warning: %s also holds %zu sk%s an earlier import made from photographs not given this "
                     "time (%s%s): a command that reads the folder as a sequence takes %s too\n",
                     o.out.c_str(), others.size(), others.size() == 1 ? "y" : "ies", others.front().c_str(),
                     others.size() > 1 ? ", ..." : "", others.size() == 1 ? "it" : "them");
    if (!failed.empty())
        throw Error(std::to_string(failed.size()) + " of " + std::to_string(photos.size()) +
                    " photographs not imported (each named above), the first " + failed.front());
}

}  // namespace dynsky
