// Importing an all-sky photograph into the canonical fisheye sky (../shared/CONVENTIONS.md).
//
// A camera's photograph differs from the canonical image in: where its sky circle is (centre and
// radius), its lens law, where north is (rotation), mirroring (mirror imagers such as the Total
// Sky Imager show the sky reversed), optionally a tilt of the optical axis, and which pixels are not
// sky at all (masts, shadow band, camera arm, rooftops). PhotoImportParams holds each of these;
// import_photo() resamples the photograph into the canonical image with cv::remap, fills the
// non-sky pixels with cv::inpaint and decodes 8-bit (display-referred, sRGB) values to linear.
//
// The result is linear but RELATIVE: an 8-bit photograph has lost its exposure, so values are the
// decoded [0, 1] numbers (HDR input keeps its own scale). sky/hdr_recovery.h turns it into
// absolute radiance.
//
// Photo pixel coordinates follow OpenCV: pixel (x, y) has its centre at (x, y), x to the right,
// y down, (0, 0) the top-left pixel's centre.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "sky/sky_image.h"
#include "util/image.h"
#include "util/math.h"

namespace dynsky {

// How a lens maps the angle theta off its axis to the distance from the image centre. Normalised
// here so that r = 1 at theta = 90 degrees: the sky circle's radius is the horizon of a level camera.
//   equidistant    r = theta / (pi/2)             (the canonical image's own law)
//   equisolid      r = sqrt(2) sin(theta / 2)     (equal-area; a convex mirror seen from afar)
//   orthographic   r = sin(theta)
//   stereographic  r = tan(theta / 2)
enum class LensLaw { Equidistant, Equisolid, Orthographic, Stereographic };

LensLaw parse_lens_law(const std::string& name);  // throws dynsky::Error listing the valid names
const char* lens_law_name(LensLaw law);
double lens_radius(LensLaw law, double theta);  // theta in [0, pi/2] (beyond: extrapolated)
double lens_angle(LensLaw law, double r);       // inverse, r >= 0

// The sky circle in a photograph, in pixels: r = 1 of the lens law lies at `radius` from the centre.
struct SkyCircle {
    double center_x = 0, center_y = 0, radius = 0;
};

// Where the sky is in the photo and how the photo is oriented. Directions map to pixels as:
// world direction -> camera frame (undo the tilt) -> angle off the axis theta and camera azimuth phi
// -> r = radius * lens_radius(theta) -> image angle psi measured CLOCKWISE from the photo's top as
// displayed: psi = north_deg - phi (normal camera looking up: east is counter-clockwise from north)
// or psi = north_deg + phi (mirrored) -> (x, y) = centre + r (sin psi, -cos psi).
struct PhotoGeometry {
    SkyCircle circle;
    LensLaw lens = LensLaw::Equidistant;
    double north_deg = 0;         // where north appears, clockwise from the photo's top (0: north up)
    bool mirrored = false;        // true: east is clockwise from north in the photo (mirror imagers)
    double tilt_deg = 0;          // zenith angle of the optical axis (0: level camera)
    double tilt_azimuth_deg = 0;  // azimuth the axis leans towards (only with tilt_deg != 0)

    // Photo pixel of a world direction; false if the direction is outside the lens's 180 deg field.
    bool project(const Vec3d& direction, double* x, double* y) const;
    // World direction of a photo pixel; false outside the sky circle.
    bool unproject(double x, double y, Vec3d* direction) const;
};

// How a non-sky mask file is laid out and coded.
enum class MaskLayout {
    // Same pixel grid as the photograph; black (every channel 0) = not sky, anything else = sky.
    // This is how the TSI's own per-frame masks (tsi_cloudmask/) code "not sky" (palette index 0).
    PhotoBlackIsNotSky,
    // The TSI's own per-frame masks (tsi_cloudmask/): photo-sized, black = not sky (shadow band,
    // arm) inside the mask's own circle (about 81 deg zenith); the TSI leaves everything beyond it
    // black, so there each pixel takes the value found just inside that circle along the same ray.
    TsiCloudMask,
    // The Mobotix background_mask.png of MariusAlonso/Irradiance-forecast-using-Fish-Eye-images:
    // 512 x 512 in that project's "planar" projection (an equidistant fisheye of radius 480 px at
    // (640, 480) projected onto a horizontal plane at height 0.1 of the plane's width); pure green =
    // not sky. Objects that leave the plane's square are extended radially to the horizon.
    AlonsoPlanarGreenIsNotSky,
};

// A TSI's shadow band as the photo shows it: a strip through the sky circle's centre towards the
// sun's azimuth (the imager turns its mirror so the band hides the sun), from start_px along that
// direction (negative: it begins behind the centre) to beyond the rim. Measured on the imager's own
// masks (docs/sky-import.md): the strip's centre line lies within 0.1 deg of the sun's azimuth.
struct ShadowBand {
    double azimuth_deg = 0;     // the sun's at the photo's time (set per photo)
    double half_width_px = 30;  // photo pixels either side of the centre line
    double start_px = -20;      // where the strip begins, along its direction from the circle's centre
    // No time to put it at the sun (a photograph whose name and EXIF give none): its azimuth is
    // found in the photograph (find_shadow_band) and azimuth_deg is not used.
    bool find_in_photo = false;
};

// Where a shadow band of `band`'s shape lies in an encoded photograph (0..1): the world azimuth
// whose strip is darkest and greyest against the strips beside it (two to four times its half
// width away), by the medians of each pixel's brightest channel plus its chroma; searched every
// degree, then refined to 0.1. Pixels in `hidden` (photo-sized 0/1: the arm, the housing) are left
// out. `contrast` = the strip's median over its neighbours'; none when no strip is below
// kShadowBandContrast (nothing band-like). On the shared TSI sets the band's strip is at most 0.76
// of its neighbours, any other strip at least 0.82.
struct ShadowBandFound {
    double azimuth_deg = 0;
    double contrast = 1;
};
constexpr double kShadowBandContrast = 0.8;
std::optional<ShadowBandFound> find_shadow_band(const Image& encoded_photo, const PhotoGeometry& geometry,
                                                const ShadowBand& band, const std::vector<unsigned char>& hidden);

// An obstruction on the horizon (roof, railing, mast) in the photo: from radius_fraction x the sky
// circle's radius outwards, between two image angles (degrees clockwise from the photo's top).
// A list of these is a horizon profile: everything below an object's top is hidden too.
struct HorizonObstruction {
    double from_deg = 0, to_deg = 0;
    double radius_fraction = 1;
};

struct PhotoImportParams {
    int resolution = 512;             // N of the N x N canonical output
    std::optional<SkyCircle> circle;  // none: found automatically (find_sky_circle)
    // The width and height of the photographs `circle` was measured on (a camera preset's), and
    // whose (e.g. "the arm-tsi preset"): a photograph of another size is refused, as another
    // camera's (its sky would be cut from the wrong circle). None: any size.
    std::optional<std::array<int, 2>> circle_photo_size;
    std::string circle_source;
    double min_radius_fraction = 0.30;  // automatic search range for the radius, as fractions of
    double max_radius_fraction = 0.55;  //   the photo's shorter side
    LensLaw lens = LensLaw::Equidistant;
    double north_deg = 0;
    bool mirrored = false;
    double tilt_deg = 0, tilt_azimuth_deg = 0;
    std::string mask_path;  // non-sky mask file ("": none)
    MaskLayout mask_layout = MaskLayout::PhotoBlackIsNotSky;
    int mask_dilate_px = 2;            // grow the mask (photo pixels) to cover object edges
    bool detect_obstructions = false;  // also find large dark obstructions (detect_dark_obstructions)
    // Thin dark objects (masts, wires, the housing's dark edge; detect_thin_dark_structures): found
    // by default, on any camera (nothing found within 60 % of the radius on 100 photographs of
    // another camera: it does not take sky).
    bool detect_thin_obstructions = true;
    // Photo rectangles that are never sky, {x, y, width, height} in pixels (burnt-in captions).
    std::vector<std::array<int, 4>> not_sky_rects;
    std::optional<ShadowBand> shadow_band;                 // also not sky: a band at the sun's azimuth
    std::vector<HorizonObstruction> horizon_obstructions;  // also not sky: a horizon profile
    bool inpaint = true;                                   // fill non-sky pixels (fill_method); else leave 0
    // How: Smooth (default; cv::inpaint, Telea: smooth and the same from frame to frame, for
    // sequences) or Texture (cv::xphoto::inpaint shift-map: the sky's own texture copied in, for
    // one sky that will be moved: a smooth fill of a wide band (the TSI's shadow band) drags the
    // sun's glare along it, and in rollouts that light streak flies across the sky). Texture costs
    // about 1 s at 256 px, 4 s at 512 (computed at most at 512).
    enum class FillMethod { Smooth, Texture } fill_method = FillMethod::Smooth;
    // Input encoding: "auto" (8-bit formats are sRGB-encoded, .exr/.hdr/.pfm are linear), "srgb", "linear".
    std::string encoding = "auto";
    // Saturation: a pixel is "clipped" if its largest channel is within 2/255 of this encoded level.
    // < 0: automatic (the photo's own maximum, if a plateau of pixels sits there; see the docs).
    double clip_level = -1;
    // The camera's colour shading (a lens's IR-cut filter passes less red off-axis): a grey's
    // log(R/G) and log(B/G) against the zenith's, as rg2 r^2 + rg4 r^4 and bg2 r^2 + bg4 r^4 at the
    // canonical radius r (zenith angle / 90 degrees, evaluated at most at max_radius), divided out
    // of the linear sky before its hidden pixels are filled. Saturated pixels keep their colour
    // (none left to correct). None: the camera's colours as they are (presets measure theirs).
    struct ColourShading {
        double rg2 = 0, rg4 = 0, bg2 = 0, bg4 = 0, max_radius = 0.9;
    };
    std::optional<ColourShading> colour_shading;
};

// A photograph after import.
struct ImportedPhoto {
    SkyImage sky;                  // linear, relative to the photo (see the file comment)
    PhotoGeometry geometry;        // the geometry used, with the circle found or given
    bool circle_detected = false;  // true if the circle was found automatically
    std::string circle_caution;    // why that circle may be wrong (find_sky_circle), "" if none
    bool display_referred = true;  // true if the photo was sRGB-decoded (8-bit input)
    float encoding_gamma = 0;      // the power law its values were decoded by (header_gamma); 0: sRGB's
    // A linear value encoded as the photograph's values were (sRGB, or its header's gamma): for the
    // rules judged on encoded values (the cloud rule, the clip level).
    float encoded(float linear) const;
    std::vector<unsigned char> not_sky;  // N*N: 1 where the sky was hidden and has been filled
    std::vector<unsigned char> clipped;  // N*N: 1 where the photo was saturated (LDR input only)
    double clip_level = 1.0;             // encoded level treated as saturation (1: none found)
    int exif_orientation = 1;            // the file's EXIF orientation, applied before anything else
    std::string pixel_type;              // the file's stored pixels ("uint8", "half", ...; "" in memory)
    std::string photo_path;
    // A band with find_in_photo: where it was found (none: not found, dark objects were filled instead).
    std::optional<ShadowBandFound> shadow_band_found;
};

// Whole pipeline from a file, the photograph first turned as its EXIF orientation says viewers show
// it (util/image.h apply_orientation: --center, --north and masks refer to that view). Throws
// dynsky::Error naming the file on unreadable input, NaN/Inf pixels, no detectable sky circle, a
// mask of the wrong size, ...
ImportedPhoto import_photo(const std::string& path, const PhotoImportParams& params);

// The smallest photograph side import_photo_image and find_sky_circle accept, pixels.
constexpr int kMinPhotoSide = 16;

// Throws dynsky::Error naming `name` when a photograph cannot be one of `params`' camera: a side under
// kMinPhotoSide, or another size than the one the preset's sky circle was measured on. Run by
// import_photo_image and by `sky mask`, so both refuse the same photographs.
void check_photo_fits(const Image& photo, const std::string& name, const PhotoImportParams& params);

// Same on an image already in memory (`name` is used in messages and as the sky's source).
// `extra_not_sky`, if given, is a photo-sized 1-channel image, > 0.5 = not sky (added to the mask file).

ImportedPhoto import_photo_image(const Image& photo, const std::string& name, const PhotoImportParams& params,
                                 const Image* extra_not_sky = nullptr);

// Finds the sky circle, radius in [min_fraction, max_fraction] of the photo's shorter side.
// A lens circle on a black surround (fisheye cameras): the outline of every pixel with any light
// (its farthest lit pixel in each of 720 directions), fitted with a circle that leaves out the
// directions off it (captions, dark rooftops, the frame's edge where it cuts the circle); its radius
// may then lie in [min_fraction / 2, 1.4 max_fraction]. Otherwise the strongest circular edge
// (cv::HoughCircles on a contrast-stretched, blurred copy about 400 px wide). `photo` holds
// display-encoded values in [0, 1]. Throws dynsky::Error naming `name` if no circle is found.
// *caution (if given): why the circle found may be wrong, "" when it is the lens's own outline: an
// outline that is an ellipse (the photograph's pixels not square: the largest circle inside it is
// returned), or a frame too dark to show the lens (the circle from the sky's edges lies inside it:
// a dawn Mobotix frame 435-448 px against 489). The import warns with it.
SkyCircle find_sky_circle(const Image& photo, const std::string& name, double min_fraction = 0.30,
                          double max_fraction = 0.55, std::string* caution = nullptr);

// Which photograph is the k-th of `tries` spread evenly over a sequence of `count` (the first and
// the last among them): what the sequence-wide searches below look at.
size_t spread_index(int k, int tries, int count);

// Whether a photograph's values are display-encoded (sRGB) rather than linear. auto goes by what the
// file holds, not its name: integer pixels (8- and 16-bit JPEG, PNG, TIFF: what cameras and editors
// write) are display-encoded unless the header calls them linear (oiio:ColorSpace, as a raw
// converter's linear TIFF may); float pixels (EXR, HDR, PFM, float TIFF) are linear. An image made
// in memory (no file type) goes by the name's extension.
// encoding: "auto", "srgb" or "linear" (PhotoImportParams::encoding).
bool is_display_encoded(const Image& photo, const std::string& path, const std::string& encoding);

// The power law a display-encoded image's header gives (a PNG's gAMA, OpenImageIO's oiio:ColorSpace
// "GammaG": values v mean v^G); nullopt: none (the sRGB curve). With --encoding auto the import
// decodes by it.
std::optional<float> header_gamma(const Image& photo);

// The sky circle of one photograph file as import_photo finds it (turned by its EXIF orientation,
// HDR files tone-mapped first), with params' search range and encoding; *size: the photo's width
// and height as turned.
SkyCircle find_photo_sky_circle(const std::string& path, const PhotoImportParams& params,
                                std::array<int, 2>* size = nullptr, std::string* caution = nullptr);

// One sky circle for a sequence of one camera's photographs, so that frames imported one by one do
// not wobble against each other: found on up to max_photos of them spread evenly over the
// sequence, the median centre and radius. Photos where none is found are listed and skipped;
// throws dynsky::Error when none is found in any, or naming a photo of another size than the others.
struct SequenceSkyCircle {
    SkyCircle circle;
    int tried = 0, found = 0;
    double centre_spread_px = 0, radius_spread_px = 0;  // largest distance of a photo's from the median
    std::vector<std::string> not_found;                 // the errors of the photos without one
    std::vector<std::string> cautions;                  // "PHOTO: why its circle may be wrong" (find_sky_circle)
    std::array<int, 2> photo_size{0, 0};                // width, height of the photographs (as turned)
};
SequenceSkyCircle find_sequence_sky_circle(const std::vector<std::string>& photos, const PhotoImportParams& params,
                                           int max_photos = 25);

// A camera's colour shading (PhotoImportParams::ColourShading) measured on its own sequence: on the
// overcast photos among up to max_photos spread over it (95 % of the seen pixels within half the
// radius cloud by the red/blue rule), every seen pixel is a grey; per 5 % of the radius, the median
// log(R/G) and log(B/G) against the photo's zenith's, medians over the photos, fitted as r^2 and
// r^4 terms. None with fewer than 3 overcast photos (a clear sky's colour does change towards the
// horizon: it cannot be told from shading). params: the sequence's geometry (imported at 128 px).
struct SequenceColourShading {
    PhotoImportParams::ColourShading shading;
    int tried = 0, overcast = 0;
    double rms_fit = 0;  // of the fit against the band medians, in log units
};
std::optional<SequenceColourShading> find_sequence_colour_shading(const std::vector<std::string>& photos,
                                                                  PhotoImportParams params, int max_photos = 25);

// What hides the sky in a sequence of one camera's photographs, found once for all: dark objects
// (detect_dark_obstructions) and thin ones (detect_thin_dark_structures) on the per-pixel 80th
// percentile of up to max_photos photographs spread over the sequence. The sky brightens at some
// time at every pixel (a cloud lit, blue sky, the day brightening), a roof or a mast does not rise
// above it, so every frame leaves out the same pixels and a cloud's shadow in one frame is not
// taken for a roof. What moves (a shadow band following the sun) is not found. Photo-sized, 1 = not
// sky; *percentile_out: the percentile image the objects were found on. Throws naming a photo of
// another size than the first.
std::vector<unsigned char> find_sequence_obstructions(const std::vector<std::string>& photos, const SkyCircle& circle,
                                                      const PhotoImportParams& params, int max_photos = 15,
                                                      Image* percentile_out = nullptr);

// Dark, sky-blocking objects (shadow band, arm, masts) inside the circle: pixels much darker than
// the sky's median brightness, kept in large connected pieces. Returns a photo-sized 0/1 mask.
// A heuristic: deep cloud shadows on dark overcast can be taken for obstructions (see docs).
std::vector<unsigned char> detect_dark_obstructions(const Image& encoded_photo, const SkyCircle& circle,
                                                    double darkness = 0.45);

// Thin dark objects (masts, wires, lightning rods, the housing's dark edge inside the circle):
// pixels whose brightest channel is below `darkness` x that of the sky within about 1.5 % of the
// radius around them (a morphological closing), in long, thin connected pieces. Photo-sized 0/1.
std::vector<unsigned char> detect_thin_dark_structures(const Image& encoded_photo, const SkyCircle& circle,
                                                       double darkness = 0.5);

// The band's and the horizon profile's pixels in the photo's grid as 0/1 (1 = not sky), for the
// photo's circle and orientation (`geometry`).
std::vector<unsigned char> shadow_band_mask(const ShadowBand& band, const PhotoGeometry& geometry, int photo_width,
                                            int photo_height);
std::vector<unsigned char> horizon_obstruction_mask(const std::vector<HorizonObstruction>& profile,
                                                    const SkyCircle& circle, int photo_width, int photo_height);

// Reads a mask file into the photo's grid as 0/1 (1 = not sky). Throws naming the mask file.
std::vector<unsigned char> load_not_sky_mask(const std::string& path, MaskLayout layout, int photo_width,
                                             int photo_height);

// How a camera renders colour, against a grey and the clear-sky model (sky/hdr_recovery.h): a grey
// (a cloud lit by the sun and sky) comes out as `grey` (R, G, B, relative), and the sky's colour
// away from that grey is stretched: log(R/G) and log(B/G), measured from the grey's, are chroma_rg
// and chroma_bg times the clear-sky model's (typical values; fitted per photo when it shows clear sky).
struct CameraColour {
    Color grey = Color(1, 1, 1);
    double chroma_rg = 1, chroma_bg = 1;
};

// Camera presets for the real data sets in ../shared/skies (docs/sky-import.md says how each was
// measured): "arm-tsi" (ARM SGP C1 Total Sky Imager) and "mobotix" (Mobotix, Sophia Antipolis).
// Unknown names throw dynsky::Error listing the valid ones.
struct CameraPreset {
    std::string name;
    PhotoImportParams params;  // geometry and mask handling (resolution left at the default)
    double latitude_deg = 0, longitude_deg = 0, elevation_m = 0;
    // Offset of the file names' clock from UTC, hours (local = UTC + offset). TSI names are UTC.
    double filename_utc_offset_hours = 0;
    double sun_search_deg = 3;  // how far from the computed sun a seen sun may lie (HDR recovery)
    // The camera's own obstructions as geometry, used when its mask file is not beside the photo
    // (plan_preset_import): fixed rectangles (the TSI's camera arm and housing), a shadow band at the
    // sun's azimuth, a horizon profile (the Mobotix's roofs and masts). Derived once from the masks
    // in ../shared/skies (docs/sky-import.md), so no mask file is shipped or needed.
    std::vector<std::array<int, 4>> fixed_not_sky_rects;
    std::optional<ShadowBand> shadow_band;
    std::vector<HorizonObstruction> horizon_obstructions;
    // How the camera renders colour (sky/hdr_recovery.h CameraColour); none: unknown.
    std::optional<CameraColour> colour;
};
CameraPreset camera_preset(const std::string& name);
std::vector<std::string> camera_preset_names();

// For presets: the per-frame or per-camera mask that belongs to `photo_path` in the layout of
// ../shared/skies ("" if none is found): arm-tsi -> ../tsi_cloudmask/tsicldmask_sgpC1_<stamp>.png,
// mobotix -> ../background_mask.png.
std::string find_preset_mask(const std::string& preset, const std::string& photo_path);

// The frame time encoded in a file name, ISO 8601 with an explicit zone, or "" if none is
// recognised. Recognised (the first valid date and time in the name; digits not part of a longer
// run): "YYYYMMDDhhmmssZ" (UTC), "YYYY-MM-DD?hh?mm[?ss]" with any of T _ space between date and
// time and : - _ . within it, then optionally Z or +hh:mm / -hhmm (as given), "YYYYMMDDhhmmss" and
// "YYYYMMDD?hhmmss" / "YYYYMMDD?hhmm" with ? one of T _ -. A time without a zone is on a clock
// utc_offset_hours ahead of UTC (written as "+hh:mm"); *zone_in_name (optional) tells whether the
// name gave the zone.
std::string time_from_file_name(const std::string& path, double utc_offset_hours = 0, bool* zone_in_name = nullptr);

// When a photograph was taken: its file name's time (above), else its EXIF DateTimeOriginal (or
// DateTime) with OffsetTimeOriginal when the camera recorded one, else the clock utc_offset_hours
// ahead of UTC. ISO 8601 with a zone, or "" when neither says.
struct PhotoTime {
    std::string iso;            // "" when none
    bool zone_in_file = false;  // the name or the EXIF gave the zone (else utc_offset_hours was assumed)
    std::string source;         // "file name" or "EXIF"
};
PhotoTime photo_time(const std::string& path, double utc_offset_hours = 0);

}  // namespace dynsky
