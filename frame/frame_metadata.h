// What a rendered frame records about itself (glossary: "frame metadata"), stored as dynsky:*
// attributes of its EXR header (util/image.h ImageMetadata), so a frame file says how it was made.
// Only what follows from the settings: no timings (they are in timings*.csv), so a frame's file is
// the same bytes wherever and whenever it is rendered (docs/render-farm.md).
#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "util/image.h"

namespace dynsky {

// The settings a frame's pixels depend on (glossary: "frame settings"), by name: scene, sky (input
// files by name, size and content hash), step model, fps, spp, size, seed, exposure, ... Stored in
// each frame (dynsky:settings, with its hash dynsky:settings_hash); resume keeps a frame only when
// they equal this run's. Settings that do not change frame k (duration, --frames, threads, --out)
// are not in it.
using FrameSettings = std::map<std::string, std::string>;

// "key=value" lines in key order: the canonical form that is stored and hashed.
std::string canonical_settings(const FrameSettings& settings);
FrameSettings parse_settings(const std::string& canonical);
// FNV-1a 64 of the canonical form, 16 hex digits.
std::string settings_hash(const std::string& canonical);
// The settings that differ, "spp 2 -> 4, res 64x36 -> 32x18" (at most `limit` named).
std::string describe_settings_change(const FrameSettings& before, const FrameSettings& now, int limit = 4);

// An input as it enters the settings: a file as "NAME (BYTES bytes, fnv1a HASH)" so a changed or
// replaced file counts and a moved one does not; a folder as the list of its files so; anything
// else (builtin, procedural:3, clear) as written.
std::string describe_input(const std::string& input);
// A scene as it enters the settings: a .gltf with the buffers and images its JSON names (a key moved
// in Blender and exported again changes only the .bin: its frames were kept); anything else as
// describe_input.
std::string describe_scene_input(const std::string& scene);

struct FrameMetadata {
    int frame = 0;            // k, from 0
    double time_seconds = 0;  // t = k / fps, sky time since t = 0  (dynsky:time)
    double fps = 0;
    int spp = 0;
    uint64_t seed = 0;
    // No timings: a frame file depends only on its settings, so a resumed frame is byte for byte
    // the one an uninterrupted run writes. Per-frame times go to timings.csv beside the frames.
    double medium_step_seconds = 0;  // Delta t
    double png_exposure_ev = 0;
    std::string sky, sky_model, scene, camera;
    std::string units;     // the sky's (dynsky:units); empty: relative
    std::string gamma;     // the in-between: constant | paper (dynsky:gamma)
    std::string settings;  // canonical_settings of the run (dynsky:settings, dynsky:settings_hash)
    // The EXR's DateTime ("YYYY:MM:DD HH:MM:SS"): the UTC moment the frame shows when its sky follows
    // a clock, else EXIF's "unknown" (blanks and colons). Always set: OpenImageIO would otherwise
    // stamp the time of writing, and the file would differ from run to run.
    std::string date_time;

    void write_to(ImageMetadata* m) const;
};

}  // namespace dynsky
