#include "frame/frame_store.h"

#include <filesystem>
#include <regex>

#include "util/error.h"
#include "util/parse.h"
#include "util/frame_names.h"

namespace dynsky {

namespace fs = std::filesystem;

std::string FrameStore::frame_exr(int k) const { return numbered_path(folder_, "frame", k, ".exr"); }
std::string FrameStore::frame_png(int k) const { return numbered_path(folder_, "frame", k, ".png"); }
std::string FrameStore::sky_png(int k) const { return numbered_path(folder_, "sky", k, ".png"); }
std::string FrameStore::file(const std::string& name) const { return (fs::path(folder_) / name).string(); }

bool FrameStore::is_complete(int k) const {
    return fs::exists(frame_exr(k)) && fs::exists(frame_png(k)) && fs::exists(sky_png(k));
}

bool FrameStore::all_complete(int total) const {
    for (int k = 0; k < total; ++k)
        if (!is_complete(k)) return false;
    return true;
}

void parse_frame_range(const std::string& text, int total, int* first, int* last) {
    *first = 0, *last = total - 1;
    if (text.empty()) return;
    std::smatch m;
    if (!std::regex_match(text, m, std::regex("^([0-9]+)(-([0-9]+))?$")))
        throw Error("--frames '" + text + "': expected A-B (inclusive, from 0) or a single frame number");
    *first = int(parse_whole_number(m[1], "--frames '" + text + "'", 0, 1 << 30));
    *last = m[3].matched ? int(parse_whole_number(m[3], "--frames '" + text + "'", 0, 1 << 30)) : *first;
    if (*first > *last || *last >= total)
        throw Error("--frames '" + text + "': the animation has frames 0-" + std::to_string(total - 1));
}

}  // namespace dynsky
