#include "motion/photo_sequence.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "sky/clear_sky.h"
#include "sky/sky_image.h"
#include "tests/test_support.h"
#include "util/error.h"

namespace dynsky {
namespace {

namespace fs = std::filesystem;

// ARM photographs linked under names of the given seconds after 17:45:00 (the preset reads the
// time from the name).
std::string arm_photos_at(const std::string& dir, const std::vector<int>& seconds) {
    const std::string src = test::shared_path("skies/arm_tsi_sgp_20170524/images");
    std::vector<fs::path> all;
    for (const auto& e : fs::directory_iterator(src)) all.push_back(e.path());
    std::sort(all.begin(), all.end());
    fs::create_directories(dir);
    for (size_t k = 0; k < seconds.size(); ++k) {
        char name[64];
        const int t = 17 * 3600 + 45 * 60 + seconds[k];
        std::snprintf(name, sizeof name, "tsi_sgpC1_20170524%02d%02d%02dZ.jpg", t / 3600, t / 60 % 60, t % 60);
        fs::create_symlink(all[100 + k], fs::path(dir) / name);
    }
    return dir;
}

// Timer-driven cameras name frames to the second and jitter by one: still one sequence, at the
// mean cadence. A missing frame is not jitter.
TEST(PhotoSequence, OneSecondOfJitterIsTheCadenceAMissingFrameIsNot) {
    DYNSKY_REQUIRE_SHARED();
    const std::string dir = test::temp_dir("photo_sequence_jitter");
    PhotoSequence s = photo_sequence_from_folder(arm_photos_at(dir + "/jitter", {0, 31, 60, 91, 120, 151}), "arm-tsi");
    EXPECT_EQ(s.photos.size(), 6u);
    EXPECT_DOUBLE_EQ(s.dt, 30.0);
    try {
        photo_sequence_from_folder(arm_photos_at(dir + "/gap", {0, 30, 60, 120, 150}), "arm-tsi");
        ADD_FAILURE() << "a missing frame was taken for the cadence";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("missing frames"), std::string::npos) << e.what();
    }
    fs::remove_all(dir);
}

// A named sequence in a shared folder missing a photograph: `sky training-data` paired the frames
// around the gap as one 30 s step (the next frame's time made up as 300 s for 330), where the
// evaluation of the same folder refused it (a researcher's audit). Both now refuse, naming the
// frame after the gap; a whole sequence still loads.
TEST(PhotoSequence, ANamedSequenceMissingAFrameIsRefused) {
    DYNSKY_REQUIRE_SHARED();
    const std::string dir = test::temp_dir("photo_sequence_named_gap");
    arm_photos_at(dir + "/skies/arm_tsi_sgp_20170524/images", {0, 30, 60, 90, 120});
    EXPECT_EQ(named_photo_sequence("arm-tsi", dir).photos.size(), 5u);
    fs::remove(dir + "/skies/arm_tsi_sgp_20170524/images/tsi_sgpC1_20170524174630Z.jpg");
    try {
        named_photo_sequence("arm-tsi", dir);
        ADD_FAILURE() << "a missing frame was taken for the cadence";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("tsi_sgpC1_20170524174700Z.jpg"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("missing frames"), std::string::npos) << e.what();
    }
    fs::remove_all(dir);
}

// Dot-files (macOS's ._NAME.jpg resource forks with the photograph's own name and time,
// .DS_Store) are not photographs: they were refused as a second frame of the same time.
TEST(PhotoSequence, HiddenFilesAreNotPhotographs) {
    DYNSKY_REQUIRE_SHARED();
    const std::string dir = test::temp_dir("photo_sequence_hidden");
    const std::string photos = arm_photos_at(dir + "/photos", {0, 30, 60, 90});
    std::ofstream(photos + "/._tsi_sgpC1_20170524174530Z.jpg") << "Mac OS X resource fork";
    std::ofstream(photos + "/.DS_Store") << "junk";
    PhotoSequence s = photo_sequence_from_folder(photos, "arm-tsi");
    EXPECT_EQ(s.photos.size(), 4u);
    for (const std::string& p : s.photos) EXPECT_NE(fs::path(p).filename().string()[0], '.') << p;
    fs::remove_all(dir);
}

// What `sky import --detect-obstructions` writes into a folder of skies (its obstruction mask,
// previews) belongs to the skies: evaluating that folder refused it as a photograph left out.
TEST(PhotoSequence, AFolderOfImportedSkiesKeepsWhatTheImportWroteBesideThem) {
    const std::string dir = test::temp_dir("photo_sequence_skies");
    ClearSkyParams p;
    p.sun_direction = Vec3d(0.3, 0.8, 0.2).normalized();
    const SkyImage sky = make_clear_sky(p, 16);
    for (const char* stamp : {"20170524174500Z", "20170524174530Z", "20170524174600Z"})
        save_sky(dir + "/tsi_" + stamp + ".exr", sky, dir + "/tsi_" + std::string(stamp) + ".png");
    write_image(dir + "/" + kSequenceObstructionsName, Image(16, 16, 1));
    PhotoSequence s = photo_sequence_from_folder(dir, "");
    EXPECT_EQ(s.photos.size(), 3u);
    EXPECT_DOUBLE_EQ(s.dt, 30.0);
    std::ofstream(dir + "/holiday.jpg") << "a photograph";  // not imported: still said
    EXPECT_THROW(photo_sequence_from_folder(dir, ""), Error);
    fs::remove_all(dir);
}

}  // namespace
}  // namespace dynsky
