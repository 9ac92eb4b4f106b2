// End-to-end tests of `dynsky animate`: a run killed with SIGKILL mid-frame resumes to the same
// frames as an uninterrupted run (EXR pixels byte for byte), frame ranges rendered separately
// equal one run, and bad input fails cleanly.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "tests/test_support.h"
#include "util/image.h"

namespace dynsky {
namespace {

namespace fs = std::filesystem;

// 8 frames at 8 fps, Delta t 0.5 s: two medium-step boundaries and Gamma's keys in between.
std::string animate(const std::string& out, const std::string& extra = "") {
    return std::string(DYNSKY_EXE) +
           " animate builtin --sky procedural:3 --model procedural --sky-res 96 --res 64x36 --spp 2 --duration 1 --fps 8 --dt 0.5"
           " --no-video --quiet --threads 2 --out " +
           out + " " + extra;
}

std::string frame(const std::string& dir, int k) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "/frame_%04d.exr", k);
    return dir + buf;
}

void expect_same_frames(const std::string& a, const std::string& b, int count) {
    for (int k = 0; k < count; ++k) {
        ASSERT_TRUE(fs::exists(frame(a, k))) << frame(a, k);
        ASSERT_TRUE(fs::exists(frame(b, k))) << frame(b, k);
        Image ia = read_image(frame(a, k)), ib = read_image(frame(b, k));
        EXPECT_EQ(ia.width, ib.width);
        EXPECT_TRUE(ia.pixels == ib.pixels) << "frame " << k << " differs";
    }
}

TEST(AnimateCli, KilledRunResumesToTheSameFrames) {
    std::string dir = test::temp_dir("animate_kill");
    std::string full = dir + "/full", killed = dir + "/killed";
    auto r = test::run_command(animate(full));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(fs::exists(full + "/contact_sheet.png"));

    // Kill -9 while frame 3 is being written, without depending on timing: frames are written
    // through a temporary named .tmp-frame_0003-PID.exr (util/image.cpp), so a named pipe put there
    // beforehand (the shell execs dynsky, keeping its PID) holds the run in open() until it is
    // killed. Frames 0-2 are then complete and nothing of frame 3 or later exists, however fast
    // or slow the machine; the wait for frame 2 is bounded (60 s).
    fs::create_directories(killed);
    const std::string pipe = killed + "/.tmp-frame_0003-$$.exr";
    std::ofstream(dir + "/run.sh") << "mkfifo " << pipe << " && exec " << animate(killed) << "\n";
    std::ofstream(dir + "/kill.sh") << "sh " << dir << "/run.sh & pid=$!\n"
                                    << "for i in $(seq 1 600); do [ -e " << killed << "/sky_0002.png ] && break; "
                                    << "kill -0 $pid 2>/dev/null || break; sleep 0.1; done\n"
                                    << "kill -9 $pid; wait $pid; echo rc=$?\n";
    r = test::run_command("sh " + dir + "/kill.sh");
    const char* naming = " (has the temporary naming in util/image.cpp changed?)";
    ASSERT_NE(r.output.find("rc=137"), std::string::npos)
        << "not killed by SIGKILL while held" << naming << ": " << r.output;
    ASSERT_TRUE(fs::exists(frame(killed, 2)));
    ASSERT_TRUE(fs::exists(killed + "/sky_0002.png"));
    ASSERT_FALSE(fs::exists(frame(killed, 3))) << "the run got past frame 3" << naming;
    ASSERT_FALSE(fs::exists(killed + "/sky_0007.png"));
    // What a real kill leaves there: a half-written temporary (a regular file, not the pipe).
    int temporaries = 0;
    for (const auto& e : fs::directory_iterator(killed)) {
        if (e.path().filename().string().rfind(".tmp-frame_0003-", 0) != 0) continue;
        ++temporaries;
        fs::path p = e.path();
        fs::remove(p);
        std::ofstream(p.string()) << "half an EXR";
    }
    ASSERT_EQ(temporaries, 1);

    r = test::run_command(animate(killed) + " 2>&1; echo rc=$?");
    EXPECT_NE(r.output.find("rc=0"), std::string::npos) << r.output;
    expect_same_frames(full, killed, 8);
    EXPECT_TRUE(fs::exists(killed + "/contact_sheet.png"));
    fs::remove_all(dir);
}

TEST(AnimateCli, FrameRangesEqualOneRun) {
    std::string dir = test::temp_dir("animate_ranges");
    std::string full = dir + "/full", parts = dir + "/parts";
    ASSERT_EQ(test::run_command(animate(full)).exit_code, 0);
    auto r = test::run_command(animate(parts, "--frames 5-7"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_FALSE(fs::exists(frame(parts, 0)));
    EXPECT_FALSE(fs::exists(parts + "/contact_sheet.png")) << "not every frame exists yet";
    ASSERT_EQ(test::run_command(animate(parts, "--frames 0-4")).exit_code, 0);
    expect_same_frames(full, parts, 8);
    EXPECT_TRUE(fs::exists(parts + "/contact_sheet.png"));
    fs::remove_all(dir);
}

// The main job's default moves the clouds with the shipped networks (issue 4), recorded per frame.
TEST(AnimateCli, DefaultModelIsTheShippedAdvectResidualNetwork) {
    std::string dir = test::temp_dir("animate_default_model");
    auto r = test::run_command(std::string(DYNSKY_EXE) +
                               " animate builtin --sky-res 96 --res 32x18 --spp 1 --duration 30 --fps 0.05 "
                               "--quiet --out " +
                               dir + " 2>&1");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    for (int k = 0; k < 2; ++k) {
        Image img = read_image(frame(dir, k));
        const std::string& model = img.metadata.strings["dynsky:sky_model"];
        EXPECT_EQ(model.rfind("network:", 0), 0u) << model;
        EXPECT_NE(model.find("networks/models/advect_residual"), std::string::npos) << model;
    }
    fs::remove_all(dir);
}

TEST(AnimateCli, BadInputFailsCleanly) {
    std::string dir = test::temp_dir("animate_bad");
    auto r = test::run_command(animate(dir + "/a", "--frames 3-20") + " 2>&1");
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.output.find("--frames"), std::string::npos) << r.output;
    r = test::run_command(std::string(DYNSKY_EXE) + " animate builtin --sky " + dir + "/missing.exr --out " + dir +
                          "/b 2>&1");
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.output.find("missing.exr"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir + "/b/frame_0000.exr"));
    r = test::run_command(std::string(DYNSKY_EXE) + " animate builtin --model network:" + dir + "/nomodel --out " +
                          dir + "/c 2>&1");
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.output.find("nomodel"), std::string::npos) << r.output;
    fs::remove_all(dir);
}

}  // namespace
}  // namespace dynsky
