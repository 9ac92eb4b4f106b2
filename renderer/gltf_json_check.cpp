#include "renderer/gltf_json_check.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "util/parse.h"

namespace dynsky {
namespace {

using Json = nlohmann::json;

constexpr double kMaxInteger = 9007199254740992.0;  // 2^53: every JSON integer a double holds exactly

std::string describe(const Json& v) {
    switch (v.type()) {
        case Json::value_t::string: {
            std::string s = v.get<std::string>();
            return "the string \"" + (s.size() > 40 ? s.substr(0, 40) + "..." : s) + "\"";
        }
        case Json::value_t::object: return "an object";
        case Json::value_t::array: return "an array";
        case Json::value_t::null: return "null";
        case Json::value_t::boolean: return v.get<bool>() ? "true" : "false";
        default: return number_text(v.get<double>());
    }
}

class Checker {
  public:
    GltfJsonReport report;

    void run(const Json& root) {
        if (const Json* asset = object_member(root, "asset", "asset"))
            if (asset->contains("version") && !(*asset)["version"].is_string())
                error("asset.version is " + describe((*asset)["version"]) + ", not a string such as \"2.0\"");
        index(root, "scene", "scene");
        for_each_object(root, "scenes", [&](const Json& s, const std::string& at) { indices(s, "nodes", at); });
        for_each_object(root, "nodes", [&](const Json& n, const std::string& at) { node(n, at); });
        for_each_object(root, "meshes", [&](const Json& m, const std::string& at) {
            for_each_object(
                m, "primitives",
                [&](const Json& p, const std::string& pat) {
                    index(p, "indices", pat + ".indices");
                    index(p, "material", pat + ".material");
                    integer(p, "mode", pat + ".mode", 0, 6);
                    if (const Json* attributes = object_member(p, "attributes", pat + ".attributes"))
                        for (auto it = attributes->begin(); it != attributes->end(); ++it)
                            index(*attributes, it.key(), pat + ".attributes." + it.key());
                },
                at);
        });
        for_each_object(root, "accessors", [&](const Json& a, const std::string& at) {
            index(a, "bufferView", at + ".bufferView");
            integer(a, "byteOffset", at + ".byteOffset", 0);
            integer(a, "count", at + ".count", 1);
            if (const Json* sparse = object_member(a, "sparse", at + ".sparse")) {  // tinygltf reads it as int
                integer(*sparse, "count", at + ".sparse.count", 1, 2147483647.0);
                for (const char* part : {"indices", "values"})
                    if (const Json* p = object_member(*sparse, part, at + ".sparse." + part)) {
                        index(*p, "bufferView", at + ".sparse." + part + ".bufferView");
                        integer(*p, "byteOffset", at + ".sparse." + part + ".byteOffset", 0, 2147483647.0);
                    }
            }
            integer(a, "componentType", at + ".componentType", 0);
            boolean(a, "normalized", at + ".normalized");
            numbers(a, "min", at + ".min", 0);
            numbers(a, "max", at + ".max", 0);
        });
        for_each_object(root, "bufferViews", [&](const Json& v, const std::string& at) {
            index(v, "buffer", at + ".buffer");
            integer(v, "byteOffset", at + ".byteOffset", 0);
            integer(v, "byteLength", at + ".byteLength", 1);
            // glTF's minimum is 4; 0 is what some writers put for "tightly packed", and is read so.
            if (integer(v, "byteStride", at + ".byteStride", 0) && v["byteStride"].get<double>() == 0)
                warn(at + ".byteStride is 0, not valid glTF (4 to 252, or left out): read as tightly packed");
        });
        for_each_object(root, "buffers",
                        [&](const Json& b, const std::string& at) { integer(b, "byteLength", at + ".byteLength", 1); });
        for_each_object(root, "images",
                        [&](const Json& im, const std::string& at) { index(im, "bufferView", at + ".bufferView"); });
        for_each_object(root, "textures", [&](const Json& t, const std::string& at) {
            index(t, "source", at + ".source");
            index(t, "sampler", at + ".sampler");
        });
        for_each_object(root, "samplers", [&](const Json& s, const std::string& at) {
            for (const char* key : {"magFilter", "minFilter", "wrapS", "wrapT"}) integer(s, key, at + "." + key, 0);
        });
        for_each_object(root, "materials", [&](const Json& m, const std::string& at) { material(m, at); });
        for_each_object(root, "cameras", [&](const Json& c, const std::string& at) { camera(c, at); });
    }

  private:
    void error(const std::string& message) {
        if (report.error.empty()) report.error = message;
    }
    void warn(const std::string& message) { report.warnings.push_back(message); }

    const Json* object_member(const Json& parent, const char* key, const std::string& at) {
        auto it = parent.find(key);
        if (it == parent.end()) return nullptr;
        if (!it->is_object()) {
            error(at + " is " + describe(*it) + ", not an object");
            return nullptr;
        }
        return &*it;
    }

    template <class F>
    void for_each_object(const Json& parent, const char* key, F&& visit, const std::string& prefix = "") {
        auto it = parent.find(key);
        const std::string at = prefix.empty() ? std::string(key) : prefix + "." + key;
        if (it == parent.end()) return;
        if (!it->is_array()) {
            error(at + " is " + describe(*it) + ", not an array");
            return;
        }
        for (size_t i = 0; i < it->size(); ++i) {
            const std::string item = at + "[" + std::to_string(i) + "]";
            if (!(*it)[i].is_object()) error(item + " is " + describe((*it)[i]) + ", not an object");
            else visit((*it)[i], item);
        }
    }

    // A whole number in [lo, hi], written as a JSON integer. True if present and valid.
    bool integer(const Json& parent, const std::string& key, const std::string& at, double lo,
                 double hi = kMaxInteger) {
        auto it = parent.find(key);
        return it != parent.end() && integer_value(*it, at, lo, hi);
    }
    bool integer_value(const Json& v, const std::string& at, double lo, double hi = kMaxInteger) {
        if (!v.is_number()) {
            error(at + " is " + describe(v) + ", not a number");
            return false;
        }
        const double x = v.get<double>();
        if (!(x == std::floor(x))) {
            error(at + " is " + describe(v) + ", not a whole number");
            return false;
        }
        // tinygltf reads 0.0 as no value at all ("mesh": 0.0 drew no mesh).
        if (!v.is_number_integer()) {
            error(at + " is written " + v.dump() + ": glTF integers have no decimal point or exponent");
            return false;
        }
        if (x < lo || x > hi) {
            error(at + " is " + describe(v) +
                  (hi < kMaxInteger ? ", outside [" + number_text(lo) + ", " + number_text(hi) + "]"
                   : x < lo         ? "; it must be at least " + number_text(lo)
                                    : ", beyond 2^53, the largest integer a glTF number holds exactly"));
            return false;
        }
        return true;
    }
    // An index into one of the document's arrays: a JSON integer >= 0.
    // (An index of 2^31 or more, which tinygltf's 32-bit ints wrap: wrapped_index, for every key.)
    void index_value(const Json& v, const std::string& at) {
        if (!v.is_number()) error(at + " is " + describe(v) + ", not an index (a number)");
        else integer_value(v, at, 0);
    }
    void index(const Json& parent, const std::string& key, const std::string& at) {
        if (auto it = parent.find(key); it != parent.end()) index_value(*it, at);
    }
    void indices(const Json& parent, const char* key, const std::string& at) {
        auto it = parent.find(key);
        if (it == parent.end()) return;
        if (!it->is_array()) return error(at + "." + key + " is " + describe(*it) + ", not an array of indices");
        for (size_t i = 0; i < it->size(); ++i) index_value((*it)[i], at + "." + key + "[" + std::to_string(i) + "]");
    }
    void boolean(const Json& parent, const char* key, const std::string& at) {
        auto it = parent.find(key);
        if (it != parent.end() && !it->is_boolean()) error(at + " is " + describe(*it) + ", not true or false");
    }
    // A number; true if present and a number.
    bool number(const Json& parent, const char* key, const std::string& at) {
        auto it = parent.find(key);
        if (it == parent.end()) return false;
        if (!it->is_number()) {
            error(at + " is " + describe(*it) + ", not a number");
            return false;
        }
        return true;
    }
    // An array of numbers, of exactly `length` when length > 0. Returns them (empty if absent or wrong).
    std::vector<double> numbers(const Json& parent, const char* key, const std::string& at, size_t length) {
        auto it = parent.find(key);
        if (it == parent.end()) return {};
        if (!it->is_array()) {
            error(at + " is " + describe(*it) + ", not an array of numbers");
            return {};
        }
        std::vector<double> out;
        for (size_t i = 0; i < it->size(); ++i) {
            if (!(*it)[i].is_number()) {
                error(at + "[" + std::to_string(i) + "] is " + describe((*it)[i]) + ", not a number");
                return {};
            }
            out.push_back((*it)[i].get<double>());
        }
        if (length > 0 && out.size() != length) {
            error(at + " has " + std::to_string(out.size()) + " numbers, not " + std::to_string(length));
            return {};
        }
        return out;
    }

    void node(const Json& n, const std::string& at) {
        index(n, "camera", at + ".camera");
        index(n, "mesh", at + ".mesh");
        index(n, "skin", at + ".skin");
        if (auto ext = n.find("extensions"); ext != n.end() && ext->is_object())
            if (auto light = ext->find("KHR_lights_punctual"); light != ext->end() && light->is_object())
                index(*light, "light", at + ".extensions.KHR_lights_punctual.light");
        indices(n, "children", at);
        numbers(n, "translation", at + ".translation", 3);
        numbers(n, "scale", at + ".scale", 3);
        numbers(n, "weights", at + ".weights", 0);
        const std::vector<double> r = numbers(n, "rotation", at + ".rotation", 4);
        if (r.size() == 4) {
            const double norm = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + r[3] * r[3]);
            if (!(norm > 1e-6))
                error(at + ".rotation is (" + number_text(r[0]) + ", " + number_text(r[1]) + ", " + number_text(r[2]) +
                      ", " + number_text(r[3]) + "), not a rotation (glTF wants a unit quaternion x, y, z, w)");
            else if (std::abs(norm - 1) > 0.01)
                warn(at + ".rotation has length " + number_text(norm, 4) +
                     ", not 1 (glTF wants a unit quaternion): normalised");
        }
        const std::vector<double> m = numbers(n, "matrix", at + ".matrix", 16);
        // Column-major: the bottom row is elements 3, 7, 11, 15. glTF node matrices are affine
        // (decomposable into translation, rotation and scale); a projective row would be dropped.
        if (m.size() == 16 && !(m[3] == 0 && m[7] == 0 && m[11] == 0 && m[15] == 1))
            error(at + ".matrix has the bottom row (" + number_text(m[3]) + ", " + number_text(m[7]) + ", " +
                  number_text(m[11]) + ", " + number_text(m[15]) +
                  "), not (0, 0, 0, 1): glTF node matrices are affine (translation, rotation, scale)");
        // The spec forbids both: the matrix was used without a word.
        if (m.size() == 16 && (n.contains("translation") || n.contains("rotation") || n.contains("scale")))
            warn(at +
                 " has both a matrix and translation / rotation / scale (glTF allows one or the other): the "
                 "matrix is used");
    }

    void texture_info(const Json& parent, const char* key, const std::string& at) {
        const Json* info = object_member(parent, key, at + "." + key);
        if (!info) return;
        const std::string here = at + "." + key;
        if (!info->contains("index")) error(here + " has no index (which texture)");
        index(*info, "index", here + ".index");
        index(*info, "texCoord", here + ".texCoord");
        number(*info, "scale", here + ".scale");
        number(*info, "strength", here + ".strength");
    }

    void material(const Json& m, const std::string& at) {
        if (const Json* pbr = object_member(m, "pbrMetallicRoughness", at + ".pbrMetallicRoughness")) {
            const std::string p = at + ".pbrMetallicRoughness";
            numbers(*pbr, "baseColorFactor", p + ".baseColorFactor", 4);
            number(*pbr, "metallicFactor", p + ".metallicFactor");
            number(*pbr, "roughnessFactor", p + ".roughnessFactor");
            texture_info(*pbr, "baseColorTexture", p);
            texture_info(*pbr, "metallicRoughnessTexture", p);
        }
        numbers(m, "emissiveFactor", at + ".emissiveFactor", 3);
        texture_info(m, "normalTexture", at);
        texture_info(m, "occlusionTexture", at);
        texture_info(m, "emissiveTexture", at);
        number(m, "alphaCutoff", at + ".alphaCutoff");
        boolean(m, "doubleSided", at + ".doubleSided");
        auto mode = m.find("alphaMode");
        if (mode != m.end() && !mode->is_string())
            error(at + ".alphaMode is " + describe(*mode) + ", not \"OPAQUE\", \"MASK\" or \"BLEND\"");
    }

    void camera(const Json& c, const std::string& at) {
        if (const Json* p = object_member(c, "perspective", at + ".perspective")) {
            const std::string here = at + ".perspective";
            number(*p, "yfov", here + ".yfov");
            if (number(*p, "aspectRatio", here + ".aspectRatio") && !((*p)["aspectRatio"].get<double>() > 0))
                warn(here + ".aspectRatio " + describe((*p)["aspectRatio"]) +
                     " is not positive (not valid glTF): ignored, the image's width / height is used");
            clip_planes(*p, here, true);
        }
        if (const Json* o = object_member(c, "orthographic", at + ".orthographic")) {
            const std::string here = at + ".orthographic";
            number(*o, "ymag", here + ".ymag");
            if (number(*o, "xmag", here + ".xmag") && (*o)["xmag"].get<double>() == 0)
                warn(here + ".xmag is 0 (not valid glTF): ignored, the image's width / height is used");
            clip_planes(*o, here, false);
        }
    }
    // dynsky traces rays without clip planes: invalid ones are said, not used.
    void clip_planes(const Json& c, const std::string& at, bool perspective) {
        const bool has_near = number(c, "znear", at + ".znear"), has_far = number(c, "zfar", at + ".zfar");
        const double znear = has_near ? c["znear"].get<double>() : 0, zfar = has_far ? c["zfar"].get<double>() : 0;
        if (has_near && (perspective ? !(znear > 0) : !(znear >= 0)))
            warn(at + ".znear " + number_text(znear) + (perspective ? " is not positive" : " is negative") +
                 " (not valid glTF): ignored, dynsky renders without clip planes");
        if (has_far && !(zfar > znear))
            warn(at + ".zfar " + number_text(zfar) + " is not beyond znear " + number_text(znear) +
                 " (not valid glTF): ignored, dynsky renders without clip planes");
    }
};

}  // namespace

namespace {

// Every index anywhere in the document, extensions included (KHR_texture_transform's texCoord,
// EXT_texture_webp's source, a skin's joints, an animation's target node...): tinygltf keeps them
// all in 32-bit ints, so one of 2^31 or more silently named another object. Found by the keys
// glTF and its extensions give indices, and every value of a primitive's attributes and targets;
// "extras" (the application's own data) is not looked into.
const char* const kIndexKeys[] = {
    "scene",   "nodes",    "children",   "camera",  "mesh",    "skin",   "skeleton", "joints",   "inverseBindMatrices",
    "indices", "material", "bufferView", "buffer",  "sampler", "source", "index",    "texCoord", "input",
    "output",  "node",     "light",      "variant", "variants"};

bool is_index_key(const std::string& key) {
    for (const char* k : kIndexKeys)
        if (key == k) return true;
    return false;
}

// Values: none are indices but by their key; Elements: an index key's array (its numbers are
// indices, its objects looked into as usual); All: attributes and targets (every number an index).
enum class IndexValues { ByKey, Elements, All };

std::string wrapped_index(const Json& v, const std::string& at, IndexValues mode) {
    auto too_big = [](const Json& x) { return x.is_number_integer() && x.get<double>() > 2147483647.0; };
    auto said = [](const std::string& here, const Json& x) {
        return here + " is " + x.dump() + ", beyond any array (indices are below 2^31)";
    };
    if (v.is_object()) {
        for (auto it = v.begin(); it != v.end(); ++it) {
            if (it.key() == "extras") continue;
            const std::string here = at + "." + it.key();
            const bool all = mode == IndexValues::All || it.key() == "attributes" || it.key() == "targets";
            if ((all || is_index_key(it.key())) && too_big(*it)) return said(here, *it);
            const IndexValues inner = all                                        ? IndexValues::All
                                      : is_index_key(it.key()) && it->is_array() ? IndexValues::Elements
                                                                                 : IndexValues::ByKey;
            if (std::string e = wrapped_index(*it, here, inner); !e.empty()) return e;
        }
    } else if (v.is_array()) {
        for (size_t i = 0; i < v.size(); ++i) {
            const std::string here = at + "[" + std::to_string(i) + "]";
            if (mode != IndexValues::ByKey && too_big(v[i])) return said(here, v[i]);
            const IndexValues inner = mode == IndexValues::All ? IndexValues::All : IndexValues::ByKey;
            if (std::string e = wrapped_index(v[i], here, inner); !e.empty()) return e;
        }
    }
    return "";
}

}  // namespace

GltfJsonReport check_gltf_json(const Json& root) {
    Checker checker;
    if (root.is_object()) checker.run(root);
    if (root.is_object() && checker.report.error.empty()) {
        std::string e = wrapped_index(root, "", IndexValues::ByKey);
        if (!e.empty()) checker.report.error = e.substr(1);  // no leading "."
    }
    return checker.report;
}

std::optional<nlohmann::json> read_gltf_json(const std::string& path) {
    try {
        std::ifstream f(path, std::ios::binary);
        if (!f) return std::nullopt;
        unsigned char head[20] = {};
        f.read(reinterpret_cast<char*>(head), sizeof head);
        if (f.gcount() >= 4 && std::memcmp(head, "glTF", 4) == 0) {
            if (f.gcount() < 20) return std::nullopt;
            const uint32_t length = uint32_t(head[12]) | uint32_t(head[13]) << 8 | uint32_t(head[14]) << 16 |
                                    uint32_t(head[15]) << 24;
            if (std::memcmp(head + 16, "JSON", 4) != 0 || length > (64u << 20)) return std::nullopt;
            std::string text(length, '\0');
            if (!f.read(text.data(), std::streamsize(length))) return std::nullopt;
            return nlohmann::json::parse(text);
        }
        f.clear();
        f.seekg(0);
        return nlohmann::json::parse(f);
    } catch (const nlohmann::json::exception&) {
        return std::nullopt;
    }
}

}  // namespace dynsky
