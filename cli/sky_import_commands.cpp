// dynsky sky import | mask: all-sky photographs into canonical HDR skies, and the cloud mask.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <vector>

#include "cli/commands.h"
#include "cli/options.h"
#include "cli/sky_output.h"
#include "sky/cloud_mask.h"
#include "sky/hdr_recovery.h"
#include "sky/photo_import.h"
#include "sky/preset_import.h"
#include "sky/sky_image.h"
#include "sky/sun_position.h"
#include "util/atomic_file.h"
#include "util/color.h"
#include "util/error.h"
#include "util/image.h"
#include "util/progress.h"

namespace dynsky::cli {

namespace {

struct ImportOptions {
    std::vector<std::string> photos;                      // as given: one photograph, several, or a folder of them
    std::string circle_origin;                            // how the circle given came about ("" : "given")
    std::optional<std::array<int, 2>> circle_photo_size;  // the sequence's photos' size, when its circle is used
    bool find_north = false, flatten_colour = false;
    std::optional<PhotoImportParams::ColourShading> colour_shading;  // a sequence's, measured on it
    std::optional<double> north_found;  // a sequence's north, found from the sun on its photographs
    std::string photo, preset, center, lens, mask, mask_layout = "photo", encoding = "auto";
    double radius = 0, north = 0, tilt = 0, tilt_azimuth = 0;
    bool mirror = false, keep_colours = false, auto_circle = false, no_preset_mask = false, detect = false,
         keep_thin = false, no_inpaint = false;
    std::string time, hdr = "auto", fill = "texture";
    double lat = 0, lon = 0, elevation = 0, utc_offset = 0, turbidity = 3.0;
    int resolution = 512;
    std::string out, preview, filled_mask;
    // Set by CLI11 when given, so presets can be overridden option by option.
    CLI::Option *fill_opt = nullptr, *lens_opt = nullptr, *north_opt = nullptr, *lat_opt = nullptr, *lon_opt = nullptr,
                *elev_opt = nullptr, *offset_opt = nullptr, *tilt_opt = nullptr, *tilt_az_opt = nullptr;
};

struct MaskOptions {
    std::string input, out, rule = "rb", preset, center, mask;
    double threshold = 0.46, radius = 0;
    bool whole_image = false;
};

SkyCircle parse_center(const std::string& text, double radius) {
    double x = 0, y = 0;
    char comma = 0, extra = 0;
    std::istringstream s(text);
    if (!(s >> x >> comma >> y) || comma != ',' || (s >> extra) || !std::isfinite(x) || !std::isfinite(y))
        throw Error("--center '" + text + "': expected X,Y in photo pixels (e.g. --center 243.1,317.5)");
    if (!(radius > 0)) throw Error("--center needs --radius R (pixels from the centre to the horizon)");
    return SkyCircle{x, y, radius};
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

ImportPlan plan_import(const ImportOptions& o, bool verbose) {
    ImportPlan plan;
    PhotoImportParams& params = plan.params;
    check_extension("--out", o.out, ".exr");
    if (!o.preview.empty()) check_extension("--preview", o.preview, ".png");
    if (!o.filled_mask.empty()) check_extension("--filled-mask", o.filled_mask, ".png");
    check_outputs_are_not_inputs({o.out, o.preview, o.filled_mask}, {o.photo, o.mask});
    if (!o.preview.empty() && !o.filled_mask.empty() &&
        std::filesystem::weakly_canonical(o.preview) == std::filesystem::weakly_canonical(o.filled_mask))
        throw Error("--filled-mask " + o.filled_mask + ": the same file as --preview (one would replace the other)");
    if (o.resolution < 16 || o.resolution > 16384)
        throw Error("--res " + std::to_string(o.resolution) + ": the fisheye must be 16..16384 pixels wide");
    if (o.hdr != "auto" && o.hdr != "none" && o.hdr != "calibrated")
        throw Error("--hdr '" + o.hdr + "': use none, calibrated or auto");

    double lat = o.lat, lon = o.lon, elevation = o.elevation, utc_offset = o.utc_offset;
    double& sun_search = plan.sun_search;
    std::optional<CameraColour>& camera_colour = plan.camera_colour;
    bool have_location = o.lat_opt->count() && o.lon_opt->count();
    std::string& obstructions = plan.obstructions;
    if (!o.preset.empty()) {
        // The preset's decisions (sky/preset_import.h), then the options that override them.
        const CameraPreset preset = camera_preset(o.preset);
        if (!o.lat_opt->count()) lat = preset.latitude_deg;
        if (!o.lon_opt->count()) lon = preset.longitude_deg;
        if (!o.elev_opt->count()) elevation = preset.elevation_m;
        if (!o.offset_opt->count()) utc_offset = preset.filename_utc_offset_hours;
        sun_search = preset.sun_search_deg;
        camera_colour = preset.colour;
        have_location = true;
        // The shadow band follows the sun at the time used (given, or the file name's on its clock).
        std::string band_time = o.time.empty() ? photo_time(o.photo, utc_offset).iso : o.time;
        if (o.mask.empty()) {
            PresetImportPlan plan = plan_preset_import(o.preset, o.photo, o.resolution, band_time, !o.no_preset_mask);
            params = plan.params;
            obstructions = plan.obstructions;
        } else {
            params = preset.params;  // a mask given replaces the preset's own obstructions
        }
    }
    params.resolution = o.resolution;
    params.encoding = o.encoding;
    if (!o.center.empty()) params.circle = parse_center(o.center, o.radius);
    else if (o.radius > 0) throw Error("--radius needs --center X,Y as well");
    if (o.circle_photo_size) params.circle_photo_size = o.circle_photo_size, params.circle_source = "the sequence";
    if (o.auto_circle) params.circle.reset();
    if (o.lens_opt->count()) params.lens = parse_lens_law(o.lens);
    if (o.north_opt->count()) params.north_deg = o.north;
    if (o.north_found) params.north_deg = *o.north_found;
    if (o.colour_shading) params.colour_shading = o.colour_shading;
    if (o.mirror) params.mirrored = true;
    if (o.tilt_opt->count()) params.tilt_deg = o.tilt;
    if (o.tilt_az_opt->count()) params.tilt_azimuth_deg = o.tilt_azimuth;
    if (!o.mask.empty()) {
        params.mask_path = o.mask;
        if (o.mask_layout == "photo") params.mask_layout = MaskLayout::PhotoBlackIsNotSky;
        else if (o.mask_layout == "tsi") params.mask_layout = MaskLayout::TsiCloudMask;
        else if (o.mask_layout == "alonso-planar") params.mask_layout = MaskLayout::AlonsoPlanarGreenIsNotSky;
        else throw Error("--mask-layout '" + o.mask_layout + "': use photo, tsi or alonso-planar");
    }
    if (o.detect) params.detect_obstructions = true;
    if (o.keep_thin) params.detect_thin_obstructions = false;
    if (o.no_inpaint) params.inpaint = false;
    params.fill_method = o.fill == "smooth" ? PhotoImportParams::FillMethod::Smooth
                                            : PhotoImportParams::FillMethod::Texture;

    // Time: given, or the photograph's (its file name's, else its EXIF's: sky/photo_import.h
    // photo_time); one without a zone is on a clock --utc-offset hours ahead of UTC, which presets
    // know; without a preset or --utc-offset such a time is not guessed.
    std::string& time = plan.time;
    time = o.time;
    if (time.empty()) {
        const PhotoTime found = photo_time(o.photo, utc_offset);
        time = found.iso;
        if (!time.empty() && !found.zone_in_file && o.preset.empty() && !o.offset_opt->count()) {
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

// One photograph into one sky (o.photo, o.out, o.preview, o.filled_mask); `verbose`: the lines
// saying what was found and done (a sequence's import says it once for all).
void import_one(const ImportOptions& o, bool verbose) {
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
                    imported.display_referred ? "sRGB-encoded, decoded to linear" : "linear, taken as they are",
                    why.c_str());
    if (imported.display_referred && verbose)
        std::printf("saturation: %s\n",
                    imported.clip_level < 1.0
                        ? ("clipped at encoded level " + std::to_string(imported.clip_level)).c_str()
                        : "no clipping plateau found");
    if (obstructions.empty() && !params.mask_path.empty()) obstructions = "mask " + params.mask_path;
    if (verbose)
        std::printf("not-sky pixels filled: %.1f%% of the disc%s%s\n", disc ? 100.0 * filled / disc : 0.0,
                    obstructions.empty() ? "" : (" (" + obstructions + ")").c_str(),
                    params.inpaint ? "" : " (left black: --no-inpaint)");
    if (!o.filled_mask.empty()) {
        // 255 where the import filled the sky in (arm, band, masts, unseen), 0 elsewhere: what
        // evaluations and training leave out.
        Image m(o.resolution, o.resolution, 1);
        for (size_t p = 0; p < imported.not_sky.size(); ++p) m.pixels[p] = imported.not_sky[p] ? 1.0f : 0.0f;
        write_image(o.filled_mask, m);
    }

    SkyImage sky = imported.sky;
    std::string unit = "relative linear units (decoded photo values)";
    if (calibrate) {
        if (!imported.display_referred) {
            if (verbose) std::printf("HDR input: kept at its own scale (no calibration)\n");
        } else {
            HdrCalibrationParams hp;
            hp.time = utc;
            hp.location = where;
            hp.turbidity = o.turbidity;
            hp.sun_search_deg = sun_search;
            hp.camera_colour = camera_colour;
            hp.white_balance = !o.keep_colours;
            HdrCalibrationReport report;
            sky = recover_hdr(imported, hp, &report);
            if (verbose) std::printf("time %s; %s\n", format_utc_time(utc).c_str(), report.summary().c_str());
            if (std::string w = report.sun_offset_warning(); !w.empty())
                std::fprintf(stderr, "dynsky: warning: %s: %s\n", o.photo.c_str(), w.c_str());
            unit = "W m^-2 sr^-1 (calibrated against the clear-sky model)";
        }
    } else {
        if (verbose) std::printf("HDR: none (give --time with --lat/--lon or a --preset for calibrated radiance)\n");
    }
    std::ostringstream source;
    source << sky.source;
    if (!time.empty()) source << " time=" << time;
    sky.source = source.str();
    save_sky(o.out, sky);
    if (verbose) std::printf("wrote %s (%dx%d fisheye, %s)\n", o.out.c_str(), o.resolution, o.resolution, unit.c_str());
    if (!o.preview.empty()) write_preview(o.preview, sky_to_image(sky), verbose);
}

// The image files of a folder, in name order (a sequence's frames are named by their time).
std::vector<std::string> photos_in_folder(const std::string& folder) {
    std::vector<std::string> out;
    for (const auto& e : std::filesystem::directory_iterator(folder)) {
        const std::string path = e.path().string(), ext = file_extension(path);
        if (!e.is_regular_file() || (path.size() >= 11 && path.compare(path.size() - 11, 11, ".filled.png") == 0))
            continue;
        for (const char* known : {".jpg", ".jpeg", ".png", ".tif", ".tiff", ".exr", ".hdr", ".heic", ".heif", ".webp"})
            if (ext == known) out.push_back(path);
    }
    std::sort(out.begin(), out.end());
    if (out.empty())
        throw_file_error(folder,
                         "no photographs in this folder (.jpg, .jpeg, .png, .tif, .tiff, .exr, .hdr, .heic, .webp)");
    return out;
}

void run_import(const ImportOptions& o) {
    namespace fs = std::filesystem;
    const bool sequence = o.photos.size() > 1 || fs::is_directory(o.photos.front());
    if (!sequence) {
        if (o.flatten_colour)
            throw Error(
                "--flatten-colour measures a camera's colour shading on its overcast photographs: give a "
                "sequence (several photographs or a folder)");
        ImportOptions one = o;
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
        throw Error("-o " + o.out + ": with several photographs -o is the folder their skies go to (STEM.exr each)");
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
    std::error_code ec;
    fs::create_directories(o.out, ec);
    if (ec || !fs::is_directory(o.out)) throw_file_error(o.out, "cannot create this output folder: " + ec.message());

    ImportOptions each = o;
    // A sequence's hidden pixels are filled smoothly unless asked otherwise: the texture fill takes
    // seconds a frame and differs from frame to frame.
    if (!o.fill_opt->count()) each.fill = "smooth";
    if (o.center.empty() && (o.preset.empty() || o.auto_circle || !camera_preset(o.preset).params.circle)) {
        PhotoImportParams search = o.preset.empty() ? PhotoImportParams{} : camera_preset(o.preset).params;
        search.encoding = o.encoding;
        const SequenceSkyCircle found = find_sequence_sky_circle(photos, search);
        const SkyCircle& c = found.circle;
        std::printf(
            "sky circle: centre (%.1f, %.1f) px, radius %.1f px, the median of %d of %d photographs spread over the "
            "sequence (each within %.1f px of centre, %.1f px of radius); used for every photograph\n",
            c.center_x, c.center_y, c.radius, found.found, found.tried, found.centre_spread_px, found.radius_spread_px);
        for (const std::string& e : found.not_found) std::fprintf(stderr, "dynsky: warning: %s\n", e.c_str());
        char centre[64];
        std::snprintf(centre, sizeof centre, "%.3f,%.3f", c.center_x, c.center_y);
        each.center = centre;
        each.radius = c.radius;
        each.auto_circle = false;
        each.circle_origin = "the sequence's";
        each.circle_photo_size = found.photo_size;
    }
    if (o.detect && o.preset.empty() && o.mask.empty()) {
        // One obstruction mask for the sequence (sky/photo_import.h find_sequence_obstructions),
        // written beside the skies, used by every import instead of finding them frame by frame.
        PhotoImportParams search;
        search.encoding = o.encoding;
        const SkyCircle circle = parse_center(each.center, each.radius);
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
        const std::string mask_path = (fs::path(o.out) / "obstructions.png").string();
        write_image(mask_path, mask);
        std::printf(
            "obstructions: found once for the sequence, on the 80th percentile of %zu photographs spread over "
            "it: %.1f%% of the sky circle (%s, black = not sky); used for every photograph\n",
            std::min<size_t>(photos.size(), 15), in_circle ? 100.0 * hidden_in_circle / in_circle : 0.0,
            mask_path.c_str());
        each.mask = mask_path;
        each.mask_layout = "photo";
        each.detect = false;
        each.keep_thin = true;  // found on the percentile with the rest
    } else if (o.preset.empty() && o.mask.empty())
        std::printf(
            "note: rooftops, trees and masts at the horizon are left in the skies (thin ones aside): "
            "--detect-obstructions finds them once for the whole sequence\n");
    if (o.flatten_colour) {
        // The camera's colour shading, measured on the sequence's overcast photos and divided out of
        // every one (sky/photo_import.h find_sequence_colour_shading).
        PhotoImportParams probe = o.preset.empty() ? PhotoImportParams{} : camera_preset(o.preset).params;
        probe.encoding = o.encoding;
        if (!each.center.empty()) probe.circle = parse_center(each.center, each.radius);
        if (!each.mask.empty()) probe.mask_path = each.mask, probe.mask_layout = MaskLayout::PhotoBlackIsNotSky;
        if (o.lens_opt->count()) probe.lens = parse_lens_law(o.lens);
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
            ImportOptions probe = each;
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
                tries, o.north_opt->count() ? o.north : 0.0);
        } else {
            const ConsensusNorth north = consensus_north(norths);
            std::printf(
                "north: %.1f deg clockwise from the photos' top, found from the clipped sun on %zu of %d "
                "photographs spread over the sequence (%d within %.1f deg of it); used for every photograph\n",
                north.north_deg, norths.size(), tries, north.near, north.spread_deg);
            each.north_found = north.north_deg;
        }
        each.find_north = false;
    }
    std::vector<std::string> failed;
    ProgressBar progress((long long)photos.size(), "importing " + std::to_string(photos.size()) + " photographs");
    for (size_t i = 0; i < photos.size(); ++i) {
        each.photo = photos[i];
        each.out = outputs[i];
        each.preview = (fs::path(o.out) / (fs::path(photos[i]).stem().string() + ".png")).string();
        each.filled_mask = (fs::path(o.out) / (fs::path(photos[i]).stem().string() + ".filled.png")).string();
        try {
            // The first says what it found and did, as a single import does; the rest as it.
            import_one(each, i == 0);
        } catch (const Error& e) {
            // One unreadable frame does not lose the others: reported, the run exits 1 at the end.
            std::fprintf(stderr, "dynsky: error: %s\n", e.what());
            failed.push_back(photos[i]);
        }
        progress.advance();
    }
    progress.finish();
    std::printf("imported %zu of %zu photographs into %s%s (STEM.exr, STEM.png, STEM.filled.png)\n",
                photos.size() - failed.size(), photos.size(), o.out.c_str(), o.out.back() == '/' ? "" : "/");
    if (!failed.empty())
        throw Error(std::to_string(failed.size()) + " of " + std::to_string(photos.size()) +
                    " photographs not imported (each named above), the first " + failed.front());
}

// Without its mask file, a preset's own obstruction geometry in the photo's grid (as import uses it):
// fixed rectangles, the shadow band at the sun's azimuth for the file name's time, the horizon profile.
std::vector<unsigned char> preset_geometry_not_sky(const std::string& preset, const std::string& photo,
                                                   const SkyCircle& circle, int width, int height) {
    const PresetImportPlan plan = plan_preset_import(preset, photo, 64);
    const PhotoImportParams& p = plan.params;
    PhotoGeometry g;
    g.circle = circle;
    g.lens = p.lens, g.north_deg = p.north_deg, g.mirrored = p.mirrored;
    g.tilt_deg = p.tilt_deg, g.tilt_azimuth_deg = p.tilt_azimuth_deg;
    std::vector<unsigned char> out = horizon_obstruction_mask(p.horizon_obstructions, circle, width, height);
    if (p.shadow_band) {
        const auto band = shadow_band_mask(*p.shadow_band, g, width, height);
        for (size_t k = 0; k < out.size(); ++k) out[k] |= band[k];
    }
    for (const auto& r : p.not_sky_rects)
        for (int y = std::max(0, r[1]); y < std::min(height, r[1] + r[3]); ++y)
            for (int x = std::max(0, r[0]); x < std::min(width, r[0] + r[2]); ++x) out[size_t(y) * width + x] = 1;
    return out;
}

void run_mask(const MaskOptions& o) {
    check_extension("--out", o.out, ".png");
    check_outputs_are_not_inputs({o.out}, {o.input, o.mask});
    CloudMaskParams mp{parse_cloud_rule(o.rule), o.threshold};
    if (!std::isfinite(o.threshold)) throw Error("--threshold must be a finite number");
    Image encoded, mask;
    std::vector<unsigned char> sky;
    if (file_extension(o.input) == ".exr") {
        // A canonical sky (linear radiance): encoded as a camera would, inside the disc.
        SkyImage s = load_sky(o.input);
        encoded = encode_sky_for_mask(s);
        sky.assign(size_t(s.resolution) * s.resolution, 0);
        for (int j = 0; j < s.resolution; ++j)
            for (int i = 0; i < s.resolution; ++i) sky[size_t(j) * s.resolution + i] = s.in_disc(i, j);
    } else {
        Image photo = read_image(o.input);
        apply_orientation(photo);  // as `sky import` turns it
        if (photo.channels < 3) throw_file_error(o.input, "the cloud rule needs an RGB photograph");
        for (float v : photo.pixels)
            if (!std::isfinite(v)) throw_file_error(o.input, "has NaN or infinite pixels");
        encoded = photo;
        sky.assign(size_t(photo.width) * photo.height, 1);
        if (!o.whole_image) {
            SkyCircle c;
            PhotoImportParams pp;
            if (!o.preset.empty()) pp = camera_preset(o.preset).params;
            if (o.center.empty()) check_photo_fits(photo, o.input, pp);  // as `sky import` refuses it
            if (!o.center.empty()) c = parse_center(o.center, o.radius);
            else if (pp.circle) c = *pp.circle;
            else c = find_sky_circle(photo, o.input, pp.min_radius_fraction, pp.max_radius_fraction);
            std::string mask_path = o.mask.empty() && !o.preset.empty() ? find_preset_mask(o.preset, o.input) : o.mask;
            std::vector<unsigned char> not_sky;
            if (!mask_path.empty())
                not_sky = load_not_sky_mask(mask_path, o.mask.empty() ? pp.mask_layout : MaskLayout::PhotoBlackIsNotSky,
                                            photo.width, photo.height);
            else if (!o.preset.empty())
                not_sky = preset_geometry_not_sky(o.preset, o.input, c, photo.width, photo.height);
            for (int y = 0; y < photo.height; ++y)
                for (int x = 0; x < photo.width; ++x) {
                    double dx = x - c.center_x, dy = y - c.center_y;
                    size_t p = size_t(y) * photo.width + x;
                    sky[p] = dx * dx + dy * dy <= c.radius * c.radius && (not_sky.empty() || !not_sky[p]);
                }
        }
    }
    // A black photograph has no colour to judge (0 / 0 in the rule called half of it cloud).
    bool lit = false;
    for (size_t p = 0; p < sky.size() && !lit; ++p)
        if (sky[p])
            for (int c = 0; c < 3 && !lit; ++c) lit = encoded.pixels[p * size_t(encoded.channels) + size_t(c)] > 0;
    if (!lit) throw_file_error(o.input, "the sky it shows is black everywhere: no cloud to find");
    mask = cloud_mask(encoded, mp, &sky);
    long long cloud = 0, total = 0;
    for (size_t p = 0; p < sky.size(); ++p)
        if (sky[p]) {
            ++total;
            cloud += mask.pixels[p] > 0.5f;
        }
    write_image(o.out, mask);
    std::printf(
        "wrote %s (255 cloud, 100 clear, 0 not sky); rule %s %s %.3f; cloud fraction %.1f%% of %lld sky pixels\n",
        o.out.c_str(), cloud_rule_name(mp.rule), mp.rule == CloudRule::RedBlueRatio ? "r/b >" : "(b-r)/(b+r) <",
        mp.threshold, total ? 100.0 * cloud / total : 0.0, total);
}

}  // namespace

void register_sky_import_commands(CLI::App& sky) {
    auto io = std::make_shared<ImportOptions>();
    CLI::App* imp = sky.add_subcommand(
        "import",
        "Import an all-sky photograph (8-bit JPEG/PNG, or HDR .exr/.hdr) into a canonical fisheye sky EXR:\n"
        "find or take the sky circle, undo the lens law, rotation (north), mirroring and tilt, fill the\n"
        "non-sky pixels (masts, shadow band, arm) by inpainting, decode sRGB to linear and, given the time\n"
        "and place, calibrate to absolute radiance against the clear-sky model and restore the clipped sun.\n"
        "A sequence (several photographs or a folder) is imported under one sky circle. See docs/sky-import.md.");
    imp->add_option("photo", io->photos,
                    "The photograph; or several, or a folder of them (one camera's sequence: one sky\n"
                    "circle for all, a sky per photograph in the folder -o)")
        ->required();
    std::string presets;
    for (const auto& n : camera_preset_names()) presets += (presets.empty() ? "" : "|") + n;
    imp->add_option("--preset", io->preset,
                    "Camera preset (" + presets +
                        "): geometry, mask handling, place and file-name clock of the real cameras in ../shared/skies. "
                        "Options given explicitly override it")
        ->check(CLI::IsMember(camera_preset_names()));
    imp->add_option("--center", io->center,
                    "Sky circle centre X,Y in photo pixels (pixel centres at integers); default: found automatically");
    imp->add_option("--radius", io->radius, "Sky circle radius in pixels: distance from the centre to 90 deg off-axis")
        ->check(finite_in(4, 1e6));
    imp->add_flag("--auto-circle", io->auto_circle, "Find the circle automatically even if the preset gives one");
    io->lens_opt = imp->add_option("--lens", io->lens,
                                   "Lens law: equidistant (default), equisolid, orthographic, stereographic")
                       ->check(parsed_by([](const std::string& s) { parse_lens_law(s); }, "LENS"));
    io->north_opt =
        imp->add_option("--north", io->north,
                        "Where north appears in the photo, degrees clockwise from its top (default 0: north up)")
            ->check(finite_in(-360, 360));
    imp->add_flag(
        "--find-north", io->find_north,
        "Find where north is from the sun the photo shows (its clipped blob at the computed sun's height, put\n"
        "at its azimuth; a level camera, time and place needed); for a sequence, one north for all");
    imp->add_flag("--flatten-colour", io->flatten_colour,
                  "A sequence: measure the camera's colour shading (less red or blue towards the horizon) on its\n"
                  "overcast photographs, where every pixel is a grey, and divide it out of every photograph");
    imp->add_flag("--mirror", io->mirror,
                  "The photo is mirror-reversed (east clockwise from north), as mirror imagers (TSI) show the sky "
                  "(arm-tsi sets it already)");
    io->tilt_opt = imp->add_option("--tilt", io->tilt,
                                   "Zenith angle of the camera's optical axis, degrees (default 0: level)")
                       ->check(finite_in(-90, 90));
    io->tilt_az_opt = imp->add_option("--tilt-azimuth", io->tilt_azimuth,
                                      "Azimuth the optical axis leans towards, degrees east of north")
                          ->check(finite_in(-360, 360));
    CLI::Option* mask_opt = imp->add_option(
        "--mask", io->mask, "Non-sky mask image (photo-sized; black = not sky unless --mask-layout says otherwise)");
    imp->add_option(
           "--mask-layout", io->mask_layout,
           "photo (default: photo-sized, black = not sky), tsi (a TSI tsi_cloudmask/ frame: black inside its circle, "
           "extended radially beyond) or alonso-planar (the Mobotix background_mask.png)")
        ->check(CLI::IsMember({"photo", "tsi", "alonso-planar"}))
        ->needs(mask_opt);
    imp->add_flag("--no-preset-mask", io->no_preset_mask,
                  "Do not look for the preset's mask beside the photo: use the preset's obstruction geometry");
    imp->add_flag(
        "--detect-obstructions", io->detect,
        "Also detect large dark obstructions (shadow band, arm, rooftops) and fill them (thin ones are found by\n"
        "default); for a sequence without a preset, found once for all on its photos (obstructions.png)");
    imp->add_flag("--keep-thin-objects", io->keep_thin,
                  "Do not look for thin dark objects (masts, wires, the housing's dark edge inside the circle), which "
                  "are otherwise found and filled on any photograph");
    imp->add_flag("--no-inpaint", io->no_inpaint, "Leave non-sky pixels black instead of filling them");
    io->fill_opt =
        imp->add_option("--fill", io->fill,
                        "How non-sky pixels are filled: texture (default for one photograph: the sky's own clouds and\n"
                        "blue copied in, so a moved sky carries no smooth streak; ~4 s at 512 px) or smooth (Telea\n"
                        "inpainting: fast, the same from frame to frame; the default for a sequence)")
            ->check(CLI::IsMember({"texture", "smooth"}));
    imp->add_option(
           "--encoding", io->encoding,
           "Input values: auto (default: by the file's pixels: 8- and 16-bit files are sRGB unless their header\n"
           "says linear, float files (EXR, HDR, PFM, float TIFF) linear), srgb, linear")
        ->check(CLI::IsMember({"auto", "srgb", "linear"}));
    imp->add_option(
           "--time", io->time,
           "When the photo was taken, ISO 8601 with a zone (2017-05-24T17:00:00Z); default: from the file name, "
           "else its EXIF DateTimeOriginal (docs/sky-import.md lists the names understood)")
        ->check(utc_time());
    io->offset_opt =
        imp->add_option(
               "--utc-offset", io->utc_offset,
               "Hours the camera's clock is ahead of UTC, for times (in the file name or the EXIF) without a zone (default 0; presets know theirs)")
            ->check(finite_in(-24, 24));
    io->lat_opt = imp->add_option("--lat", io->lat, "Latitude of the camera, degrees north")->check(finite_in(-90, 90));
    io->lon_opt = imp->add_option("--lon", io->lon, "Longitude of the camera, degrees EAST (write --lon=-97.485)")
                      ->check(finite_in(-360, 360));
    io->elev_opt = imp->add_option("--elevation", io->elevation, "Height above sea level, metres")
                       ->check(finite_in(-1000, 100000));
    imp->add_option(
        "--hdr", io->hdr,
        "none: linear relative values; calibrated: absolute radiance (W m^-2 sr^-1) from the clear-sky model and "
        "the sun restored; auto (default): calibrated when time and place are known");
    imp->add_flag("--keep-camera-colours", io->keep_colours,
                  "Calibrate one scale for all channels, keeping the camera's colours (default: colours corrected "
                  "to the clear-sky model on the clear sky, clouds kept grey; docs/sky-import.md)");
    imp->add_option("--turbidity", io->turbidity, "Clear-sky model turbidity for the calibration (default 3)")
        ->check(finite_in(1, 10));
    imp->add_option("--sky-res", io->resolution, "Output fisheye size N (N x N pixels), 16..16384")
        ->check(CLI::Range(16, 16384))
        ->capture_default_str();
    add_hidden_alias(imp, "--res", &io->resolution);
    imp->add_option("--out,-o", io->out,
                    "Output sky, .exr; for several photographs a folder (STEM.exr, STEM.png, STEM.filled.png each)")
        ->required();
    imp->add_option("--preview", io->preview, "Also write a tone-mapped .png preview");
    imp->add_option("--filled-mask", io->filled_mask,
                    "Also write the pixels the import filled in (arm, band, masts; 255) as a .png of the sky's size, "
                    "for evaluations and training to leave out");
    imp->callback([io] { run_import(*io); });

    auto mo = std::make_shared<MaskOptions>();
    CLI::App* mask = sky.add_subcommand(
        "mask",
        "Cloud mask of a photograph or a canonical sky (.exr) by the red/blue rule on camera-encoded values,\n"
        "written as a PNG: 255 cloud, 100 clear sky, 0 not sky (the WSISEG coding). The paper's threshold is\n"
        "0.46; on WSISEG's human labels 0.75 agrees far better (docs/sky-import.md).");
    mask->add_option("input", mo->input, "Photograph (JPEG/PNG) or canonical sky (.exr)")->required();
    mask->add_option("--out,-o", mo->out, "Output mask, .png")->required();
    mask->add_option("--threshold", mo->threshold, "Rule threshold (default 0.46, the paper's r/b)")
        ->check(finite_in(-1e6, 1e6));
    mask->add_option("--rule", mo->rule,
                     "rb: cloud if r/b > threshold (default); nbr: cloud if (b-r)/(b+r) < threshold")
        ->check(parsed_by([](const std::string& s) { parse_cloud_rule(s); }, "RULE"));
    mask->add_option("--preset", mo->preset, "Camera preset for the sky circle and non-sky mask (" + presets + ")")
        ->check(CLI::IsMember(camera_preset_names()));
    mask->add_option("--center", mo->center, "Sky circle centre X,Y in pixels (photos only; default: preset or found)");
    mask->add_option("--radius", mo->radius, "Sky circle radius in pixels (with --center)")->check(finite_in(4, 1e6));
    mask->add_option("--mask", mo->mask, "Photo-sized non-sky mask (black = not sky)");
    mask->add_flag("--whole-image", mo->whole_image, "Photos: classify every pixel (no sky circle)");
    mask->callback([mo] { run_mask(*mo); });
}

}  // namespace dynsky::cli
