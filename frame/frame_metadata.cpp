#include "frame/frame_metadata.h"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include <nlohmann/json.hpp>

#include "renderer/gltf_json_check.h"
#include "util/file_hash.h"
#include "util/image.h"
#include "util/parse.h"
#include "util/version.h"

namespace dynsky {

namespace fs = std::filesystem;

std::string canonical_settings(const FrameSettings& settings) {
    std::string s;
    for (const auto& [key, value] : settings) s += key + "=" + value + "\n";
    return s;
}

FrameSettings parse_settings(const std::string& canonical) {
    FrameSettings s;
    std::istringstream in(canonical);
    std::string line;
    while (std::getline(in, line)) {
        size_t eq = line.find('=');
        if (eq != std::string::npos) s[line.substr(0, eq)] = line.substr(eq + 1);
    }
    return s;
}

std::string settings_hash(const std::string& canonical) { return hash_text(canonical); }

namespace {

// A number of the settings as a person typed it: stored with 17 digits so that it round-trips,
// --coverage 0.6 read "0.59999999999999998". 15 digits unless that hides the change.
std::string readable_number(const std::string& value, const std::string& other) {
    char* end = nullptr;
    const double v = std::strtod(value.c_str(), &end);
    if (value.empty() || end != value.c_str() + value.size()) return value;
    char a[40], b[40];
    std::snprintf(a, sizeof a, "%.15g", v);
    const double w = std::strtod(other.c_str(), &end);
    if (!other.empty() && end == other.c_str() + other.size()) {
        std::snprintf(b, sizeof b, "%.15g", w);
        if (std::string(a) == b) return value;
    }
    return a;
}

}  // namespace

std::string describe_settings_change(const FrameSettings& before, const FrameSettings& now, int limit) {
    std::vector<std::string> keys;
    for (const auto& [k, v] : now) keys.push_back(k);
    for (const auto& [k, v] : before)
        if (!now.count(k)) keys.push_back(k);
    std::string out;
    int named = 0, more = 0;
    for (const std::string& k : keys) {
        auto a = before.find(k), b = now.find(k);
        // A key recorded only when not the default (turbidity, evolution, sky_turn) or by later revisions:
        // "(none)" read as "no evolution" where the clouds had evolved at the default 900 s.
        const std::string unset = "(default)";
        std::string va = a == before.end() ? unset : a->second, vb = b == now.end() ? unset : b->second;
        if (va == vb) continue;
        if (named == limit) {
            ++more;
            continue;
        }
        out += (named++ ? ", " : "") + k + " " + readable_number(va, vb) + " -> " + readable_number(vb, va);
    }
    if (more) out += " and " + std::to_string(more) + " more";
    return out;
}

std::string describe_scene_input(const std::string& scene) {
    std::error_code ec;
    const std::string ext = file_extension(scene);
    if (!fs::is_regular_file(scene, ec) || (ext != ".gltf" && ext != ".glb")) return describe_input(scene);
    std::string s = describe_file(scene);
    // The files its buffers and images name (percent-escapes decoded; data: URIs are in the JSON).
    // A .glb's images may still be files beside it (the Kenney city kit's shared colormap.png).
    const std::optional<nlohmann::json> json = read_gltf_json(scene);
    if (!json) return s;  // the loader names what is wrong with it
    const nlohmann::json& j = *json;
    for (const char* key : {"buffers", "images"}) {
        if (!j.contains(key) || !j[key].is_array()) continue;
        for (const auto& item : j[key]) {
            if (!item.is_object() || !item.contains("uri") || !item["uri"].is_string()) continue;
            const std::string uri = item["uri"].get<std::string>();
            if (uri.rfind("data:", 0) == 0) continue;
            const fs::path file = fs::path(scene).parent_path() / percent_decoded(uri);
            if (fs::is_regular_file(file, ec)) s += "; " + describe_file(file);
        }
    }
    return s;
}

std::string describe_input(const std::string& input) {
    std::error_code ec;
    if (fs::is_regular_file(input, ec)) return describe_file(input);
    if (!fs::is_directory(input, ec)) return input;
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(input, ec))
        if (e.is_regular_file(ec) && e.path().filename().string().rfind(".tmp-", 0) != 0) files.push_back(e.path());
    std::sort(files.begin(), files.end());
    std::string s = "folder [";
    for (size_t i = 0; i < files.size(); ++i) s += (i ? "; " : "") + describe_file(files[i]);
    return s + "]";
}

void FrameMetadata::write_to(ImageMetadata* m) const {
    m->numbers["dynsky:frame"] = frame;
    m->numbers["dynsky:time"] = time_seconds;
    m->numbers["dynsky:fps"] = fps;
    m->numbers["dynsky:spp"] = spp;
    m->numbers["dynsky:seed"] = double(seed);
    m->strings["dynsky:seed_exact"] = std::to_string(seed);  // a double holds 53 bits of it
    m->numbers["dynsky:medium_step_seconds"] = medium_step_seconds;
    m->numbers["dynsky:png_exposure_ev"] = png_exposure_ev;
    m->strings["dynsky:sky"] = sky;
    if (!units.empty()) m->strings["dynsky:units"] = units;
    m->strings["Software"] = dynsky_version();  // the build (util/version.h): a mixed farm shows in its frames
    m->strings["dynsky:sky_model"] = sky_model;
    m->strings["dynsky:gamma"] = gamma;
    m->strings["dynsky:scene"] = scene;
    m->strings["dynsky:camera"] = camera;
    m->strings["dynsky:settings"] = settings;
    if (!date_time.empty()) m->strings["DateTime"] = date_time;  // none when unknown (util/image.cpp)
    m->strings["dynsky:settings_hash"] = settings_hash(settings);
}

}  // namespace dynsky
