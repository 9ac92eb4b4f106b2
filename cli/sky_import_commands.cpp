// dynsky sky import | mask: options of the photo import and cloud mask jobs (sky/photo_import_job.h,
// sky/cloud_mask_job.h).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <sstream>
#include <vector>

#include "cli/commands.h"
#include "cli/options.h"
#include "sky/cloud_mask_job.h"
#include "sky/sky_image.h"
#include "sky/photo_import.h"
#include "sky/photo_import_job.h"
#include "util/error.h"

namespace dynsky::cli {

namespace {

// The options as given (sky/photo_import_job.h PhotoImportJob is what they mean).
struct ImportOptions {
    std::vector<std::string> photos;  // as given: one photograph, several, or a folder of them
    bool find_north = false, flatten_colour = false;
    std::string preset, center, lens, mask, mask_layout = "photo", encoding = "auto";
    double radius = 0, north = 0, tilt = 0, tilt_azimuth = 0;
    bool mirror = false, keep_colours = false, auto_circle = false, no_preset_mask = false, detect = false,
         keep_thin = false, no_inpaint = false;
    std::string time, hdr = "auto", fill = "texture";
    double lat = 0, lon = 0, elevation = 0, utc_offset = 0, turbidity = 3.0, calibration_window = 150;
    int resolution = 512;
    std::string out, preview, filled_mask;
    // Set by CLI11 when given, so presets can be overridden option by option.
    CLI::Option *fill_opt = nullptr, *lens_opt = nullptr, *north_opt = nullptr, *lat_opt = nullptr, *lon_opt = nullptr,
                *elev_opt = nullptr, *offset_opt = nullptr, *tilt_opt = nullptr, *tilt_az_opt = nullptr;
};

struct MaskOptions {
    std::string input, out, rule = "rb", preset, center, mask;
    std::optional<double> threshold;  // none: the rule's boundary at WSISEG's best r / b (0.75)
    double radius = 0;
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

// The job from what was given: options given explicitly override a preset's (CLI11 counts them).
PhotoImportJob import_job(const ImportOptions& o) {
    PhotoImportJob job;
    job.photos = o.photos;
    job.preset = o.preset;
    if (!o.center.empty()) job.circle = parse_center(o.center, o.radius);
    else if (o.radius > 0) throw Error("--radius needs --center X,Y as well");
    job.auto_circle = o.auto_circle;
    if (o.lens_opt->count()) job.lens = parse_lens_law(o.lens);
    if (o.north_opt->count()) job.north_deg = o.north;
    if (o.tilt_opt->count()) job.tilt_deg = o.tilt;
    if (o.tilt_az_opt->count()) job.tilt_azimuth_deg = o.tilt_azimuth;
    job.mirror = o.mirror, job.find_north = o.find_north, job.flatten_colour = o.flatten_colour;
    job.mask = o.mask;
    if (o.mask_layout == "photo") job.mask_layout = MaskLayout::PhotoBlackIsNotSky;
    else if (o.mask_layout == "tsi") job.mask_layout = MaskLayout::TsiCloudMask;
    else if (o.mask_layout == "alonso-planar") job.mask_layout = MaskLayout::AlonsoPlanarGreenIsNotSky;
    else throw Error("--mask-layout '" + o.mask_layout + "': use photo, tsi or alonso-planar");
    job.no_preset_mask = o.no_preset_mask, job.detect_obstructions = o.detect, job.keep_thin_objects = o.keep_thin;
    job.no_inpaint = o.no_inpaint;
    if (o.fill_opt->count())
        job.fill = o.fill == "smooth" ? PhotoImportParams::FillMethod::Smooth : PhotoImportParams::FillMethod::Texture;
    job.encoding = o.encoding;
    job.time = o.time;
    if (o.offset_opt->count()) job.utc_offset_hours = o.utc_offset;
    if (o.lat_opt->count()) job.latitude_deg = o.lat;
    if (o.lon_opt->count()) job.longitude_deg = o.lon;
    if (o.elev_opt->count()) job.elevation_m = o.elevation;
    job.hdr = o.hdr, job.keep_colours = o.keep_colours, job.turbidity = o.turbidity;
    job.calibration_window_s = o.calibration_window;
    job.resolution = o.resolution;
    job.out = o.out, job.preview = o.preview, job.filled_mask = o.filled_mask;
    return job;
}

CloudMaskJob mask_job(const MaskOptions& o) {
    CloudMaskJob job;
    job.input = o.input, job.out = o.out, job.preset = o.preset, job.mask = o.mask;
    const CloudRule rule = parse_cloud_rule(o.rule);
    // The default is the one the rest of dynsky masks with (imports, training data): r / b = 0.75,
    // or the same boundary in the normalised form. The paper's 0.46 called a clear model sky cloud
    // everywhere.
    const double k = kWsisegBestRedBlueThreshold;
    job.params = CloudMaskParams{rule, o.threshold.value_or(rule == CloudRule::RedBlueRatio ? k : (1 - k) / (1 + k))};
    if (!o.center.empty()) job.circle = parse_center(o.center, o.radius);
    else if (o.radius > 0) throw Error("--radius needs --center X,Y as well");  // as `sky import` (it was ignored)
    if (o.whole_image && (!o.preset.empty() || job.circle || !o.mask.empty()))
        throw Error(std::string("--whole-image classifies every pixel: it leaves no room for ") +
                    (!o.preset.empty() ? "--preset (its sky circle and what hides the sky)"
                     : job.circle      ? "--center/--radius"
                                       : "--mask"));
    job.whole_image = o.whole_image;
    return job;
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
    CLI::Option* no_inpaint = imp->add_flag("--no-inpaint", io->no_inpaint,
                                            "Leave non-sky pixels black instead of filling them");
    io->fill_opt =
        imp->add_option("--fill", io->fill,
                        "How non-sky pixels are filled: texture (default for one photograph: the sky's own clouds and\n"
                        "blue copied in, so a moved sky carries no smooth streak; ~4 s at 512 px) or smooth (Telea\n"
                        "inpainting: fast, the same from frame to frame; the default for a sequence)")
            ->check(CLI::IsMember({"texture", "smooth"}))
            ->excludes(no_inpaint);  // how to fill, and not to fill: refused, not one silently dropped
    imp->add_option(
           "--encoding", io->encoding,
           "Input values: auto (default: by the file's pixels: 8- and 16-bit files are sRGB unless their header\n"
           "says linear or gives a gamma (a PNG's gAMA), float files (EXR, HDR, PFM, float TIFF) linear, in the\n"
           "primaries their header names, e.g. ACEScg, converted to Rec.709), srgb, linear")
        ->check(CLI::IsMember({"auto", "srgb", "linear"}));
    imp->add_option(
           "--time", io->time,
           "When the photo was taken, ISO 8601 with a zone (2017-05-24T17:00:00Z); default: from the file name, "
           "else its EXIF DateTimeOriginal (docs/sky-import.md lists the names understood). One photograph only: "
           "a sequence takes each photograph's own")
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
    imp->add_option("--calibration-window", io->calibration_window,
                    "Several photographs: how far each sky's calibration uses the scale and colour fitted on its "
                    "clear pixels follows the median clear share of the photographs within this many seconds either "
                    "side (and of the two nearest each side within twice it), so a frame whose clear share "
                    "spikes is calibrated as its neighbours are; 0: each photograph by its own share")
        ->check(finite_in(0, 86400))
        ->capture_default_str();
    imp->add_option("--sky-res", io->resolution, "Output fisheye size N (N x N pixels), 16..16384")
        ->check(CLI::Range(kMinSkyResolution, kMaxSkyResolution))
        ->capture_default_str();
    imp->add_option("--out,-o", io->out,
                    "Output sky, .exr; for several photographs a folder (STEM.exr, STEM.png, STEM.filled.png each)")
        ->required();
    imp->add_option("--preview", io->preview, "Also write a tone-mapped .png preview");
    imp->add_option("--filled-mask", io->filled_mask,
                    "Also write the pixels the import filled in (arm, band, masts; 255) as a .png of the sky's size, "
                    "for evaluations and training to leave out");
    imp->callback([io] { run_photo_import(import_job(*io)); });

    auto mo = std::make_shared<MaskOptions>();
    CLI::App* mask = sky.add_subcommand(
        "mask",
        "Cloud mask of a photograph or a canonical sky (.exr) by the red/blue rule on camera-encoded values,\n"
        "written as a PNG: 255 cloud, 100 clear sky, 0 not sky (the WSISEG coding). Default r/b > 0.75: on\n"
        "WSISEG's human labels it agrees far better than the paper's 0.46 (docs/sky-import.md).");
    mask->add_option("input", mo->input,
                     "Photograph (JPEG/PNG) or canonical sky (.exr: encoded as a camera would, its 99th-percentile\n"
                     "luminance at white, so a cloudless sky's bright sun side can read as cloud: 27 % of a clear\n"
                     "morning sky)")
        ->required();
    mask->add_option("--out,-o", mo->out, "Output mask, .png")->required();
    mask->add_option("--cloud-threshold", mo->threshold,
                     "Rule threshold (default: rb 0.75, WSISEG's best, as imports and training data use; nbr the\n"
                     "same boundary, 0.143; the paper's r/b was 0.46)")
        ->check(finite_in(-1000, 1000));
    mask->add_option("--cloud-rule", mo->rule,
                     "rb: cloud if r/b > threshold (default); nbr: cloud if (b-r)/(b+r) < threshold")
        ->check(parsed_by([](const std::string& s) { parse_cloud_rule(s); }, "RULE"));
    mask->add_option("--preset", mo->preset, "Camera preset for the sky circle and non-sky mask (" + presets + ")")
        ->check(CLI::IsMember(camera_preset_names()));
    mask->add_option("--center", mo->center, "Sky circle centre X,Y in pixels (photos only; default: preset or found)");
    mask->add_option("--radius", mo->radius, "Sky circle radius in pixels (with --center)")->check(finite_in(4, 1e6));
    mask->add_option("--mask", mo->mask, "Photo-sized non-sky mask (black = not sky)");
    mask->add_flag("--whole-image", mo->whole_image, "Photos: classify every pixel (no sky circle)");
    mask->callback([mo] { run_cloud_mask(mask_job(*mo)); });
}

}  // namespace dynsky::cli
