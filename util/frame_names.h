// File names of numbered images (glossary): PREFIX_NNNN.EXT with at least four digits, numbered
// from 0; a set of more than 10000 pads every name to its largest number's width, so that names
// sort in order (frame_10000 came between frame_1000 and frame_1001). "frame" for frames of an
// animation or a procedural sequence, "sky" for an animation's sky frames, "flow" for a procedural
// sequence's flow fields, "step" for medium steps of a prediction.
#pragma once

#include <optional>
#include <string>

namespace dynsky {

// "frame", 7, ".exr" -> "frame_0007.exr"; with a folder, the path inside it. `count`: how many the
// set has (0: unknown, four digits); 12000 -> "frame_00007.exr".
std::string numbered_name(const std::string& prefix, int k, const std::string& ext, int count = 0);
std::string numbered_path(const std::string& folder, const std::string& prefix, int k, const std::string& ext,
                          int count = 0);

// The number k of such a name (a file name or path: "frame_0007.exr" -> 7), none for any other.
std::optional<int> numbered_index(const std::string& name, const std::string& prefix);

// The printf pattern of those names ("frame_%04d.png"; "frame_%05d.png" for 12000), for ffmpeg.
std::string numbered_pattern(const std::string& prefix, const std::string& ext, int count = 0);

// Names in the order people number them: runs of digits compared as numbers ("img 9" before
// "img 10", "sky (2)" before "sky (11)"), the rest byte by byte; equal numbers with more leading
// zeros first, so the order is total. For folders of frames whose files say no time.
bool natural_less(const std::string& a, const std::string& b);

}  // namespace dynsky
