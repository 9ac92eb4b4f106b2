#include "motion/photo_sequence.h"

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "util/data_path.h"
#include "util/error.h"

namespace dynsky {

namespace fs = std::filesystem;

std::string default_shared_dir() {
    // The shared data sits beside the source tree (the tests' ../shared).
    try {
        return (fs::path(data_path("sky")).parent_path().parent_path() / "shared").string();
    } catch (const Error&) {
        return "../shared";
    }
}

PhotoSequence named_photo_sequence(const std::string& name, const std::string& shared_dir) {
    PhotoSequence s;
    if (name == "arm-tsi" || name == "arm_tsi") {
        s = {"arm_tsi", "arm-tsi", (fs::path(shared_dir) / "skies" / "arm_tsi_sgp_20170524").string(), 30.0, {}};
    } else if (name == "mobotix") {
        s = {"mobotix",
             "mobotix",
             (fs::path(shared_dir) / "skies" / "mobotix_sophia_20200812_morning").string(),
             60.0,
             {}};
    } else {
        throw Error("--sequence: unknown sequence '" + name + "' (known: arm-tsi, mobotix)");
    }
    const std::string csv = (fs::path(s.folder) / "frames.csv").string();
    if (fs::exists(csv)) {
        std::ifstream f(csv);
        std::string line;
        std::getline(f, line);  // header
        while (std::getline(f, line))
            if (!line.empty()) s.photos.push_back((fs::path(s.folder) / line.substr(0, line.find(','))).string());
    } else if (fs::is_directory(fs::path(s.folder) / "images")) {
        for (const auto& e : fs::directory_iterator(fs::path(s.folder) / "images"))
            if (e.path().extension() == ".jpg" || e.path().extension() == ".png") s.photos.push_back(e.path().string());
        std::sort(s.photos.begin(), s.photos.end());
    } else {
        throw_file_error(s.folder, "sequence folder not found (give the shared data folder with --shared)");
    }
    if (s.photos.size() < 2) throw_file_error(s.folder, "fewer than two frames");
    return s;
}

}  // namespace dynsky
