// Float images and their files (OpenImageIO). Writes are atomic: a temporary file is renamed into
// place only when complete, so an interrupted or failed write never leaves a half-written output.
#pragma once

#include <map>
#include <string>
#include <vector>

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

    Image() = default;
    Image(int w, int h, int c) : width(w), height(h), channels(c), pixels(size_t(w) * h * c, 0.0f) {}
    float& at(int x, int y, int c) { return pixels[(size_t(y) * width + x) * channels + c]; }
    float at(int x, int y, int c) const { return pixels[(size_t(y) * width + x) * channels + c]; }
    bool empty() const { return pixels.empty(); }
    // Index of the channel named `name`, or -1.
    int channel_index(const std::string& name) const;
};

// Reads any format OpenImageIO knows, as float. 8-bit files come back as their encoded values
// in [0, 1] (no sRGB decode here: callers decide). Throws dynsky::Error naming the file.
Image read_image(const std::string& path);

// Writes by extension: .exr (linear float, metadata as header attributes), .png/.jpg (8-bit,
// values taken as already display-encoded in [0, 1]). Atomic (temporary name, then rename).
void write_image(const std::string& path, const Image& image);

// Linear radiance to an 8-bit-ready display image: exposure (2^ev), ACES filmic, sRGB encode.
// The exposure policies (which ev) are util/exposure.h.
Image tonemap_to_display(const Image& linear, float exposure_ev = 0.0f);

// Lower-cased extension with the dot (".exr"), or "" if none.
std::string file_extension(const std::string& path);

}  // namespace dynsky
