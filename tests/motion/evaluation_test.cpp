#include "motion/evaluation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "sky/clear_sky.h"
#include "sky/sky_image.h"
#include "tests/test_support.h"
#include "util/interrupt.h"

namespace dynsky {
namespace {

namespace fs = std::filesystem;

using test::read_text;

// A run of `sky evaluate` asked to stop (Ctrl-C, SIGTERM: util/interrupt.h) ends after the start
// frame under way and writes the report of the frames it scored, saying so: the same scores as a
// run limited to those frames. Before, the report was written only at the end, and an interrupted
// evaluation of a long folder lost everything. (The request stays set in this test process: no
// other motion test stops on request.)
TEST(Evaluation, AnEvaluationAskedToStopReportsTheFramesItScored) {
    const std::string dir = test::temp_dir("evaluation_stop"), skies = dir + "/skies";
    fs::create_directories(skies);
    for (int k = 0; k < 8; ++k) {  // a clear sky whose sun moves a degree a frame
        ClearSkyParams p;
        const double az = 0.3 + k * 0.0175;
        p.sun_direction = Vec3d(std::cos(az) * 0.6, 0.8, std::sin(az) * 0.6);
        char name[64];
        std::snprintf(name, sizeof name, "/s_20260621120%d%02dZ.exr", k / 2, 30 * (k % 2));
        save_sky(skies + name, make_clear_sky(p, 64, false));
    }
    EvaluationOptions o;
    o.model = "advect", o.photos = skies, o.paper = false, o.quiet = true;
    o.horizons = "1", o.resolutions = "64", o.import_resolution = 64;
    o.report = dir + "/one.md", o.limit = 1;
    const EvaluationResult one = evaluate_cloud_model(o);
    ASSERT_EQ(one.first, 1);
    ASSERT_EQ(one.last, 1);
    o.limit = 0, o.report = dir + "/stopped.md", o.stop_on_request = true;
    request_stop();
    const EvaluationResult stopped = evaluate_cloud_model(o);
    EXPECT_TRUE(stopped_early());
    EXPECT_EQ(stopped.first, 1);
    EXPECT_EQ(stopped.last, 1);  // of 1..6
    const std::string md = read_text(dir + "/stopped.md");
    EXPECT_NE(md.find("STOPPED by an interrupt after start frame 1 of 1..6"), std::string::npos) << md;
    EXPECT_NE(md.find("start frames 1..1"), std::string::npos) << md;
    EXPECT_TRUE(fs::exists(dir + "/stopped.csv"));
    EXPECT_TRUE(fs::exists(dir + "/stopped_64.png"));
    for (const auto& [method, score] : one.scores.at(64).at(1)) {
        ASSERT_TRUE(stopped.scores.at(64).at(1).count(method)) << method;
        EXPECT_EQ(stopped.scores.at(64).at(1).at(method).psnr, score.psnr) << method;
        EXPECT_EQ(stopped.scores.at(64).at(1).at(method).frames, 1) << method;
    }
    fs::remove_all(dir);
}

}  // namespace
}  // namespace dynsky
