#include "motion/photo_sequence.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>

#include "sky/photo_import.h"
#include "sky/sky_image.h"
#include "sky/sun_position.h"
#include "util/data_path.h"
#include "util/math.h"
#include "util/error.h"
#include "util/image.h"

namespace dynsky {

namespace fs = std::filesystem;

std::string default_shared_dir() {
    // The shared data sits beside the source tree (the tests' ../shared): beside any data root that
    // has one (the source tree recorded at build time, DYNSKY_DATA), else beside the working folder.
    // An installed program's root (PREFIX/share/dynsky) has none beside it; the first existing wins.
    std::error_code ec;
    for (const std::string& root : data_roots()) {
        const fs::path candidate = (fs::path(root) / ".." / "shared").lexically_normal();
        if (fs::is_directory(candidate / "skies", ec)) return candidate.string();
    }
    return "../shared";
}

namespace {

// Throws naming the first frame whose gap to the one before is not the cadence (a repeated time,
// a missing frame, mixed cadences). `timed`: (UTC seconds, path) in time order.
void check_regular_cadence(const std::vector<std::pair<double, std::string>>& timed, double cadence) {
    // Names carry whole seconds and timer-driven cameras jitter by one: a gap within 10 % of the
    // cadence (at least 1.5 s, under half of it) is the cadence; a missing frame doubles it.
    const double tolerance = std::min(std::max(1.5, 0.1 * cadence), 0.45 * cadence);
    for (size_t k = 1; k < timed.size(); ++k) {
        const double gap = timed[k].first - timed[k - 1].first;
        if (gap < 0.5)
            throw_file_error(timed[k].second,
                             "has the same time as " + fs::path(timed[k - 1].second).filename().string());
        if (std::abs(gap - cadence) > tolerance)
            throw_file_error(timed[k].second,
                             "comes " + std::to_string(long(std::lround(gap))) + " s after " +
                                 fs::path(timed[k - 1].second).filename().string() + ", but the cadence is " +
                                 std::to_string(long(std::lround(cadence))) +
                                 " s (mixed cadence or missing frames: give a folder of one regular sequence)");
    }
}

}  // namespace

PhotoSequence named_photo_sequence(const std::string& name, const std::string& shared_dir) {
    // name (as in data sets and split.json), CLI spelling, preset, folder in shared/skies, cadence.
    struct Known {
        const char *name, *spelling, *preset, *folder;
        double dt;
    };
    static const Known known[] = {
        {"arm_tsi", "arm-tsi", "arm-tsi", "arm_tsi_sgp_20170524", 30.0},
        {"arm_clear", "arm-clear", "arm-tsi", "arm_tsi_sgp_20170524_clear_morning", 30.0},
        {"arm_dusk", "arm-dusk", "arm-tsi", "arm_tsi_sgp_20170524_overcast_dusk", 30.0},
        {"mobotix", "mobotix", "mobotix", "mobotix_sophia_20200812_morning", 60.0},
    };
    PhotoSequence s;
    for (const Known& k : known)
        if (name == k.name || name == k.spelling)
            s = {k.name, k.preset, (fs::path(shared_dir) / "skies" / k.folder).string(), k.dt, {}, {}};
    if (s.name.empty())
        throw Error("--sequence: unknown sequence '" + name +
                    "' (known: arm-tsi, arm-clear, arm-dusk, mobotix; or give any folder with --photos and --preset)");
    const std::string csv = (fs::path(s.folder) / "frames.csv").string();
    if (fs::exists(csv)) {
        std::ifstream f(csv);
        std::string line;
        std::getline(f, line);  // header
        while (std::getline(f, line))
            if (!line.empty()) s.photos.push_back((fs::path(s.folder) / line.substr(0, line.find(','))).string());
    } else if (fs::is_directory(fs::path(s.folder) / "images")) {
        for (const auto& e : fs::directory_iterator(fs::path(s.folder) / "images"))
            if ((e.path().extension() == ".jpg" || e.path().extension() == ".png") &&
                !is_hidden_file(e.path().string()))
                s.photos.push_back(e.path().string());
        std::sort(s.photos.begin(), s.photos.end());
    } else {
        throw_file_error(s.folder, "sequence folder not found (give the shared data folder with --shared)");
    }
    if (s.photos.size() < 2) throw_file_error(s.folder, "fewer than two frames");
    const double utc_offset = camera_preset(s.preset).filename_utc_offset_hours;
    for (const std::string& p : s.photos) {
        const std::string time = time_from_file_name(p, utc_offset);
        s.utc.push_back(time.empty() ? std::nan("") : utc_seconds(time));
    }
    // A frame missing from the folder: the pairs around it are not one step apart (training data
    // paired them as one 30 s step; the evaluation of a folder refused the same photographs).
    std::vector<std::pair<double, std::string>> timed;
    for (size_t k = 0; k < s.photos.size(); ++k)
        if (std::isfinite(s.utc[k])) timed.emplace_back(s.utc[k], s.photos[k]);
    if (timed.size() == s.photos.size()) check_regular_cadence(timed, s.dt);
    return s;
}

namespace {

// The UTC time an imported sky was photographed at (Julian date x 86400): its file name's, else the
// one its import recorded (sky_recorded_utc_seconds). nullopt when neither says.
std::optional<double> imported_sky_time(const std::string& path) {
    const std::string time = time_from_file_name(path, 0);
    if (!time.empty()) return utc_seconds(time);
    return sky_recorded_utc_seconds(load_sky(path));
}

// Where a sequence folder keeps its frames: its images/ sub-folder when it has one.
fs::path frames_folder(const std::string& folder) {
    return fs::is_directory(fs::path(folder) / "images") ? fs::path(folder) / "images" : fs::path(folder);
}

}  // namespace

bool folder_holds_skies(const std::string& folder) {
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(frames_folder(folder), ec))
        if (file_extension(e.path().string()) == ".exr") return true;
    return false;
}

PhotoSequence photo_sequence_from_folder(const std::string& folder, const std::string& preset) {
    if (!fs::is_directory(folder)) throw_file_error(folder, "not a folder of photographs");
    const bool skies = preset.empty();  // a folder of imported skies (EXR)
    const double utc_offset = skies ? 0.0 : camera_preset(preset).filename_utc_offset_hours;  // throws listing them
    const fs::path dir = frames_folder(folder);
    std::vector<std::pair<double, std::string>> timed;
    for (const auto& e : fs::directory_iterator(dir)) {
        if (!e.is_regular_file() || is_hidden_file(e.path().string())) continue;
        const std::string ext = file_extension(e.path().string());
        if (skies && (ext == ".jpg" || ext == ".jpeg" || ext == ".png")) {
            // Another photograph would be left out of the sequence unseen.
            if (written_beside_a_sky(e.path().string())) continue;
            throw_file_error(e.path().string(),
                             "is a photograph among imported skies (.exr): import it with the others ('dynsky sky "
                             "import' with the camera's options) or move it out of the folder");
        }
        if (skies ? ext != ".exr" : ext != ".jpg" && ext != ".jpeg" && ext != ".png") continue;
        std::optional<double> seconds;
        if (skies) {
            seconds = imported_sky_time(e.path().string());
        } else if (const std::string time = photo_time(e.path().string(), utc_offset).iso; !time.empty()) {
            seconds = utc_seconds(time);
        }
        if (!seconds)
            throw_file_error(e.path().string(),
                             skies
                                 ? "carries no time (none in its name, as ..._YYYYMMDDhhmmssZ.exr, nor the "
                                   "photograph's time that 'dynsky sky import' records)"
                                 : "carries no time: none in its file name (as ..._YYYYMMDDhhmmssZ.jpg, "
                                   "YYYY-MM-DD_hh_mm.jpg, YYYY-MM-DDThh:mm:ss.jpg or YYYYMMDD_hhmmss.jpg) and no EXIF "
                                   "DateTimeOriginal");
        timed.emplace_back(*seconds, e.path().string());
    }
    if (timed.empty())
        throw_file_error(dir.string(), skies ? "no imported skies (.exr) in this folder"
                                             : "no photographs (.jpg, .jpeg, .png) in this folder");
    if (timed.size() < 3)
        throw_file_error(dir.string(), std::string("fewer than three ") + (skies ? "skies" : "photographs") +
                                           ": nothing to predict and score");
    std::sort(timed.begin(), timed.end());
    std::vector<double> gaps;
    for (size_t k = 1; k < timed.size(); ++k) gaps.push_back(timed[k].first - timed[k - 1].first);
    const double cadence = median(gaps);
    check_regular_cadence(timed, cadence);
    PhotoSequence s;
    s.name = fs::path(folder).filename().string();
    if (s.name.empty()) s.name = fs::path(folder).parent_path().filename().string();
    s.preset = preset;
    s.folder = folder;
    s.dt = std::round((timed.back().first - timed.front().first) / double(timed.size() - 1));  // the mean gap
    for (auto& [t, p] : timed) s.photos.push_back(p), s.utc.push_back(t);
    return s;
}

void check_import_resolution(int resolution) {
    if (resolution < kImportResolutionMin || resolution > kImportResolutionMax)
        throw Error("--import-res " + std::to_string(resolution) + ": must be " + std::to_string(kImportResolutionMin) +
                    ".." + std::to_string(kImportResolutionMax));
}

}  // namespace dynsky
