// End-to-end tests of `dynsky sky predict | evaluate | training-data`.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <vector>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "motion/cloud_model.h"
#include "sky/preset_import.h"
#include "sky/fisheye.h"
#include "sky/latlong.h"
#include "sky/procedural_clouds.h"
#include "sky/sky_image.h"
#include "sky/sun_position.h"
#include "tests/test_support.h"
#include "util/data_path.h"
#include "util/image.h"

namespace dynsky {
namespace {

namespace fs = std::filesystem;

std::string dynsky(const std::string& args) { return std::string(DYNSKY_EXE) + " " + args; }
std::string shipped_model() { return data_path("networks/models/arm_tsi"); }

std::string small_sky(const std::string& dir, int n) {
    ProceduralSkyParams p;
    p.seed = 4;
    p.clear_sky.sun_direction = fisheye::direction_from_angles(0.8, 2.0);
    SkyImage sky = render_procedural_sky(p, 0.0, n);
    std::string path = dir + "/in.exr";
    save_sky(path, sky);
    return path;
}

using test::read_text;

TEST(SkyModelCli, PredictWritesStepsAndStats) {
    const std::string dir = test::temp_dir("predict");
    const std::string in = small_sky(dir, 48);
    auto r = test::run_command(dynsky("sky predict --quiet --model " + shipped_model() + " --in " + in +
                                      " --steps 4 --every 2 --out " + dir + "/out --stats " + dir + "/stats.csv"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_FALSE(fs::exists(dir + "/out/step_0001.exr"));
    ASSERT_TRUE(fs::exists(dir + "/out/step_0002.exr"));
    ASSERT_TRUE(fs::exists(dir + "/out/step_0004.exr"));
    SkyImage s4 = load_sky(dir + "/out/step_0004.exr");
    EXPECT_EQ(s4.resolution, 48);
    EXPECT_DOUBLE_EQ(s4.time_seconds, 4 * 30.0);
    std::ifstream f(dir + "/stats.csv");
    std::string header, line;
    std::getline(f, header);
    EXPECT_EQ(header.rfind("step,time_s,mean_luminance", 0), 0u) << header;
    int rows = 0;
    while (std::getline(f, line)) {
        ++rows;
        EXPECT_EQ(line.substr(line.rfind(',') + 1), "0") << "non-finite pixels in " << line;
    }
    EXPECT_EQ(rows, 5);  // step 0 (the input) and 4 steps

    // A shorter prediction into the same folder leaves none of the earlier one's steps (they read
    // as this sky's future: `animate --sky` took the stale step 4 as its last frame); a file of the
    // user's that happens to be named as a step is left, said (it was deleted too).
    std::ofstream(dir + "/out/step_0003.png") << "my holiday photo";
    std::ofstream(dir + "/out/steps.txt") << "not a step";
    r = test::run_command(dynsky("sky predict --model advect --in " + in + " --steps 2 --out " + dir + "/out"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(fs::exists(dir + "/out/step_0001.exr"));
    EXPECT_TRUE(fs::exists(dir + "/out/step_0002.exr"));
    EXPECT_TRUE(fs::exists(dir + "/out/step_0003.png"));
    EXPECT_NE(r.output.find("step_0003.png is named as a step but is not a sky dynsky wrote: left as it is"),
              std::string::npos)
        << r.output;
    EXPECT_FALSE(fs::exists(dir + "/out/step_0003.exr"));
    EXPECT_FALSE(fs::exists(dir + "/out/step_0004.exr"));
    EXPECT_TRUE(fs::exists(dir + "/out/steps.txt"));
    // (Both of its step files go before the first step is written: a run stopped midway left the
    // earlier run's later steps after its own.)
    EXPECT_NE(r.output.find("removed 2 step file(s) of an earlier prediction"), std::string::npos) << r.output;
    // One this run would write over is refused, untouched.
    std::ofstream(dir + "/out/step_0001.exr") << "my notes";
    r = test::run_command(dynsky("sky predict --model advect --in " + in + " --steps 2 --out " + dir + "/out"));
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("step_0001.exr: is not a sky dynsky wrote"), std::string::npos) << r.output;
    std::ifstream notes(dir + "/out/step_0001.exr");
    std::string kept;
    std::getline(notes, kept);
    EXPECT_EQ(kept, "my notes");
    fs::remove(dir + "/out/step_0001.exr");

    // Continued from its own last step into the same folder: its inputs stay (they were removed
    // as stale steps), the rest of the earlier run's steps go.
    r = test::run_command(dynsky("sky predict --model advect --in " + in + " --steps 4 --out " + dir + "/cont -q"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    r = test::run_command(dynsky("sky predict --model advect --in " + dir + "/cont/step_0004.exr --prev " + dir +
                                 "/cont/step_0003.exr --steps 2 --out " + dir + "/cont"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(fs::exists(dir + "/cont/step_0004.exr"));
    EXPECT_TRUE(fs::exists(dir + "/cont/step_0003.exr"));
    EXPECT_TRUE(fs::exists(dir + "/cont/step_0002.exr"));  // written again, by this run

    // A previous frame when neither file says when it was taken: one medium step, said.
    r = test::run_command(dynsky("sky predict --model advect --in " + in + " --prev " + in + " --steps 1 --out " + dir +
                                 "/prev"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("says when it was taken (no clock, no recorded time): taken one medium step"),
              std::string::npos)
        << r.output;
    // With the network, what share of its correction the pair supports is said (a sky that did not
    // change supports next to none of it).
    r = test::run_command(dynsky("sky predict --model " + data_path("networks/models/advect_residual") + " --in " + in +
                                 " --prev " + in + " --steps 1 --out " + dir + "/prevnet"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const size_t said = r.output.find(" % of the network's correction; the first step takes that much");
    ASSERT_NE(said, std::string::npos) << r.output;
    const size_t number = r.output.rfind("supports ", said);
    ASSERT_NE(number, std::string::npos) << r.output;
    EXPECT_LT(std::stod(r.output.substr(number + 9, said - number - 9)), 10.0) << r.output;
    fs::remove_all(dir);
}

// A 2:1 lat-long HDRI (as downloaded) is taken as render takes it: its upper half, converted to the
// canonical fisheye. The prediction equals the one from that fisheye (written by sky latlong and
// read back the same way).
// A clear all-sky photograph whose camera clipped a wide glare around the sun (WSISEG 077, 2.4 %
// cloud by its human mask), imported at a time and place: under the default wind its glare was read
// as cloud beside the sun, carried onto it, and put the sun out for 14 of 40 steps (the sky's mean
// to 0.46), and it moved as a hard white blob. The glare and its halo now stay with the sun.
TEST(SkyModelCli, AClearPhotographsGlareStaysWithItsSun) {
    DYNSKY_REQUIRE_SHARED();
    const std::string dir = test::temp_dir("predict_glare");
    auto r = test::run_command(dynsky("sky import " + test::shared_path("skies/wsiseg/images/ASC100-1006_077.png") +
                                      " --sky-res 128 --lat 30.53 --lon 114.36 --time 2018-06-01T08:00:00Z -q -o " +
                                      dir + "/w.exr"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    r = test::run_command(dynsky("sky predict --sky " + dir + "/w.exr --steps 40 --every 40 -q --stats " + dir +
                                 "/s.csv -o " + dir + "/p"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    std::istringstream csv(read_text(dir + "/s.csv"));
    std::string line;
    std::getline(csv, line);
    double start = -1;
    int out = 0, steps = 0;
    while (std::getline(csv, line)) {
        const double mean = std::stod(line.substr(line.find(',', line.find(',') + 1) + 1));
        if (start < 0) start = mean;
        else ++steps, out += mean < 0.7 * start;
    }
    ASSERT_EQ(steps, 40);
    EXPECT_LE(out, 4) << "steps with the sun out (the sky's mean under 0.7 of the start)";
    fs::remove_all(dir);
}

TEST(SkyModelCli, PredictTakesALatLongHdriAsRenderDoes) {
    const std::string dir = test::temp_dir("predict_latlong");
    const std::string in = small_sky(dir, 96);  // a lat-long 192 x 96: a fisheye of 96 (the model's 64 at least)
    auto r = test::run_command(dynsky("sky latlong " + in + " -o " + dir + "/ll.exr"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    std::shared_ptr<SkyImage> ground;
    const SkyImage upper = load_sky_or_latlong(dir + "/ll.exr", &ground);
    ASSERT_TRUE(ground);
    save_sky(dir + "/upper.exr", upper);
    for (const std::string name : {"ll", "upper"}) {
        r = test::run_command(dynsky("sky predict --quiet --in " + dir + "/" + name + ".exr --steps 2 --out " + dir +
                                     "/" + name + "_out"));
        ASSERT_EQ(r.exit_code, 0) << r.output;
    }
    const SkyImage a = load_sky(dir + "/ll_out/step_0002.exr"), b = load_sky(dir + "/upper_out/step_0002.exr");
    ASSERT_EQ(a.resolution, b.resolution);
    EXPECT_EQ(a.rgb, b.rgb);
    // --sky-res: the HDRI moves at the size asked for, and says so.
    r = test::run_command(dynsky("sky predict --in " + dir + "/ll.exr --sky-res 80 --steps 1 --out " + dir + "/at80"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("moves, as a 80 x 80 fisheye"), std::string::npos) << r.output;
    EXPECT_EQ(load_sky(dir + "/at80/step_0001.exr").resolution, 80);
    fs::remove_all(dir);
}

// A sky in other units than the models' (an EXR scaled by hand, a relative HDRI) moves as the same
// sky at scale does and keeps its units: a clear sky x 3 lost its sun in one step and x 1e-6 came out
// 1400 times too bright (motion/radiance_scale.h). Also through animate's timeline.
// A sky file's --time given without its place (Paris by default), or of another day, moved the sun
// the file records to the clock's without a word: the clear sky lit from the west while the
// photograph's light came from the east. Said where they are more than 3 degrees apart.
TEST(SkyModelCli, ASunTheClockMovesFarFromTheFilesIsTold) {
    const std::string dir = test::temp_dir("sun_conflict");
    auto r = test::run_command(dynsky(
        "sky clear --lat 48.8566 --lon 2.3522 --time 2026-06-21T16:00:00Z --sky-res 32 -q -o " + dir + "/paris.exr"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::string timeline = "sky timeline --sky " + dir + "/paris.exr --duration 30 --model advect -o " + dir;
    r = test::run_command(dynsky(timeline + "/a --time 2026-06-21T08:00:00Z 2>&1"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("records its sun"), std::string::npos) << r.output;
    // A warning, said under -q too (farm runs use -q; it was silenced with the reports).
    r = test::run_command(dynsky(timeline + "/aq -q --time 2026-06-21T08:00:00Z 2>&1"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("records its sun"), std::string::npos) << r.output;
    r = test::run_command(dynsky(timeline + "/b --time 2026-06-21T16:00:00Z 2>&1"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(r.output.find("records its sun"), std::string::npos) << r.output;
    {
        // At its own time and place, a sun the import put where the photograph shows it (12 degrees
        // off: a camera whose north is off) is said as such; the advice to give its time and place
        // was what the user had done.
        SkyImage placed = load_sky(dir + "/paris.exr");
        const Vec3 s = *placed.sun_direction;
        const float c = std::cos(0.21f), sn = std::sin(0.21f);
        placed.sun_direction = Vec3(c * s.x() - sn * s.z(), s.y(), sn * s.x() + c * s.z());
        save_sky(dir + "/placed.exr", placed);
        r = test::run_command(dynsky("sky timeline --sky " + dir +
                                     "/placed.exr --duration 30 --model advect --lat 48.8566 --lon 2.3522 "
                                     "--time 2026-06-21T16:00:00Z -o " +
                                     dir + "/c 2>&1"));
        ASSERT_EQ(r.exit_code, 0) << r.output;
        EXPECT_NE(r.output.find("from the sun of its own time at --lat and --lon: the place is not the sky's, or "
                                "its sun was put where its photograph shows it"),
                  std::string::npos)
            << r.output;
    }
    // A sky that records no sun but shows one (a downloaded HDRI): its sun moved 65 degrees to the
    // clock's with only a note; now a warning, as for a recorded sun.
    SkyImage bare = load_sky(dir + "/paris.exr");
    bare.sun_direction.reset();
    bare.has_clock = false;
    save_sky(dir + "/bare.exr", bare);
    const std::string bare_timeline = "sky timeline --sky " + dir + "/bare.exr --duration 30 --model advect -o " + dir;
    r = test::run_command(dynsky(bare_timeline + "/c --time 2026-06-21T08:00:00Z 2>&1"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("records no sun but shows one"), std::string::npos) << r.output;
    r = test::run_command(dynsky(bare_timeline + "/d --time 2026-06-21T16:00:00Z 2>&1"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(r.output.find("records no sun but shows one"), std::string::npos) << r.output;
    fs::remove_all(dir);
}

TEST(SkyModelCli, SkiesInOtherUnitsMoveAsAtScaleAndKeepTheirUnits) {
    const std::string dir = test::temp_dir("predict_units");
    auto r = test::run_command(
        dynsky("sky clear --lat 48.85 --lon 2.35 --time 2026-06-21T12:00:00Z --sky-res 64 -q -o " + dir + "/x1.exr"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const SkyImage at_scale = load_sky(dir + "/x1.exr");
    const std::vector<std::pair<std::string, float>> units = {{"x1", 1.0f}, {"x3", 3.0f}, {"tiny", 1e-6f}};
    for (const auto& [name, factor] : units) {
        SkyImage s = at_scale;
        for (float& v : s.rgb) v *= factor;
        save_sky(dir + "/" + name + ".exr", s);
        r = test::run_command(dynsky("sky predict --in " + dir + "/" + name +
                                     ".exr --wind-from 250 --wind-speed 8 "
                                     "--steps 2 --out " +
                                     dir + "/" + name + "_out"));
        ASSERT_EQ(r.exit_code, 0) << r.output;
        if (factor != 1.0f) {
            EXPECT_NE(r.output.find("clear-sky model's radiance"), std::string::npos) << r.output;
        }
        r = test::run_command(dynsky("animate builtin --sky " + dir + "/" + name +
                                     ".exr --model advect --duration 40 "
                                     "--fps 0.05 --res 16x9 --spp 2 --no-video -q --out " +
                                     dir + "/" + name + "_anim"));
        ASSERT_EQ(r.exit_code, 0) << r.output;
    }
    const SkyImage one = load_sky(dir + "/x1_out/step_0002.exr");
    const Image frame = read_image(dir + "/x1_anim/frame_0001.exr");
    for (const auto& [name, factor] : units) {
        const SkyImage step = load_sky(dir + "/" + name + "_out/step_0002.exr");
        ASSERT_EQ(step.rgb.size(), one.rgb.size());
        double worst = 0;
        for (size_t k = 0; k < one.rgb.size(); ++k)
            worst = std::max(worst, std::abs(double(step.rgb[k]) / factor - one.rgb[k]) / (1e-3 + one.rgb[k]));
        EXPECT_LT(worst, 1e-4) << name;  // the same sky, sun and all, in its own units
        const Image f = read_image(dir + "/" + name + "_anim/frame_0001.exr");
        double frame_worst = 0;
        for (size_t k = 0; k < frame.pixels.size(); ++k)
            frame_worst = std::max(frame_worst,
                                   std::abs(double(f.pixels[k]) / factor - frame.pixels[k]) / (1e-3 + frame.pixels[k]));
        EXPECT_LT(frame_worst, 1e-3) << name;  // animate's frame 20 s in (between the first two medium steps)
    }
    // compare's clear reference is in the sky's units too (it was in the models' own: clear 914 against
    // cloudy 0.914 lx/100 for a sky x 1e-3).
    auto clear_illuminance = [&](const std::string& name) {
        auto r = test::run_command(dynsky("compare builtin --sky " + dir + "/" + name +
                                          ".exr --model advect "
                                          "--duration 20 --chart-frames 2 --res 16x9 --spp 1 --chart-res 16x9 "
                                          "--chart-spp 1 -q -o " +
                                          dir + "/" + name + "_cmp"));
        EXPECT_EQ(r.exit_code, 0) << r.output;
        std::istringstream csv(read_text(dir + "/" + name + "_cmp/illuminance.csv"));
        std::string header, row;
        std::getline(csv, header), std::getline(csv, row);
        const size_t a = row.find(','), b = row.find(',', a + 1);
        return std::make_pair(std::stod(row.substr(a + 1, b - a - 1)), std::stod(row.substr(b + 1)));
    };
    const auto [clear1, cloudy1] = clear_illuminance("x1");
    const auto [clear_tiny, cloudy_tiny] = clear_illuminance("tiny");
    EXPECT_NEAR(cloudy_tiny / cloudy1, 1e-6, 1e-9);
    EXPECT_NEAR(clear_tiny / cloudy_tiny, clear1 / cloudy1, 0.02 * clear1 / cloudy1);
    fs::remove_all(dir);
}

// A previous frame minutes before the sky measures too little motion (the clouds changed shape in
// between): said, with what to give instead; a frame 30 s before is not.
TEST(SkyModelCli, APreviousFrameMinutesBeforeIsWarnedAboutAFolderIsASequence) {
    const std::string dir = test::temp_dir("predict_gap");
    for (const char* t : {"12:00:00", "12:04:30", "12:05:00"})
        ASSERT_EQ(test::run_command(dynsky(std::string("sky clear --lat 36.6 --lon -97.5 --time 2026-06-21T") + t +
                                           "Z --sky-res 32 -q -o " + dir + "/" + std::string(t).substr(3, 2) + ".exr"))
                      .exit_code,
                  0);
    auto r = test::run_command(dynsky("sky predict --model advect --in " + dir + "/05.exr --prev " + dir +
                                      "/00.exr --steps 1 --out " + dir + "/a"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("is 300 s before"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("--wind-from"), std::string::npos) << r.output;
    r = test::run_command(dynsky("sky predict --model advect --in " + dir + "/05.exr --prev " + dir +
                                 "/04.exr --steps 1 --out " + dir + "/b"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(r.output.find("warning"), std::string::npos) << r.output;
    // The folder of the three, as animate takes a captured sequence: on from its last sky with the
    // one before it (it was "is a directory, not an image").
    r = test::run_command(dynsky("sky predict --model advect --in " + dir + " --steps 1 --out " + dir + "_c"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(
        r.output.find("moving on from its last sky, 05.exr, with the one before it as the previous frame: 04.exr"),
        std::string::npos)
        << r.output;
    EXPECT_EQ(load_sky(dir + "_c/step_0001.exr").rgb, load_sky(dir + "/b/step_0001.exr").rgb);
    // With a wind given, animate (as predict) moves the folder's last sky with it, not with the
    // previous frame (the wind was dropped without a word); with --prev as well, refused.
    const std::string tiny = " --res 8x6 --spp 1 --duration 1 --fps 1 --no-video -o " + dir + "_d";
    r = test::run_command(dynsky("animate builtin --sky " + dir + " --wind-from 200 --wind-speed 10" + tiny));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("moving on from its last sky, 05.exr"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("previous frame"), std::string::npos) << r.output;
    r = test::run_command(dynsky("animate builtin --sky " + dir + "/05.exr --prev " + dir + "/04.exr --wind-speed 3" +
                                 tiny));
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("give one source of motion"), std::string::npos) << r.output;
    fs::remove_all(dir + "_d");
    fs::remove_all(dir + "_c");
    fs::remove_all(dir);
}

// A missing model folder is a file error (1) and a mistyped choice a usage error (2), the same in
// every command that takes --model (animate said "usage error" for a missing folder).
TEST(SkyModelCli, AMissingModelIsTheSameErrorInEveryCommand) {
    const std::string dir = test::temp_dir("model_missing");
    const std::string in = small_sky(dir, 32);
    const std::vector<std::string> commands = {"sky predict --in " + in + " --steps 1 --out " + dir + "/p.exr",
                                               "animate --sky " + in + " --count-frames --out " + dir + "/a",
                                               "sky timeline --sky " + in + " --duration 20 --out " + dir + "/t"};
    for (const auto& c : commands) {
        auto r = test::run_command(dynsky(c + " --model " + dir + "/no_model 2>&1"));
        EXPECT_EQ(r.exit_code, 1) << c << "\n" << r.output;
        EXPECT_NE(r.output.find("no_model: model folder not found"), std::string::npos) << c << "\n" << r.output;
        r = test::run_command(dynsky(c + " --model advekt 2>&1"));
        EXPECT_EQ(r.exit_code, 2) << c << "\n" << r.output;
        EXPECT_NE(r.output.find("--model 'advekt': expected auto, advect, paper"), std::string::npos) << c << "\n"
                                                                                                      << r.output;
    }
    EXPECT_FALSE(fs::exists(dir + "/p.exr"));
    EXPECT_FALSE(fs::exists(dir + "/t"));
    fs::remove_all(dir);
}

TEST(SkyModelCli, PredictBadInputsFailClearlyAndWriteNothing) {
    const std::string dir = test::temp_dir("predict_bad");
    const std::string in = small_sky(dir, 32);
    auto r = test::run_command(dynsky("sky predict --model " + dir + "/no_model --in " + in + " --out " + dir + "/o1"));
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.output.find("no_model: model folder not found"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir + "/o1"));
    r = test::run_command(dynsky("sky predict --model " + shipped_model() + " --in " + dir + "/missing.exr --out " +
                                 dir + "/o2"));
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.output.find("missing.exr"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir + "/o2"));
    r = test::run_command(dynsky("sky predict --model " + shipped_model() + " --in " + in + " --steps 0 --out " + dir +
                                 "/o3"));
    EXPECT_EQ(r.exit_code, 2);  // a bad option value: usage error
    EXPECT_NE(r.output.find("--steps"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir + "/o3"));
    // --model as animate and sky timeline spell it: network:FOLDER is the folder (it was "model folder
    // not found"); their flow and procedural models need their skies: a usage error saying so.
    r = test::run_command(dynsky("sky predict --quiet --model network:" + shipped_model() + " --in " + in +
                                 " --steps 1 --out " + dir + "/o4"));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    r = test::run_command(dynsky("sky predict --model flow --in " + in + " --steps 1 --out " + dir + "/o5"));
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("--model flow: a model of the moving sky of 'animate'"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir + "/o5"));
    fs::remove_all(dir);
}

// A folder of `count` consecutive ARM photographs (links), skipping the frames in `skip`.
std::string photo_folder(const std::string& dir, int count, std::vector<int> skip = {}, int first = 100,
                         const std::string& sequence = "arm_tsi_sgp_20170524") {
    const std::string src = test::shared_path("skies/" + sequence + "/images");
    std::vector<fs::path> all;
    for (const auto& e : fs::directory_iterator(src)) all.push_back(e.path());
    std::sort(all.begin(), all.end());
    fs::create_directories(dir);
    for (int k = 0; k < count; ++k)
        if (std::find(skip.begin(), skip.end(), k) == skip.end())
            fs::create_symlink(all[size_t(first + k)], fs::path(dir) / all[size_t(first + k)].filename());
    return dir;
}


// The PSNR of each (resolution, horizon, method) in an evaluation's CSV.
std::map<std::string, double> evaluation_psnr(const std::string& csv_path) {
    std::map<std::string, double> psnr;
    std::stringstream csv(read_text(csv_path));
    std::string line;
    std::getline(csv, line);
    while (std::getline(csv, line)) {
        std::vector<std::string> f;
        std::stringstream ls(line);
        for (std::string x; std::getline(ls, x, ',');) f.push_back(x);
        if (f.size() == 8u) psnr[f[0] + "/" + f[1] + "/" + f[3]] = std::stod(f[4]);
    }
    return psnr;
}

TEST(SkyModelCli, EvaluateScoresAnyFolderOfPhotosWithEveryMethod) {
    DYNSKY_REQUIRE_SHARED();
    const std::string dir = test::temp_dir("evaluate");
    const std::string photos = photo_folder(dir + "/photos", 6);
    auto r = test::run_command(dynsky("sky evaluate --quiet --model advect --no-paper --photos " + photos +
                                      " --preset arm-tsi --horizons 1,2 --resolutions 64 --out " + dir + "/eval.md"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::string md = read_text(dir + "/eval.md");
    EXPECT_NE(md.find("| 1 | 30 s |"), std::string::npos) << md;
    EXPECT_NE(md.find("| 2 | 60 s |"), std::string::npos) << md;
    for (const char* m : {"persistence PSNR", "farneback PSNR", "farneback-linear PSNR", "advect+prev PSNR",
                          "model+prev PSNR", "advect+wind PSNR", "model+wind PSNR",
                          "One step ahead (the paper's table)", "| 64 | farneback |", "model+wind beats advect+wind"})
        EXPECT_NE(md.find(m), std::string::npos) << m << "\n" << md;
    EXPECT_EQ(md.find("nan"), std::string::npos) << md;
    // Six frames, horizons up to 2: start frames 1..3 (each needs the previous frame and two after).
    EXPECT_NE(md.find("start frames 1..3"), std::string::npos) << md;
    // The clouds of the ARM day move: any motion estimate beats persistence one step ahead.
    const auto psnr = evaluation_psnr(dir + "/eval.csv");
    ASSERT_EQ(psnr.size(), 2u * 7u);  // 2 horizons x 7 methods at 64 px
    EXPECT_GT(psnr.at("64/1/farneback"), psnr.at("64/1/persistence") + 1.0);
    EXPECT_NEAR(psnr.at("64/1/farneback"), psnr.at("64/1/farneback-linear"), 1e-9);  // one step: the same warp
    EXPECT_NE(psnr.at("64/2/farneback"), psnr.at("64/2/farneback-linear"));
    EXPECT_GT(psnr.at("64/1/model+wind"), psnr.at("64/1/persistence") + 1.0);
    // Photographs 10 s apart: the paper's model (30 s steps) is not scored, and the report says why
    // (it was said on stderr only, hidden by --quiet: the report had no paper column and no word).
    std::vector<fs::path> list;
    for (const auto& e : fs::directory_iterator(photos)) list.push_back(e.path());
    std::sort(list.begin(), list.end());
    fs::create_directories(dir + "/fast");
    for (size_t k = 0; k < list.size() && k < 6; ++k)
        fs::create_symlink(fs::read_symlink(list[k]),
                           dir + "/fast/tsi_sgpC1_201705241600" + std::to_string(k) + "0Z.jpg");
    r = test::run_command(dynsky("sky evaluate --quiet --model advect --photos " + dir +
                                 "/fast --preset arm-tsi --horizons 1 --resolutions 64 --out " + dir + "/fast.md"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(read_text(dir + "/fast.md")
                  .find("the paper's model steps 30 s, which does not divide the photographs' "
                        "cadence of 10 s: not scored"),
              std::string::npos)
        << read_text(dir + "/fast.md");
    fs::remove_all(dir);
}

// Another camera's photographs are imported with `sky import` (its own options) and evaluated as a
// folder of skies, no preset: the same scores as the preset's photographs, frames ordered by the
// photograph's time the import recorded (their names here carry none), filled pixels left out.
TEST(SkyModelCli, EvaluateScoresAFolderOfImportedSkiesAsItsPhotographs) {
    DYNSKY_REQUIRE_SHARED();
    const std::string dir = test::temp_dir("evaluate_skies");
    const std::string photos = photo_folder(dir + "/photos", 6);
    std::vector<fs::path> list;
    for (const auto& e : fs::directory_iterator(photos)) list.push_back(e.path());
    std::sort(list.begin(), list.end());
    fs::create_directories(dir + "/skies");
    for (size_t k = 0; k < list.size(); ++k) {
        // Named against their order (frame_5 is the first), so only the recorded time can order them.
        const std::string stem = dir + "/skies/frame_" + std::to_string(list.size() - 1 - k);
        // Sequences fill non-sky pixels smoothly (the same from frame to frame); `sky import`
        // does so with --fill smooth.
        auto r = test::run_command(dynsky("sky import --quiet --fill smooth --preset arm-tsi --sky-res 256 " +
                                          list[k].string() + " -o " + stem + ".exr --filled-mask " + stem +
                                          ".filled.png"));
        ASSERT_EQ(r.exit_code, 0) << r.output;
    }
    const std::string common = " --quiet --model advect --no-paper --horizons 1,2 --resolutions 64,256 --out ";
    auto r = test::run_command(dynsky("sky evaluate --photos " + photos + " --preset arm-tsi" + common + dir +
                                      "/photos.md"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    r = test::run_command(dynsky("sky evaluate --photos " + dir + "/skies" + common + dir + "/skies.md"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(read_text(dir + "/skies.md").find("every 30 s, imported skies"), std::string::npos);
    EXPECT_NE(read_text(dir + "/skies.md").find("every sky's filled pixels (STEM.filled.png) left out"),
              std::string::npos);
    const auto from_photos = evaluation_psnr(dir + "/photos.csv"), from_skies = evaluation_psnr(dir + "/skies.csv");
    ASSERT_EQ(from_photos.size(), 2u * 2u * 7u);  // 2 resolutions x 2 horizons x 7 methods
    ASSERT_EQ(from_skies.size(), from_photos.size());
    for (const auto& [key, psnr] : from_photos) {
        ASSERT_TRUE(from_skies.count(key)) << key;
        // The same frames in half-float EXRs; frames out of order would lose several dB.
        EXPECT_NEAR(from_skies.at(key), psnr, 0.15) << key;
    }
    // Without the masks of filled pixels the filled arm and band are scored too: not the same.
    for (const auto& e : fs::directory_iterator(dir + "/skies"))
        if (e.path().string().find(".filled.png") != std::string::npos) fs::remove(e.path());
    // (A report named with a space and a '#': its chart links are encoded, the charts beside it.)
    r = test::run_command(dynsky("sky evaluate --photos " + dir + "/skies" + common + "'" + dir + "/un masked#.md'"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(read_text(dir + "/un masked#.md").find("](un%20masked%23_64.png)"), std::string::npos);
    EXPECT_TRUE(fs::exists(dir + "/un masked#_64.png"));
    fs::rename(dir + "/un masked#.md", dir + "/unmasked.md");
    fs::rename(dir + "/un masked#.csv", dir + "/unmasked.csv");
    EXPECT_NE(evaluation_psnr(dir + "/unmasked.csv").at("256/1/persistence"), from_photos.at("256/1/persistence"));
    EXPECT_NE(read_text(dir + "/unmasked.md").find("no STEM.filled.png beside the skies"), std::string::npos);
    // A photograph among the skies would be left out unseen: refused, named.
    fs::copy_file(list[0], dir + "/skies/" + list[0].filename().string());
    r = test::run_command(dynsky("sky evaluate --photos " + dir + "/skies" + common + dir + "/mixed.md 2>&1"));
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find(list[0].filename().string() + ": is a photograph among imported skies"), std::string::npos)
        << r.output;
    fs::remove(dir + "/skies/" + list[0].filename().string());
    // Skies smaller than the import resolution, and skies that carry no time, are refused naming a file.
    r = test::run_command(dynsky("sky evaluate --photos " + dir + "/skies --import-res 512" + common + dir +
                                 "/big.md 2>&1"));
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.output.find("smaller than --import-res 512"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("frame_"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir + "/big.md"));
    r = test::run_command(dynsky("sky procedural --quiet --sky-res 64 --duration 20 -o " + dir + "/procedural"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    r = test::run_command(dynsky("sky evaluate --photos " + dir +
                                 "/procedural --import-res 64 --resolutions 64 --quiet --model advect --out " + dir +
                                 "/procedural.md 2>&1"));
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.output.find("carries no time"), std::string::npos) << r.output;
    fs::remove_all(dir);
}

// Which frames count as held out is decided by the photographs, never by a folder's name: a copy of
// the shipped model's training frames in a folder named after another of its sequences was scored
// as "held-out frames of the model's split.json", and a folder of any other name as "not trained on".
TEST(SkyModelCli, EvaluateNeverScoresTheModelsTrainingFramesAsHeldOut) {
    DYNSKY_REQUIRE_SHARED();
    const std::string dir = test::temp_dir("evaluate_trained");
    const std::string common = " --quiet --no-paper --preset arm-tsi --horizons 1 --resolutions 64 --out ";
    for (const char* name : {"/arm_dusk", "/mine"}) {
        const std::string photos = photo_folder(dir + name, 5);  // ARM day frames 100-104: trained on
        auto r = test::run_command(dynsky("sky evaluate --photos " + photos + common + dir + "/t.md 2>&1"));
        EXPECT_EQ(r.exit_code, 1) << r.output;
        EXPECT_NE(r.output.find("nothing held out to score"), std::string::npos) << r.output;
        EXPECT_NE(r.output.find("arm_tsi frames"), std::string::npos) << r.output;
        EXPECT_FALSE(fs::exists(dir + "/t.md"));
        // Scored anyway when asked, and said so.
        r = test::run_command(dynsky("sky evaluate --frames 1-2 --photos " + photos + common + dir + "/f.md"));
        ASSERT_EQ(r.exit_code, 0) << r.output;
        EXPECT_NE(read_text(dir + "/f.md").find("predicting frames the model was trained on"), std::string::npos);
    }
    // The shipped split names its photographs and their times: found without the shared data too.
    {
        const std::string photos = dir + "/mine";
        auto r = test::run_command(dynsky("sky evaluate --shared " + dir + "/nowhere --photos " + photos + common +
                                          dir + "/n.md 2>&1"));
        EXPECT_EQ(r.exit_code, 1) << r.output;
        EXPECT_NE(r.output.find("nothing held out to score"), std::string::npos) << r.output;
    }
    // A split of frame numbers only (made before 2026-12-07) needs the training photographs: without
    // them (a wrong --shared) it cannot tell, and says so in the report.
    const std::string legacy = dir + "/legacy_model";
    fs::create_directories(legacy);
    for (const char* f : {"model.json", "model.onnx"})
        fs::copy_file(data_path("networks/models/advect_residual/" + std::string(f)), legacy + "/" + f);
    std::ofstream(legacy + "/split.json") << R"({"arm_tsi": {"train": [0, 240], "heldout": [240, 300], "dt_s": 30.0}})";
    {
        const std::string photos = dir + "/mine";
        auto r = test::run_command(dynsky("sky evaluate --model " + legacy + " --shared " + dir + "/nowhere --photos " +
                                          photos + common + dir + "/u.md 2>&1"));
        ASSERT_EQ(r.exit_code, 0) << r.output;
        EXPECT_NE(r.output.find("warning: the model was trained on"), std::string::npos) << r.output;
        EXPECT_NE(read_text(dir + "/u.md").find("NOT checked against the model's training photographs"),
                  std::string::npos);
        // The report names the model scored, its folder and its network's bytes (two trainings'
        // reports were headed alike: a researcher's audit).
        EXPECT_NE(read_text(dir + "/u.md").find("Model: `" + legacy + "` (kind advect-residual, 64 px; model.onnx ("),
                  std::string::npos)
            << read_text(dir + "/u.md");
        EXPECT_NE(read_text(dir + "/u.md").find("fnv1a"), std::string::npos);
    }
    // A model trained on a copy of 5 of the day's photographs (frames 100-104; its data set numbers
    // them 0-4): those are found wherever they lie, and the day's first frames, which frame numbers
    // read against the shared sequence took for them, are held out (a researcher's audit: the
    // evaluation scored a model on its own training photographs and called them held out).
    {
        std::string names = "[";
        for (int k = 100; k < 105; ++k) {
            char name[64];
            const int t = 15 * 3600 + 40 * 60 + 30 * k;
            std::snprintf(name, sizeof name, "\"tsi_sgpC1_20170524%02d%02d%02dZ.jpg\"", t / 3600, t / 60 % 60, t % 60);
            names += std::string(k > 100 ? "," : "") + name;
        }
        const double first = utc_seconds("2017-05-24T16:30:00Z"), last = utc_seconds("2017-05-24T16:32:00Z");
        std::ofstream(legacy + "/split.json")
            << R"({"arm_tsi": {"train": [0, 5], "heldout": [5, 6], "dt_s": 30.0, "preset": "arm-tsi", "trained_photos": )"
            << names << R"(], "trained_utc_s": [)" << std::setprecision(17) << first << "," << last << "]}}";
        auto r = test::run_command(dynsky("sky evaluate --model " + legacy + " --photos " + dir + "/mine" + common +
                                          dir + "/c.md 2>&1"));
        EXPECT_EQ(r.exit_code, 1) << r.output;
        EXPECT_NE(r.output.find("arm_tsi frames trained on: 5 of these"), std::string::npos) << r.output;
        // Names without times (a split of a data set built before the times were recorded): the
        // times the names carry find the same photographs under other names (they were scored as
        // held out: a review).
        std::ofstream(legacy + "/split.json")
            << R"({"arm_tsi": {"train": [0, 5], "heldout": [5, 6], "dt_s": 30.0, "preset": "arm-tsi", "trained_photos": )"
            << names << "]}}";
        const std::string renamed = dir + "/renamed";
        fs::create_directories(renamed);
        for (const auto& e : fs::directory_iterator(dir + "/mine"))
            fs::create_symlink(fs::read_symlink(e.path()), renamed + "/site_" + e.path().filename().string());
        r = test::run_command(dynsky("sky evaluate --model " + legacy + " --photos " + renamed + common + dir +
                                     "/n2.md 2>&1"));
        EXPECT_EQ(r.exit_code, 1) << r.output;
        EXPECT_NE(r.output.find("nothing held out to score"), std::string::npos) << r.output;
        const std::string early = photo_folder(dir + "/early", 5, {}, 0);
        r = test::run_command(dynsky("sky evaluate --model " + legacy + " --photos " + early + common + dir + "/e.md"));
        ASSERT_EQ(r.exit_code, 0) << r.output;
        EXPECT_NE(read_text(dir + "/e.md").find("none of them among the model's training photographs"),
                  std::string::npos);
    }
    // The clear morning's last photographs end 30 s before the frames of the broken-cumulus sequence the
    // model was trained on, the same clouds arriving: not held out, though its split says so.
    const std::string before = photo_folder(dir + "/before", 5, {}, 430, "arm_tsi_sgp_20170524_clear_morning");
    auto b = test::run_command(dynsky("sky evaluate --photos " + before + common + dir + "/b.md 2>&1"));
    EXPECT_EQ(b.exit_code, 1) << b.output;
    EXPECT_NE(b.output.find("20 minutes before arm_tsi's frames trained on"), std::string::npos) << b.output;
    // An hour earlier it is.
    const std::string hour = photo_folder(dir + "/hour", 5, {}, 352, "arm_tsi_sgp_20170524_clear_morning");
    b = test::run_command(dynsky("sky evaluate --photos " + hour + common + dir + "/hour.md 2>&1"));
    EXPECT_EQ(b.exit_code, 0) << b.output;
    // The same day's held-out frames (its split holds out 240 on) are scored as such.
    const std::string held_out = photo_folder(dir + "/late", 5, {}, 250);
    auto r = test::run_command(dynsky("sky evaluate --photos " + held_out + common + dir + "/h.md"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(read_text(dir + "/h.md").find("none of them among the model's training photographs"), std::string::npos);
    fs::remove_all(dir);
}

// A rerun replaces the earlier report whole, and only once it has scored: one that fails on a
// photograph it reads midway (here one cut short) keeps the earlier report; it had been removed
// before the photographs were read.
TEST(SkyModelCli, EvaluateKeepsTheEarlierReportUntilItHasScored) {
    const std::string dir = test::temp_dir("evaluate_keeps"), skies = dir + "/skies";
    fs::create_directories(skies);
    for (const char* s : {"00", "30"})
        for (const char* m : {"00", "01", "02"}) {
            const std::string at = std::string("2026-06-21T12:") + m + ":" + s + "Z";
            auto r = test::run_command(dynsky("sky clear --sky-res 64 --lat 48 --lon 2 --time " + at + " -q -o " +
                                              skies + "/s_2026062112" + m + s + "Z.exr"));
            ASSERT_EQ(r.exit_code, 0) << r.output;
        }
    const std::string run = dynsky("sky evaluate --photos " + skies +
                                   " --model advect --no-paper --resolutions 64 --import-res 64 --horizons 1 -q -o " +
                                   dir + "/rep.md 2>&1");
    auto r = test::run_command(run);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::string report = read_text(dir + "/rep.md");
    const std::string last = skies + "/s_20260621120230Z.exr";
    fs::resize_file(last, fs::file_size(last) / 2);
    r = test::run_command(run);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("s_20260621120230Z.exr"), std::string::npos) << r.output;
    EXPECT_EQ(read_text(dir + "/rep.md"), report);
    for (const char* f : {"/rep.csv", "/rep_64.csv", "/rep_64.png"}) EXPECT_TRUE(fs::exists(dir + f)) << f;
    fs::remove_all(dir);
}

TEST(SkyModelCli, EvaluateRejectsFoldersWithoutOneRegularSequence) {
    DYNSKY_REQUIRE_SHARED();
    const std::string dir = test::temp_dir("evaluate_bad");
    fs::create_directories(dir + "/empty");
    struct Case {
        std::string folder, message;
    } cases[] = {
        {dir + "/empty", "no photographs"},
        {dir + "/nowhere", "nowhere: no such folder"},  // said it needed --preset
        {photo_folder(dir + "/gap", 8, {4}), "missing frames"},
        {photo_folder(dir + "/two", 2), "fewer than three photographs"},
    };
    for (const Case& c : cases) {
        auto r = test::run_command(dynsky("sky evaluate --quiet --model advect --photos " + c.folder +
                                          " --preset arm-tsi --out " + dir + "/eval.md 2>&1"));
        EXPECT_EQ(r.exit_code, 1) << c.folder;
        EXPECT_NE(r.output.find(c.message), std::string::npos) << c.folder << ": " << r.output;
        EXPECT_FALSE(fs::exists(dir + "/eval.md")) << c.folder;
    }
    // Five photographs: the default horizons 1, 2, 6 do not fit; 1 and 2 are scored, with a note.
    {
        auto r = test::run_command(
            dynsky("sky evaluate --model advect --no-paper --resolutions 64 --import-res 64 --photos " +
                   photo_folder(dir + "/five", 5) + " --preset arm-tsi --out " + dir + "/five.md 2>&1"));
        EXPECT_EQ(r.exit_code, 0) << r.output;
        EXPECT_NE(r.output.find("holds 5 frames, too few for horizon(s) 6 (h + 2 frames each): scoring 1, 2"),
                  std::string::npos)
            << r.output;
        std::ifstream in(dir + "/five.md");
        const std::string report((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        EXPECT_NE(report.find("| 2 |"), std::string::npos) << report;
        EXPECT_EQ(report.find("| 6 |"), std::string::npos) << report;
        // --frames as animate's: reversed, negative or outside the start frames is a usage error
        // saying which can be scored ("too few frames" before); partly outside is clipped, said.
        for (const std::string frames : {"3-1", "-1", "7-9", "1-2x"}) {
            auto bad = test::run_command(
                dynsky("sky evaluate --model advect --no-paper --resolutions 64 --import-res 64 "
                       "--horizons 1 --photos " +
                       dir + "/five --preset arm-tsi --frames " + frames + " --out " + dir + "/frames.md 2>&1"));
            EXPECT_EQ(bad.exit_code, 2) << frames << ": " << bad.output;
            EXPECT_NE(bad.output.find("--frames '" + frames + "'"), std::string::npos) << bad.output;
            if (frames != "-1" && frames != "1-2x") {
                EXPECT_NE(bad.output.find("are 1-3 (5 frames, horizon 1)"), std::string::npos) << bad.output;
            }
            EXPECT_FALSE(fs::exists(dir + "/frames.md"));
        }
        auto clipped =
            test::run_command(dynsky("sky evaluate --model advect --no-paper --resolutions 64 --import-res 64 "
                                     "--horizons 1 --photos " +
                                     dir + "/five --preset arm-tsi --frames 0-99 --out " + dir + "/frames.md 2>&1"));
        EXPECT_EQ(clipped.exit_code, 0) << clipped.output;
        EXPECT_NE(clipped.output.find("--frames 0-99 scores 1-3"), std::string::npos) << clipped.output;
    }
    // A file whose name carries no time.
    fs::create_directories(dir + "/untimed");
    fs::copy_file(test::shared_path("skies/wsiseg/images/ASC100-1006_001.png"), dir + "/untimed/sky.png");
    auto r = test::run_command(dynsky("sky evaluate --model advect --photos " + dir +
                                      "/untimed --preset arm-tsi 2>&1"));
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.output.find("carries no time"), std::string::npos) << r.output;
    fs::remove_all(dir);
}

TEST(SkyModelCli, EvaluateRejectsBadArguments) {
    auto r = test::run_command(dynsky("sky evaluate --model advect --sequence nowhere"));
    EXPECT_EQ(r.exit_code, 2);  // a bad option value: usage error
    EXPECT_NE(r.output.find("unknown sequence 'nowhere'"), std::string::npos) << r.output;
    r = test::run_command(dynsky("sky evaluate --model advect --sequence arm-tsi --horizons 1,x"));
    EXPECT_EQ(r.exit_code, 2);  // a bad option value: usage error
    EXPECT_NE(r.output.find("--horizons: 'x'"), std::string::npos) << r.output;
    r = test::run_command(dynsky("sky evaluate --model advect"));
    EXPECT_EQ(r.exit_code, 2);  // a bad option value: usage error
    EXPECT_NE(r.output.find("exactly one of --sequence"), std::string::npos) << r.output;
    {
        // A folder of photographs (no skies in it) needs a preset.
        const std::string photos = test::temp_dir("evaluate_no_preset");
        r = test::run_command(dynsky("sky evaluate --model advect --photos " + photos));
        EXPECT_EQ(r.exit_code, 2);  // a bad option value: usage error
        EXPECT_NE(r.output.find("--preset"), std::string::npos) << r.output;
        fs::remove_all(photos);
    }
    r = test::run_command(dynsky("sky evaluate --model advect --sequence arm-tsi --resolutions 100"));
    EXPECT_EQ(r.exit_code, 2);  // a bad option value: usage error
    EXPECT_NE(r.output.find("--resolutions 100"), std::string::npos) << r.output;
    // Below the model's own size: said before any photograph is read (it failed at the first frame
    // scored, "the state is smaller than the network's 64 px").
    r = test::run_command(
        dynsky("sky evaluate --model advect --sequence arm-tsi --resolutions 32 --import-res 32 2>&1"));
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.output.find("--resolutions 32: below the 64 px the model steps at"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("import "), std::string::npos) << r.output;
    {
        // A report asked into a folder (`-o out/`) failed after the whole scoring, with charts
        // left in the folder: refused first.
        const std::string dir = test::temp_dir("evaluate_out_folder");
        r = test::run_command(dynsky("sky evaluate --model advect --sequence arm-tsi -o " + dir + "/out/"));
        EXPECT_EQ(r.exit_code, 2) << r.output;
        EXPECT_NE(r.output.find("a folder; give the report's file"), std::string::npos) << r.output;
        EXPECT_FALSE(fs::exists(dir + "/out"));
        fs::remove_all(dir);
    }
}

// A procedural folder of one frame holds no training pair: said naming the folder (it said only "the
// sequence has fewer than two frames").
TEST(SkyModelCli, TrainingDataFromOneFrameNamesTheFolder) {
    const std::string dir = test::temp_dir("training_one_frame");
    ASSERT_EQ(test::run_command(dynsky("sky procedural --duration 0 --sky-res 64 -q -o " + dir + "/one")).exit_code, 0);
    auto r = test::run_command(dynsky("sky training-data --procedural " + dir +
                                      "/one --import-res 64 --sky-res 16 -q -o " + dir + "/td"));
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find(dir + "/one: the sequence has 1 frame(s)"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir + "/td/manifest.json"));
    fs::remove_all(dir);
}

TEST(SkyModelCli, TrainingDataImportsExactlyAsSkyImport) {
    // The dataset builder imports in-process (it needs the not-sky mask); the sky it sees must be
    // the one `dynsky sky import --preset arm-tsi --fill smooth` writes (sequences are filled
    // smoothly; a single import's default texture fill differs in the filled pixels only).
    DYNSKY_REQUIRE_SHARED();
    const std::string dir = test::temp_dir("import_same");
    const std::string photo = test::shared_path("skies/arm_tsi_sgp_20170524/images/tsi_sgpC1_20170524170000Z.jpg");
    auto r = test::run_command(dynsky("sky import --preset arm-tsi --fill smooth --sky-res 64 " + photo + " --out " +
                                      dir + "/cli.exr"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    SkyImage cli = load_sky(dir + "/cli.exr");
    SkyImage lib = import_preset_photo(photo, "arm-tsi", 64);
    ASSERT_EQ(cli.resolution, lib.resolution);
    double worst = 0;
    for (size_t k = 0; k < cli.rgb.size(); ++k)
        worst = std::max(worst, double(std::abs(cli.rgb[k] - lib.rgb[k])) / (1e-3 + std::abs(lib.rgb[k])));
    EXPECT_LT(worst, 1e-5);  // EXR float round trip
    fs::remove_all(dir);
}

TEST(SkyModelCli, TrainingDataNeedsOneSource) {
    const std::string dir = test::temp_dir("training_data_bad");
    auto r = test::run_command(dynsky("sky training-data --out " + dir + "/o"));
    EXPECT_EQ(r.exit_code, 2);  // a usage error
    EXPECT_NE(r.output.find("exactly one of --sequence"), std::string::npos) << r.output;
    r = test::run_command(dynsky("sky training-data --procedural " + dir + "/none --out " + dir + "/o"));
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.output.find("manifest.json: not found"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir + "/o"));
    fs::remove_all(dir);
}


// --import-res takes the same range in sky evaluate and sky training-data (8..4096 against
// 16..2048 before), refused before any photograph is read.
TEST(SkyModelCli, ImportResolutionHasOneRangeInEveryCommand) {
    const std::string dir = test::temp_dir("import_res_range");
    for (const std::string& c : {"sky evaluate --photos " + dir + " --preset arm-tsi --out " + dir + "/e.md",
                                 "sky training-data --sequence arm-dusk --out " + dir + "/td"})
        for (const std::string v : {"8", "8192"}) {
            auto r = test::run_command(dynsky(c + " --import-res " + v + " 2>&1"));
            EXPECT_EQ(r.exit_code, 2) << c << "\n" << r.output;
            EXPECT_NE(r.output.find("--import-res: '" + v + "' is not a number in 16 .. 4096"), std::string::npos)
                << c << "\n"
                << r.output;
        }
    EXPECT_FALSE(fs::exists(dir + "/e.md"));
    EXPECT_FALSE(fs::exists(dir + "/td"));
    fs::remove_all(dir);
}

}  // namespace
}  // namespace dynsky
