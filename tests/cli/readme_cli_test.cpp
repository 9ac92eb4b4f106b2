// The README's commands, run as a new user would: from a folder other than the source tree, with
// the shipped scenes named by their relative paths. Extra options only shrink what would take too
// long (frame and sky sizes, samples, durations); every option the README writes is kept.
// Also: `cmake --install` gives a program that finds its scenes and models beside itself.
#include <gtest/gtest.h>

#include <filesystem>

#include "tests/test_support.h"
#include "util/image.h"

namespace dynsky {
namespace {

namespace fs = std::filesystem;

// Runs `dynsky ARGS` in `dir` (the README's build/cli/dynsky is this build's program).
test::CommandResult in_folder(const std::string& dir, const std::string& args) {
    return test::run_command("cd '" + dir + "' && " + DYNSKY_EXE + " " + args);
}

bool non_empty(const fs::path& p) { return fs::exists(p) && fs::file_size(p) > 0; }

TEST(ReadmeCommands, RenderAndClearSkyFromAnotherFolder) {
    const std::string dir = test::temp_dir("readme_render");
    auto r = in_folder(dir,
                       "sky clear --lat 48.85 --lon 2.35 --time 2026-06-21T12:00:00Z --sky-res 1024 --out sky.exr");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    ASSERT_TRUE(non_empty(fs::path(dir) / "sky.exr"));
    r = in_folder(dir, "sky latlong sky.exr --out latlong.exr");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(non_empty(fs::path(dir) / "latlong.exr"));
    // SCENE.glb and SKY.exr of the README: the shipped Tower, the sky just made.
    r = in_folder(dir, "render scenes/tower/tower.gltf --sky sky.exr --spp 2 --res 64x36 --out frame.exr");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(non_empty(fs::path(dir) / "frame.exr"));
    // The header says which Tower was found (the shipped one, not a folder's own copy) and its files.
    const Image frame = read_image((fs::path(dir) / "frame.exr").string());
    const std::string found = frame.metadata.strings.at("dynsky:scene_file");
    EXPECT_TRUE(fs::path(found).is_absolute() &&
                fs::equivalent(found, fs::path(DYNSKY_SOURCE_DIR) / "scenes/tower/tower.gltf"))
        << found;
    EXPECT_NE(frame.metadata.strings.at("dynsky:scene_file_contents").find("tower.bin ("), std::string::npos);
    r = in_folder(dir, "render builtin --res 48x27 --spp 2");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(non_empty(fs::path(dir) / "render.exr"));
    // render makes its own sky as animate and compare do.
    r = in_folder(dir,
                  "render builtin --sky clear --lat 40 --lon -100 --time 2026-03-20T18:00:00Z --sky-res 128 "
                  "--res 32x18 --spp 2 --out clear.exr");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    Image im = read_image((fs::path(dir) / "clear.exr").string());
    EXPECT_NE(im.metadata.strings["dynsky:sky"].find("clear sky"), std::string::npos);
    r = in_folder(dir, "render builtin --sky sky.exr --time 2026-03-20T18:00:00Z --res 32x18 --spp 2 --out bad.exr");
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.output.find("--time"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(fs::path(dir) / "bad.exr"));
}

TEST(ReadmeCommands, CompareWithItsDefaultsAndWithASkyExr) {
    const std::string dir = test::temp_dir("readme_compare");
    const std::string small =
        " --res 64x36 --spp 2 --chart-frames 3 --chart-res 32x18 --chart-spp 1 --duration 20 --sky-res 128";
    auto r = in_folder(dir, "compare scenes/tower/tower.gltf --out cmp/" + small);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    for (const char* f : {"side_by_side.png", "difference.png", "illuminance.csv", "clear.exr", "cloudy.exr"})
        EXPECT_TRUE(non_empty(fs::path(dir) / "cmp" / f)) << f;
    // difference.png carries its colour bar below the image, enlarged 4x (nearest) so the bar's
    // labels fit under a 64 px render.
    Image diff = read_image((fs::path(dir) / "cmp" / "difference.png").string());
    EXPECT_EQ(diff.width, 4 * 64);
    EXPECT_GT(diff.height, 4 * 36);
    // A sky EXR that carries its sun: the clear sky takes that sun, no --time needed.
    r = in_folder(dir, "sky clear --lat 48.85 --lon 2.35 --time 2026-06-21T12:00:00Z --sky-res 128 --out sky.exr");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    r = in_folder(dir, "compare scenes/tower/tower.gltf --sky sky.exr --out cmp2/" + small);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(non_empty(fs::path(dir) / "cmp2" / "illuminance.csv"));
    // Its images say what made them, as render's do: the build, the files found, how the sky was taken.
    for (const char* f : {"clear.exr", "cloudy.exr"}) {
        const Image im = read_image((fs::path(dir) / "cmp2" / f).string());
        EXPECT_EQ(im.metadata.strings.at("Software").rfind("dynsky ", 0), 0u) << f;
        EXPECT_TRUE(fs::equivalent(im.metadata.strings.at("dynsky:sky_file"), fs::path(dir) / "sky.exr")) << f;
        EXPECT_TRUE(fs::equivalent(im.metadata.strings.at("dynsky:scene_file"),
                                   fs::path(DYNSKY_SOURCE_DIR) / "scenes/tower/tower.gltf"))
            << f;
        EXPECT_EQ(im.metadata.numbers.at("dynsky:sky_res"), 128) << f;
    }
    for (const char* f : {"side_by_side.png", "difference.png"}) {  // and its pictures the build
        const Image im = read_image((fs::path(dir) / "cmp2" / f).string());
        ASSERT_TRUE(im.metadata.strings.count("Software")) << f;
        EXPECT_EQ(im.metadata.strings.at("Software").rfind("dynsky ", 0), 0u) << f;
    }
}

TEST(ReadmeCommands, AnimateFromAnotherFolder) {
    const std::string dir = test::temp_dir("readme_animate");
    auto r = in_folder(dir,
                       "animate scenes/house/house.gltf --duration 60 --fps 2 --out anim/"
                       " --duration 2.5 --res 48x27 --spp 1 --sky-res 128 --no-video");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const fs::path anim = fs::path(dir) / "anim";
    EXPECT_TRUE(non_empty(anim / "frame_0004.exr"));
    Image f = read_image((anim / "frame_0004.exr").string());
    EXPECT_EQ(f.metadata.strings["dynsky:gamma"], "constant");
    // 5 frames: one full row of five, no empty cells, 320 px each.
    Image sheet = read_image((anim / "contact_sheet.png").string());
    EXPECT_EQ(sheet.width, 5 * 320);
    EXPECT_EQ(sheet.height, 180);
}

TEST(ReadmeCommands, SkyProceduralAndImport) {
    const std::string dir = test::temp_dir("readme_sky");
    auto r = in_folder(
        dir, "sky procedural --cloud-seed 1 --coverage 0.5 --duration 60 --dt 10 --sky-res 512 --out clouds/");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(fs::exists(fs::path(dir) / "clouds"));
    if (!test::shared_available()) GTEST_SKIP() << "../shared missing: no photograph to import";
    const std::string photos = test::shared_path("skies/arm_tsi_sgp_20170524/images");
    fs::copy_file(photos + "/tsi_sgpC1_20170524160000Z.jpg", fs::path(dir) / "photo.jpg");
    r = in_folder(dir, "sky import photo.jpg --preset arm-tsi --sky-res 512 --out sky.exr");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(non_empty(fs::path(dir) / "sky.exr"));

    // Another camera's sequence: imported under one circle, then scored.
    fs::create_directories(fs::path(dir) / "PHOTOS");
    for (int m = 0; m < 8; ++m) {
        char name[64];
        std::snprintf(name, sizeof name, "/2020-08-12_12_%02d.jpg", m);
        const std::string renamed = "IMG_20200812_12" + std::string(name + 15, 2) + "00.jpg";
        fs::copy_file(test::shared_path("skies/mobotix_sophia_20200812_morning/images") + name,
                      fs::path(dir) / "PHOTOS" / renamed);
    }
    r = in_folder(dir, "sky import PHOTOS/ --lat 48.85 --lon=2.35 --utc-offset 2 -o SKIES/ --sky-res 64");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("imported 8 of 8 photographs into SKIES/ "), std::string::npos) << r.output;
    r = in_folder(dir,
                  "sky evaluate --photos SKIES/ --out eval/eval.md --import-res 64 --resolutions 64 --horizons 1,2 -q");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(non_empty(fs::path(dir) / "eval" / "eval.md"));
}

TEST(ReadmeCommands, InstalledProgramFindsItsScenesAndModels) {
    const std::string dir = test::temp_dir("readme_install");
    const std::string prefix = dir + "/prefix";
    auto r = test::run_command(std::string("'") + CMAKE_COMMAND_PATH + "' --install '" + DYNSKY_BUILD_DIR +
                               "' --prefix '" + prefix + "' 2>&1");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    ASSERT_TRUE(fs::exists(prefix + "/bin/dynsky"));
    EXPECT_TRUE(fs::exists(prefix + "/share/dynsky/scenes/tower/tower.gltf"));
    EXPECT_TRUE(fs::exists(prefix + "/share/dynsky/networks/models/advect_residual/model.onnx"));
    EXPECT_TRUE(fs::exists(prefix + "/share/dynsky/sky/data/hosek-wilkie"));
    fs::create_directories(dir + "/elsewhere");
    r = test::run_command("cd '" + dir + "/elsewhere' && '" + prefix +
                          "/bin/dynsky' animate scenes/tower/tower.gltf --sky clear --sky-res 32 --duration 0.5 --fps 2"
                          " --res 16x9 --spp 1 --no-video --out a 2>&1");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    // The scene came from the installed share/dynsky, found beside the program.
    EXPECT_NE(r.output.find(prefix + "/share/dynsky/scenes/tower/tower.gltf"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace dynsky
