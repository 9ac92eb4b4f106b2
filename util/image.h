// Float images and their files (OpenImageIO). Writes are atomic: a temporary file is renamed into
// place only when complete, so an interrupted or failed write never leaves a half-written output.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "util/colour_space.h"

namespace dynsky {

// Metadata carried in EXR headers (and PNG text chunks): numbers and strings by name.
struct ImageMetadata {
    std::map<std::string, double> numbers;
    std::map<std::string, std::string> strings;
};

struct Image {
    int width = 0, height = 0, channels = 0;
    std::vector<float> pixels;  // row-major, row 0 at the top, channels interleaved
    ImageMetadata metadata;
    // Names of the channels in an EXR ("R", "G", "B", "A", "Normal.X", ...; OpenEXR's layer.channel
    // convention); empty: the writer's defaults (R, G, B, A for up to four channels).
    std::vector<std::string> channel_names;
    // For images read from a file: OpenImageIO's name of its format ("openexr", "png", "jpeg") and
    // of its stored pixel type ("uint8", "uint16", "half", "float"); empty for images made here.
    std::string file_format, file_pixel_type;
    // Where the pixels lie in a larger image: an EXR's data window at (origin_x, origin_y) in a
    // display window of full_width x full_height at (0, 0). A render region is written so, as
    // pbrt and Cycles write crops, and compositors put it in its place. full_width 0: the pixels
    // are the whole image. Only EXR keeps it.
    int origin_x = 0, origin_y = 0, full_width = 0, full_height = 0;
    // For images read from a file: the primaries its header gives (an EXR's `chromaticities`);
    // nullopt: none given. util/colour_space.h says what dynsky makes of them.
    std::optional<Chromaticities> chromaticities;

    Image() = default;
    // Read from a file of floating-point pixels (EXR, HDR, PFM, float TIFF: linear light), by
    // file_pixel_type; false for integer files and for images made here.
    bool has_float_file_pixels() const {
        return file_pixel_type == "half" || file_pixel_type == "float" || file_pixel_type == "double";
    }
    Image(int w, int h, int c) : width(w), height(h), channels(c), pixels(size_t(w) * h * c, 0.0f) {}
    float& at(int x, int y, int c) { return pixels[(size_t(y) * width + x) * channels + c]; }
    float at(int x, int y, int c) const { return pixels[(size_t(y) * width + x) * channels + c]; }
    bool empty() const { return pixels.empty(); }
    // Index of the channel named `name`, or -1.
    int channel_index(const std::string& name) const;
};

// The largest image read from a file (docs/input-limits.md): checked on the header, before any
// pixel is allocated, so a hostile or corrupt header cannot exhaust memory.
constexpr long long kMaxImageSide = 16384;        // pixels, each of width and height
constexpr long long kMaxImagePixels = 1LL << 28;  // width * height (16384 x 16384)
constexpr long long kMaxImageValues = 1LL << 29;  // width * height * channels (2 GiB as float)
constexpr long long kMaxImageChannels = 64;

// What is wrong with an image of this size (from a header): "" when it is within the limits.
std::string image_size_problem(long long width, long long height, long long channels);
// Throws dynsky::Error "NAME: PROBLEM" when image_size_problem finds one.
void check_image_size(const std::string& name, long long width, long long height, long long channels);

// Why the file cannot be read as an image, from the checks made before any decoder opens it ("" when
// none): missing, a directory, not a regular file, a PNG cut short (its chunks end before IEND).
std::string image_file_problem(const std::string& path);

// Whether the file starts as a JPEG does (FF D8 FF), whatever its name.
bool has_jpeg_signature(const std::string& path);

// Reads any format OpenImageIO knows, as float. 8-bit files come back as their encoded values
// in [0, 1] (no sRGB decode here: callers decide). Throws dynsky::Error naming the file for a
// missing file, one that is not a regular file, a header beyond the limits above, a file of
// several parts (multi-part EXR, multi-page TIFF: which one would be meant?) and a truncated or
// corrupt file (including a JPEG cut short, which its decoder would silently fill with grey).
// A file whose pixels are only part of its image (an EXR data window other than its display
// window) is refused as ambiguous, unless `part` is DataWindow::PartAllowed and they lie inside
// it (a render region): then the pixels are read with their place (Image::origin_x, full_width).
enum class DataWindow { Whole, PartAllowed };
Image read_image(const std::string& path, DataWindow part = DataWindow::Whole);

// Turns and mirrors an image as its EXIF orientation (metadata "Orientation", 1-8) says viewers
// show it (OpenImageIO's reorient), so a photograph's pixel positions and "up" are the ones its
// user sees; the tag is then 1. Returns the orientation found: 1 (or absent, or not 1-8) changes
// nothing.
int apply_orientation(Image& image);

// String attributes of an image file's header (OpenImageIO's names: "Exif:DateTimeOriginal",
// "DateTime", ...), read in one opening without decoding pixels; "" for each the file lacks, all ""
// when it cannot be opened.
std::vector<std::string> image_header_strings(const std::string& path, const std::vector<std::string>& names);
// A number attribute of an image's header (read without its pixels); nullopt when the file cannot be
// read or has no such number.
std::optional<double> image_header_number(const std::string& path, const std::string& name);

// The index (in Image::pixels) of the first value that is NaN or infinite, or -1 when there is
// none: what a renderer wrote is finite everywhere, so such a frame was damaged since.
long first_non_finite(const Image& image);
// Work a resumed run keeps: every file decodes to its end with finite values (a file cut short, a
// folder half copied: false), and the first one's header holds `key` under `key_name` (the hash of
// the settings that made it). A sequence import's skies and a procedural sequence's frames.
bool made_earlier_with(const std::vector<std::string>& files, const std::string& key_name, const std::string& key);
// "pixel (x, y) is NaN" (or "is infinite") for the value first_non_finite found at index i.
std::string non_finite_pixel_text(const Image& image, long i);
// True when every value is zero: a render that saw nothing lit (the camera inside closed
// geometry, looking away from everything): written, but worth a warning.
bool is_black_everywhere(const Image& image);
// The warning render, animate and compare give for such an image.
inline constexpr const char* kBlackRenderHint =
    "is black everywhere: is the camera inside closed geometry or looking at nothing lit? (--look-at, --camera)";

// Writes by extension: .exr (linear float, metadata as header attributes), .png/.jpg (8-bit,
// values taken as already display-encoded in [0, 1]). Atomic (temporary name, then rename).
void write_image(const std::string& path, const Image& image);
// The bytes write_image would write to `path` (its format from the extension), for writers that
// write several files together (util/atomic_file.h write_files_atomic).
std::string encode_image(const std::string& path, const Image& image);

// Linear radiance to an 8-bit-ready display image: exposure (2^ev), ACES filmic, sRGB encode.
// The exposure policies (which ev) are util/exposure.h.
Image tonemap_to_display(const Image& linear, float exposure_ev = 0.0f);
// The same for a colour premultiplied by `alpha` (1 channel, the same size; a render's alpha pass):
// RGBA, the colour divided by alpha before the tone curve (straight alpha, as PNG and viewers
// take it), 0 where alpha is 0.
Image tonemap_to_display(const Image& premultiplied, const Image& alpha, float exposure_ev);

// Lower-cased extension with the dot (".exr"), or "" if none.
std::string file_extension(const std::string& path);

// A dot-file (.DS_Store, the ._NAME.jpg resource forks macOS leaves on shared drives, editors'
// lock files): never one of a folder's photographs or skies.
bool is_hidden_file(const std::string& path);

// Throws naming path unless it ends in ext (".exr", ".png"); option names the flag in the message,
// which starts with it (a usage error, exit 2: docs/exit-codes.md).
void check_extension(const std::string& option, const std::string& path, const std::string& ext);

}  // namespace dynsky
