// Checks a glTF 2.0 JSON document's types and ranges before tinygltf reads it.
//
// tinygltf reads a value of the wrong JSON type as absent and clamps or wraps some numbers:
// "matrix": ["a", ...] became identity, "mesh": "0" no mesh ("no triangles"), "byteStride": -12
// tightly packed, "scene": -1 scene 0, "version": 2.0 "asset not found". Here every such value is
// named with its path ("nodes[3].matrix[0] is a string, not a number"). What changes the geometry
// or the picture is an error; what dynsky does not use (camera clip planes, aspectRatio: the image
// decides) or can read safely (byteStride 0 as tightly packed) is a warning.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace dynsky {

struct GltfJsonReport {
    std::string error;                  // the first problem that makes the file unreadable; empty if none
    std::vector<std::string> warnings;  // values ignored or read leniently
};

// `root` is the parsed document (the JSON chunk of a .glb); a non-object gives an empty report
// (tinygltf names the syntax error).
GltfJsonReport check_gltf_json(const nlohmann::json& root);

// The JSON document of a .gltf, or the JSON chunk of a .glb (a 12-byte header, then its length,
// "JSON", the text), without its buffers or images: for checks that need no geometry. Nothing
// when it cannot be read or parsed: the loader names what is wrong with it.
std::optional<nlohmann::json> read_gltf_json(const std::string& path);

}  // namespace dynsky
