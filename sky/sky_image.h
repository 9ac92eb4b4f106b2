// A sky: one canonical fisheye image (sky/fisheye.h) of linear HDR radiance, with its time and sun.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "util/image.h"
#include "util/math.h"

namespace dynsky {

inline constexpr const char* kAbsoluteRadiance = "W m^-2 sr^-1";

// The fisheye sizes N (N x N) every command makes, imports or renders with (`--sky-res`).
inline constexpr int kMinSkyResolution = 16, kMaxSkyResolution = 16384;

// Throws a usage error naming --sky-res unless kMinSkyResolution <= n <= kMaxSkyResolution.
void check_sky_resolution(int n);

struct SkyImage {
    int resolution = 0;                 // N: the image is N x N
    std::vector<float> rgb;             // N * N * 3, row-major, row 0 at the top (north); 0 outside the disc
    double time_seconds = 0.0;          // the sequence's own clock (CONVENTIONS.md, Time)
    bool has_clock = false;             // time_seconds was read from the file (dynsky:time), 0 included
    std::optional<Vec3> sun_direction;  // world frame, unit, if known
    std::string source;                 // what made it ("hosek-wilkie", "photo:FILE", "procedural", ...)
    // kAbsoluteRadiance where what made it says the pixels are W m^-2 sr^-1 (the clear and procedural
    // skies, a calibrated import; "dynsky:units"), else "": units unknown (an HDRI, an uncalibrated
    // photograph), measured against the clear-sky model where it matters (motion/radiance_scale.h).
    std::string units;
    // N * N, 1 where the import filled what the camera could not see (arm, shadow band, masts), as
    // the STEM.filled.png beside the file says (load_sky reads it); empty: every pixel seen. A moving
    // sky neither measures motion nor judges cloud there: a smooth fill through the sun's glare reads
    // as cloud over the sun.
    std::vector<unsigned char> filled;

    SkyImage() = default;
    explicit SkyImage(int n) : resolution(n), rgb(size_t(n) * n * 3, 0.0f) {}

    Color pixel(int i, int j) const {
        const float* p = &rgb[(size_t(j) * resolution + i) * 3];
        return Color(p[0], p[1], p[2]);
    }
    void set_pixel(int i, int j, const Color& c) {
        float* p = &rgb[(size_t(j) * resolution + i) * 3];
        p[0] = c[0], p[1] = c[1], p[2] = c[2];
    }
    bool is_filled(int i, int j) const {
        return filled.size() == size_t(resolution) * resolution && filled[size_t(j) * resolution + i] != 0;
    }
    // True for pixels whose centre lies inside the unit disc (above the horizon).
    bool in_disc(int i, int j) const;
};

// The brightest radiance a sky pixel may hold, W m^-2 sr^-1: the sun's disc is about 2e7, so a
// larger value is a corrupt or mis-scaled file (a 1e35 pixel would swallow all the light and
// render black). docs/input-limits.md.
constexpr double kMaxSkyRadiance = 1e9;
// The least brightest pixel a usable sky has: fainter light underflows single precision between
// the sky and a pixel (a sky of 1e-38 rendered black and exited 0). A night sky is about 1e-6.
constexpr double kMinSkyRadiance = 1e-20;

// Checks a sky is usable as radiance: square, finite, non-negative, at most kMaxSkyRadiance, not
// all black. Throws dynsky::Error starting with `name` (usually the file path).
void validate_sky(const SkyImage& sky, const std::string& name);

// Refuses, naming `path`, an image whose file held integer pixels (8-bit JPEG/PNG, 16-bit PNG:
// display-encoded values, whatever the file's name) where linear radiance is wanted.
void require_radiance_pixels(const Image& image, const std::string& path);

// Where an import writes the filled-pixel mask of the sky file at sky_path: STEM.filled.png beside
// STEM.exr.
std::string filled_mask_path(const std::string& sky_path);

// The filled-pixel mask an import wrote beside a sky file (STEM.filled.png next to STEM.exr), as
// SkyImage::filled for an N x N sky; empty when there is none, or when it is of another size (not
// this sky's: a warning names it).
std::vector<unsigned char> filled_mask_beside(const std::string& sky_path, int n);

// EXR in, validated. A file of integer pixels (8-bit JPEG/PNG, 16-bit PNG: display-encoded values,
// whatever its name) is refused: photographs are made skies by `dynsky sky import`. So is a file
// that does not say it is a dynsky sky (no "dynsky:layout") whose brightest pixel lies outside the
// sky disc (not a fisheye of the upper hemisphere: a lat-long's top half stored square); one whose
// corners hold a mean radiance of more than kMaxLightOutsideDisc of the disc's (and is not uniform)
// is taken with a warning. Reads the "dynsky:time" and "dynsky:sun_*" attributes when present.
inline constexpr double kMaxLightOutsideDisc = 0.05;
SkyImage load_sky(const std::string& path);
// The same for an image already read from `path` (read_radiance_image): one read where the caller
// looked at the image first (sky/latlong.h load_sky_or_latlong). Both read the filled mask beside it.
SkyImage sky_from_radiance_file(const Image& image, const std::string& path);

// EXR out (atomic), with time, sun direction and source as attributes (and `extra`'s). If preview_png
// is non-empty, also writes a tone-mapped PNG there. A STEM.filled.png beside it is removed: it was
// the replaced sky's (an import writes its own after the sky).
void save_sky(const std::string& path, const SkyImage& sky, const std::string& preview_png = "",
              const ImageMetadata& extra = {});

// The UTC time a sky shows, in seconds on one absolute scale (Julian date x 86400), as its source
// records it ("... time=2017-05-24T17:29:30Z ...": `dynsky sky import` and `sky clear` write it);
// nullopt when the source names no time or an unreadable one. Its dynsky:time is the sequence's own
// clock instead (0 for a single import), so two imported photographs are told apart by this.
std::optional<double> sky_recorded_utc_seconds(const SkyImage& sky);

// Sky files (a captured or imported sequence) in the order they were taken, from their headers: by
// their clocks (dynsky:time) when every file has one and they are not all 0, else by the UTC times
// their imports recorded (dynsky:source "time=") when every file has one, else by name. Ties keep
// name order. (By name alone, sky_9.exr came after sky_11.exr and a sequence started from the
// wrong frame.)
std::vector<std::string> skies_in_time_order(std::vector<std::string> files);

// The skies of a captured or imported sequence given as a folder: its sky EXRs in the order they
// were taken (skies_in_time_order; `sky procedural`'s flow_NNNN.exr are motion, not skies). Other
// images in it (a photograph not imported) are warned about, naming the folder; a folder without
// sky EXRs is refused naming it.
std::vector<std::string> sky_sequence_files(const std::string& folder);

// Where a moving sky given a sequence folder starts: its last sky and, when the run takes its motion
// from the sequence (no --prev, no wind given) and it has two, the one before it as the previous
// frame (*previous; left as it is otherwise). Says which, unless `quiet`.
std::string sequence_start(const std::string& folder, bool previous_wanted, std::string* previous, bool quiet);

// A preview or filled mask written beside a sky (STEM.png or STEM.filled.png next to STEM.exr, as
// `sky import` and `sky procedural` write them): part of that sky, not a photograph left out of a
// folder of skies; also the obstruction mask of a folder (kSequenceObstructionsName).
bool written_beside_a_sky(const std::string& path);

// The not-sky mask `sky import --detect-obstructions` writes once into a folder of skies.
inline constexpr const char* kSequenceObstructionsName = "obstructions.png";

// A sky's own metadata in an image header: dynsky:time, dynsky:sun_x/y/z (when known) and
// dynsky:source (when set). Every sky file writer uses it; load_sky reads it back.
void write_sky_metadata(const SkyImage& sky, ImageMetadata* m);
// The sky's time, sun direction and source from an image's dynsky:* attributes (the inverse of
// write_sky_metadata); throws dynsky::Error naming `name` when one is text, not finite, or the sun
// direction is partial or zero.
void read_sky_metadata(const ImageMetadata& metadata, const std::string& name, SkyImage* sky);

// read_image for a file of radiance (a sky, a lat-long environment, an HDR photograph): lossily
// compressed EXRs (DWAA, DWAB, B44) ring slightly below zero next to bright pixels (-5e-6 beside a
// clear sky's 0.1, more beside the sun), so values below zero by at most 1e-3 of the image's
// largest finite value read as 0. Larger negatives stay (validation refuses them). An image of
// more than 3 channels, or of 3 named ones, comes back as its R, G and B (rgb_channel_indices).
Image read_radiance_image(const std::string& path);

// An image read from `path` in the primaries its header names (util/colour_space.h file_primaries:
// an EXR's chromaticities, the ACES container's AP0, an ACEScg oiio:ColorSpace) converted to linear
// Rec.709, its first three channels, colours beyond Rec.709's gamut clipped to it, with a note on
// stderr; the header's colour space is then forgotten (what is written from it is Rec.709).
// read_radiance_image does this.
void convert_to_rec709(Image* image, const std::string& path);

// An image whose header carries an ICC profile other than sRGB's (a camera's Adobe RGB, Display
// P3): a warning on stderr that it is not applied (its values are taken as sRGB's, as every
// integer image's are). read_radiance_image does this.
void warn_of_unapplied_profile(const Image& image, const std::string& path);
// Throws naming the file when it is a JPEG (by its first bytes, whatever its name): 8-bit display
// values, never radiance. Called before any decoder reads a file that must hold radiance.
void refuse_jpeg_as_radiance(const std::string& path);
// A sky file (a fisheye or a lat-long): a JPEG refused, read_radiance_image, and turned the right way
// up when stored turned (an Orientation attribute; a "+Y" .hdr is bottom-up: north and south, or sky
// and ground, were swapped).
Image read_sky_file(const std::string& path);

// The R, G and B channels of a radiance image (3 channels or more) by name, any case: R, G, B; else
// one layer's LAYER.R, .G, .B (a render's AOV layers beside its RGB are ignored); a file without
// names gives its first three. Throws naming the file when they are not there (X Y Z, Y BY RY) or
// in more than one layer.
std::array<int, 3> rgb_channel_indices(const Image& image, const std::string& name);

// Conversions between SkyImage and the generic Image (3 channels).
Image sky_to_image(const SkyImage& sky);
SkyImage sky_from_image(const Image& image, const std::string& name);

// The sky at resolution n (its metadata kept): bilinear up, area-averaged down, the disc's rim
// extended outwards first so that neither darkens it; 0 outside the disc.
SkyImage resampled_sky(const SkyImage& sky, int n);

// Sets every pixel outside the disc to zero (they hold no sky).
void clear_outside_disc(SkyImage* sky);

// The illuminance the sky gives a horizontal plane, lx: 683 x the integral of luminance x cos(zenith)
// over the disc's solid angle.
double horizontal_illuminance(const SkyImage& sky);

}  // namespace dynsky
