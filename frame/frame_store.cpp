#include "frame/frame_store.h"

#include <filesystem>
#include <regex>

#include "frame/frame_metadata.h"
#include "util/error.h"
#include "util/image.h"
#include "util/parse.h"
#include "util/frame_names.h"

namespace dynsky {

namespace fs = std::filesystem;

std::string FrameStore::frame_exr(int k) const { return numbered_path(folder_, "frame", k, ".exr", count_); }
std::string FrameStore::frame_png(int k) const { return numbered_path(folder_, "frame", k, ".png", count_); }
std::string FrameStore::sky_png(int k) const { return numbered_path(folder_, "sky", k, ".png", count_); }
std::string FrameStore::file(const std::string& name) const { return (fs::path(folder_) / name).string(); }

FrameCheck FrameStore::check(int k, int width, int height, const std::string& settings) const {
    const std::string exr = frame_exr(k), png = frame_png(k), sky = sky_png(k);
    std::error_code ec;
    if (!fs::exists(exr, ec) && !fs::exists(png, ec) && !fs::exists(sky, ec)) return {FrameCheck::Missing, ""};
    auto name = [](const std::string& p) { return fs::path(p).filename().string(); };
    for (const std::string& p : {exr, png, sky})
        if (!fs::exists(p, ec)) return {FrameCheck::Damaged, name(p) + " is missing"};
    Image frame;
    try {
        frame = read_image(exr);
        Image display = read_image(png);
        if (frame.width != width || frame.height != height || display.width != width || display.height != height)
            return {FrameCheck::OtherSettings, "res " + std::to_string(frame.width) + "x" +
                                                   std::to_string(frame.height) + " -> " + std::to_string(width) + "x" +
                                                   std::to_string(height)};
        read_image(sky);
        // A frame the renderer wrote is finite everywhere: a NaN or infinite pixel means the file
        // was damaged (or replaced) since.
        if (const long i = first_non_finite(frame); i >= 0)
            return {FrameCheck::Damaged, name(exr) + ": " + non_finite_pixel_text(frame, i)};
    } catch (const Error& e) {
        std::string why = e.what();
        size_t colon = why.find(": ");  // "PATH: problem" -> the file's name and the problem
        return {FrameCheck::Damaged, colon == std::string::npos ? why : name(why.substr(0, colon)) + why.substr(colon)};
    }
    auto recorded = frame.metadata.strings.find("dynsky:settings");
    if (recorded == frame.metadata.strings.end())
        return {FrameCheck::OtherSettings, "made by an older dynsky (no settings recorded)"};
    auto hash = frame.metadata.strings.find("dynsky:settings_hash");
    if (hash == frame.metadata.strings.end() || hash->second != settings_hash(recorded->second))
        return {FrameCheck::Damaged, name(exr) + ": its recorded settings do not match their hash"};
    // A frame file copied or renamed onto another's number holds another moment.
    auto number = frame.metadata.numbers.find("dynsky:frame");
    if (number != frame.metadata.numbers.end() && number->second != double(k))
        return {FrameCheck::Damaged, name(exr) + " holds frame " + number_text(number->second)};
    if (recorded->second != settings) {
        std::string change = describe_settings_change(parse_settings(recorded->second), parse_settings(settings));
        return {FrameCheck::OtherSettings, change.empty() ? "other settings" : change};
    }
    return {FrameCheck::Complete, ""};
}

void parse_frame_range(const std::string& text, int total, int* first, int* last) {
    *first = 0, *last = total - 1;
    if (text.empty()) return;
    std::smatch m;
    if (!std::regex_match(text, m, std::regex("^([0-9]+)(-([0-9]+))?$")))
        throw Error("--frames '" + text + "': expected A-B (inclusive, from 0) or a single frame number");
    *first = int(parse_whole_number(m[1], "--frames '" + text + "'", 0, 1 << 30));
    *last = m[3].matched ? int(parse_whole_number(m[3], "--frames '" + text + "'", 0, 1 << 30)) : *first;
    if (*first > *last)
        throw Error("--frames '" + text + "': the first frame comes after the last (give A-B with A <= B)");
    if (*last >= total) throw Error("--frames '" + text + "': the animation has frames 0-" + std::to_string(total - 1));
}

}  // namespace dynsky
