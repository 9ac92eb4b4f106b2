// End-to-end tests of `dynsky animate`: a run killed with SIGKILL mid-frame, mid-write or at random
// moments resumes to the same frames as an uninterrupted run (the EXR, PNG and sky PNG files byte
// for byte: frame headers hold no timings) with no temporary left; resume
// re-renders damaged frames and frames of other settings and says so; --force starts over; frame
// ranges rendered separately equal one run; bad input fails cleanly.
#include <gtest/gtest.h>

#include <cmath>

#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>

#include "tests/test_support.h"
#include "util/data_path.h"
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

std::string numbered(const std::string& dir, const char* prefix, int k, const char* ext) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "/%s_%04d%s", prefix, k, ext);
    return dir + buf;
}

// The frames of two runs, byte for byte (cmp): pixels, headers and PNG text chunks alike.
void expect_same_frames(const std::string& a, const std::string& b, int count) {
    for (int k = 0; k < count; ++k) {
        ASSERT_TRUE(fs::exists(frame(a, k))) << frame(a, k);
        ASSERT_TRUE(fs::exists(frame(b, k))) << frame(b, k);
        for (const std::string& file :
             {frame(a, k).substr(a.size()), numbered("", "frame", k, ".png"), numbered("", "sky", k, ".png")}) {
            test::CommandResult r = test::run_command("cmp " + a + file + " " + b + file);
            EXPECT_EQ(r.exit_code, 0) << file << " differs: " << r.output;
        }
    }
}

// Files of dir named like a temporary (util/atomic_file.h).
std::vector<std::string> temporaries_in(const std::string& dir) {
    std::vector<std::string> found;
    for (const auto& e : fs::directory_iterator(dir))
        if (e.path().filename().string().rfind(".tmp-", 0) == 0) found.push_back(e.path().filename().string());
    return found;
}

ino_t inode(const std::string& path) {
    struct stat st {};
    ::stat(path.c_str(), &st);
    return st.st_ino;
}

// Each frame's line says how many of the frames to render are done and the time left (a farm's
// log showed nothing of it; frames kept from an earlier run are not counted as work left).
TEST(AnimateCli, FrameLinesSayTheTimeLeft) {
    const std::string dir = test::temp_dir("animate_eta");
    const std::string run = std::string(DYNSKY_EXE) +
                            " animate builtin --sky-res 32 --res 16x9 --spp 1 --duration 1 --fps 2 --no-video --out " +
                            dir + "/a 2>&1";
    auto r = test::run_command(run);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("1 of 2 rendered"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("2 of 2 rendered"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("s left"), std::string::npos) << r.output;
    fs::remove(dir + "/a/frame_0001.exr");  // one frame to render again: one of one
    r = test::run_command(run);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("1 of 1 rendered"), std::string::npos) << r.output;
    fs::remove_all(dir);
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
    // or slow the machine; the wait for frame 2 (its EXR, written after its PNGs) is bounded (60 s).
    fs::create_directories(killed);
    const std::string pipe = killed + "/.tmp-frame_0003-$$.exr";
    std::ofstream(dir + "/run.sh") << "mkfifo " << pipe << " && exec " << animate(killed) << "\n";
    std::ofstream(dir + "/kill.sh") << "sh " << dir << "/run.sh & pid=$!\n"
                                    << "for i in $(seq 1 600); do [ -e " << frame(killed, 2) << " ] && break; "
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
    EXPECT_NE(r.output.find("temporary file(s) left in " + killed + " by a killed run"), std::string::npos) << r.output;
    EXPECT_TRUE(temporaries_in(killed).empty()) << temporaries_in(killed)[0];
    expect_same_frames(full, killed, 8);
    EXPECT_TRUE(fs::exists(killed + "/contact_sheet.png"));
    fs::remove_all(dir);
}

// Killed mid-write: frame 2's EXR temporary is a named pipe this test reads 1000 bytes of and then
// stops reading, so the run is held inside write() with part of the frame written when SIGKILL comes.
TEST(AnimateCli, KilledMidWriteResumesToTheSameFrames) {
    std::string dir = test::temp_dir("animate_kill_write");
    std::string full = dir + "/full", killed = dir + "/killed";
    // Frames of 256 x 144: an EXR well over a pipe's 64 kB buffer, so the write blocks.
    const std::string settings = "--res 256x144 --frames 0-3";
    ASSERT_EQ(test::run_command(animate(full, settings)).exit_code, 0);
    fs::create_directories(killed);
    std::ofstream(dir + "/run.sh") << "mkfifo " << killed << "/.tmp-frame_0002-$$.exr && exec "
                                   << animate(killed, settings) << "\n";
    std::ofstream(dir + "/kill.sh") << "sh " << dir << "/run.sh & pid=$!\n"
                                    << "for i in $(seq 1 600); do [ -p " << killed
                                    << "/.tmp-frame_0002-$pid.exr ] && break; sleep 0.05; done\n"
                                    << "exec 3< " << killed << "/.tmp-frame_0002-$pid.exr\n"
                                    << "head -c 1000 <&3 | wc -c\n"
                                    << "kill -9 $pid; wait $pid; echo rc=$?\n";
    auto r = test::run_command("sh " + dir + "/kill.sh");
    ASSERT_NE(r.output.find("1000"), std::string::npos) << "not held mid-write: " << r.output;
    ASSERT_NE(r.output.find("rc=137"), std::string::npos) << r.output;
    ASSERT_EQ(temporaries_in(killed).size(), 1u);  // the pipe, as a killed write leaves its temporary
    ASSERT_FALSE(fs::exists(frame(killed, 2)));
    r = test::run_command(animate(killed, settings));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(temporaries_in(killed).empty());
    expect_same_frames(full, killed, 4);
    fs::remove_all(dir);
}

// SIGKILL at seeded random moments (from start-up to the last frame; some land mid-write), five times
// in a row, then one run to the end: the same frames as one uninterrupted run, no temporary left.
TEST(AnimateCli, KilledAtRandomMomentsResumesToTheSameFrames) {
    std::string dir = test::temp_dir("animate_kill_random");
    std::string full = dir + "/full", killed = dir + "/killed";
    ASSERT_EQ(test::run_command(animate(full)).exit_code, 0);
    std::mt19937 rng(20261202);
    std::uniform_int_distribution<int> delay_ms(20, 600);
    std::ofstream script(dir + "/kills.sh");
    for (int i = 0; i < 5; ++i)
        script << "sh -c 'exec " << animate(killed) << "' & pid=$!; sleep " << delay_ms(rng) / 1000.0
               << "; kill -9 $pid 2>/dev/null; wait $pid\n";
    script.close();
    test::run_command("sh " + dir + "/kills.sh");
    auto r = test::run_command(animate(killed));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(temporaries_in(killed).empty());
    expect_same_frames(full, killed, 8);
    EXPECT_TRUE(fs::exists(killed + "/contact_sheet.png"));
    fs::remove_all(dir);
}

// A sky file turned (--sky-turn) is another sky: its frames are not kept from the unturned run.
TEST(AnimateCli, ATurnedSkyFileIsOtherSettings) {
    const std::string dir = test::temp_dir("animate_turn");
    ASSERT_EQ(test::run_command(std::string(DYNSKY_EXE) + " sky procedural --sky-res 64 --duration 0 -q -o " + dir +
                                "/p")
                  .exit_code,
              0);
    const std::string cmd = std::string(DYNSKY_EXE) + " animate builtin --sky " + dir +
                            "/p/frame_0000.exr --model advect --res 32x18 --spp 1 --duration 1 --fps 2 --no-video "
                            "--out " +
                            dir + "/a ";
    auto r = test::run_command(cmd + "-q");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const Image unturned = read_image(frame(dir + "/a", 1));
    r = test::run_command(cmd + "--sky-turn 90 2>&1");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("sky_turn (default) -> 90)"), std::string::npos) << r.output;
    EXPECT_NE(read_image(frame(dir + "/a", 1)).pixels, unturned.pixels);
    fs::remove_all(dir);
}

// Resume keeps only frames that are whole and made with the same settings, and says why it renders
// the others again; --force renders every frame again.
TEST(AnimateCli, ResumeRerendersDamagedFramesAndFramesOfOtherSettings) {
    std::string dir = test::temp_dir("animate_resume_check");
    std::string a = dir + "/a";
    ASSERT_EQ(test::run_command(animate(a)).exit_code, 0);
    const Image frame5 = read_image(frame(a, 5));

    // Other --spp: every frame again, and the reason named.
    auto r = test::run_command(animate(a, "--spp 3"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("rendering again frame(s) 0-7 of " + a + " (made with other settings: spp 2 -> 3)"),
              std::string::npos)
        << r.output;
    for (int k = 0; k < 8; ++k) EXPECT_EQ(read_image(frame(a, k)).metadata.numbers["dynsky:spp"], 3) << k;
    // Back to --spp 2: the same pixels as the first run (nothing of the --spp 3 frames kept).
    r = test::run_command(animate(a));
    EXPECT_NE(r.output.find("spp 3 -> 2"), std::string::npos) << r.output;
    EXPECT_TRUE(read_image(frame(a, 5)).pixels == frame5.pixels);

    // A truncated EXR, an empty PNG and a missing sky PNG: those three frames again, each named.
    {
        std::ifstream f(frame(a, 2), std::ios::binary);
        std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
        std::ofstream(frame(a, 2), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    }
    std::ofstream(numbered(a, "frame", 5, ".png"), std::ios::trunc).flush();
    fs::remove(numbered(a, "sky", 6, ".png"));
    const ino_t kept = inode(frame(a, 0));
    r = test::run_command(animate(a));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("rendering again frame(s) 2 of " + a + " (damaged: frame_0002.exr"), std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("rendering again frame(s) 5 of " + a + " (damaged: frame_0005.png"), std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("rendering again frame(s) 6 of " + a + " (damaged: sky_0006.png is missing)"),
              std::string::npos)
        << r.output;
    EXPECT_EQ(inode(frame(a, 0)), kept) << "a complete frame was rendered again";
    EXPECT_TRUE(read_image(frame(a, 5)).pixels == frame5.pixels);
    EXPECT_GT(fs::file_size(numbered(a, "frame", 5, ".png")), 0u);
    EXPECT_TRUE(fs::exists(numbered(a, "sky", 6, ".png")));
    {
        // timings.csv: one line per frame, in order (a repaired frame's line was appended again).
        std::ifstream in(a + "/timings.csv");
        std::string row;
        std::getline(in, row);
        std::vector<int> frames;
        while (std::getline(in, row)) frames.push_back(std::stoi(row));
        std::vector<int> expected(frames.size());
        for (size_t k = 0; k < expected.size(); ++k) expected[k] = int(k);
        EXPECT_EQ(frames, expected);
        EXPECT_GE(frames.size(), 7u);
    }

    // A frame whose EXR was overwritten with a NaN pixel (its settings intact): `temporal` refuses
    // it naming the file (its table was all NaN), and a resumed run renders it again.
    {
        Image nan_frame = read_image(frame(a, 3));
        nan_frame.pixels[7] = std::nanf("");
        write_image(frame(a, 3), nan_frame);
    }
    r = test::run_command(std::string(DYNSKY_EXE) + " temporal " + a);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("frame_0003.exr: pixel (2, 0) is NaN"), std::string::npos) << r.output;
    r = test::run_command(animate(a));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("rendering again frame(s) 3 of " + a + " (damaged: frame_0003.exr: pixel (2, 0) is NaN"),
              std::string::npos)
        << r.output;
    for (float v : read_image(frame(a, 3)).pixels) ASSERT_TRUE(std::isfinite(v));

    // A frame file copied onto another's number (its settings intact, another moment): rendered
    // again; `temporal` refuses the copy's time, and a gap in the frames.
    fs::copy_file(frame(a, 6), frame(a, 4), fs::copy_options::overwrite_existing);
    r = test::run_command(std::string(DYNSKY_EXE) + " temporal " + a);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("frame_0005.exr: its time"), std::string::npos) << r.output;
    r = test::run_command(animate(a));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("rendering again frame(s) 4 of " + a + " (damaged: frame_0004.exr holds frame 6)"),
              std::string::npos)
        << r.output;
    EXPECT_EQ(read_image(frame(a, 4)).metadata.numbers["dynsky:frame"], 4);
    const std::string gap = dir + "/gap";
    fs::create_directories(gap);
    for (int k : {0, 1, 3, 4}) fs::copy_file(frame(a, k), numbered(gap, "frame", k, ".exr"));
    r = test::run_command(std::string(DYNSKY_EXE) + " temporal " + gap);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("frame 2 is missing"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(gap + "/temporal.csv"));
    // Three frames within one medium step (0, 0.125, 0.25 s; dt 0.5 s): no pair across a boundary,
    // so no ratio (it said "0.000% (0 pairs)" and "ratio 0.00", as if measured).
    const std::string pair = dir + "/pair";
    fs::create_directories(pair);
    for (int k : {0, 1, 2}) fs::copy_file(frame(a, k), numbered(pair, "frame", k, ".exr"));
    r = test::run_command(std::string(DYNSKY_EXE) + " temporal " + pair);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("none (0 pairs)"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("ratio none ("), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("0 pairs)%"), std::string::npos) << r.output;

    // --force: every frame written anew.
    r = test::run_command(animate(a, "--force"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(inode(frame(a, 0)), kept);
    EXPECT_TRUE(read_image(frame(a, 5)).pixels == frame5.pixels);
    fs::remove_all(dir);
}

// What a frame is made of includes the cloud model's files and a .glb's external textures, not
// their names alone: a retrained model in the same folder and a .glb's changed colormap.png (the
// Kenney city kit's tiles share one) kept the old frames.
TEST(AnimateCli, ResumeRerendersFramesOfAChangedModelOrGlbTexture) {
    DYNSKY_REQUIRE_SHARED();
    const std::string dir = test::temp_dir("animate_resume_files");
    fs::copy(data_path("networks/models/advect_residual"), dir + "/model", fs::copy_options::recursive);
    fs::create_directories(dir + "/kit/Textures");
    fs::copy_file(test::shared_path("scenes/KenneyCityKit/building-small-a.glb"), dir + "/kit/building.glb");
    fs::copy_file(test::shared_path("scenes/KenneyCityKit/Textures/colormap.png"), dir + "/kit/Textures/colormap.png");
    const std::string run = std::string(DYNSKY_EXE) + " animate " + dir +
                            "/kit/building.glb --sky procedural:2 --model " + dir +
                            "/model --sky-res 64 --res 32x18 --spp 1 --duration 60 --fps 0.05 --no-video --out " + dir +
                            "/a 2>&1";
    ASSERT_EQ(test::run_command(run + " -q").exit_code, 0);
    auto r = test::run_command(run);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("already complete"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("rendering again"), std::string::npos) << r.output;
    // The texture changed (its colours inverted): every frame again, the file named.
    {
        Image texture = read_image(dir + "/kit/Textures/colormap.png");
        for (float& v : texture.pixels) v = 1.0f - v;
        write_image(dir + "/kit/Textures/colormap.png", texture);
    }
    r = test::run_command(run);
    EXPECT_NE(r.output.find("rendering again frame(s) 0-"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("colormap.png"), std::string::npos) << r.output;
    // The model's description changed: again, the model named.
    { std::ofstream(dir + "/model/model.json", std::ios::app) << "\n"; }
    r = test::run_command(run);
    EXPECT_NE(r.output.find("rendering again frame(s) 0-"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("model.json"), std::string::npos) << r.output;
    fs::remove_all(dir);
}

// An animation of more than 10000 frames names every frame with five digits, so that they sort
// in order in any listing (an audit: frame_10000 came between frame_1000 and frame_1001).
TEST(AnimateCli, FramesOfALongAnimationSortInOrder) {
    const std::string dir = test::temp_dir("animate_long_names");
    auto r = test::run_command(std::string(DYNSKY_EXE) +
                               " animate builtin --sky clear --sky-res 32 --res 16x9 --spp 1 --no-video -q "
                               "--duration 100.01 --fps 100 --frames 9999-10000 --out " +
                               dir);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    for (const char* name : {"frame_09999.exr", "frame_09999.png", "sky_09999.png", "frame_10000.exr"})
        EXPECT_TRUE(fs::exists(dir + "/" + name)) << name;
    EXPECT_FALSE(fs::exists(dir + "/frame_9999.exr"));
    fs::remove_all(dir);
}

// What a farm script checks before queueing anything (`--count-frames`): a typo in the scene, sky
// or model name, or a bad pass list, fails there, not in every frames task after the keys job
// (a misspelt scene went through, and each task failed and was requeued). A timeline folder that
// is the frames' folder is refused by the keys stage, not only by the stages after it.
TEST(AnimateCli, CountFramesChecksWhatAFarmWouldQueue) {
    const std::string dir = test::temp_dir("animate_count");
    const std::string base = std::string(DYNSKY_EXE) + " animate ";
    const std::string ok = "builtin --sky procedural:1 --duration 90 --fps 0.1 --out " + dir + "/a";
    auto r = test::run_command(base + ok + " --count-frames");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(r.output, "9\n");
    for (const std::string& bad :
         {std::string("scenes/tower/towr.gltf --duration 90 --fps 0.1 --out ") + dir + "/a",
          ok + " --sky-res 64 --model nosuch", ok + " --aovs bogus", "builtin --sky nosuch.exr --out " + dir + "/a",
          // What the run refuses before any step (an audit of the options: each passed --count-frames).
          "builtin --sky procedural:abc --duration 90 --fps 0.1 --out " + dir + "/a",
          "builtin --sky clear --model procedural --duration 90 --fps 0.1 --out " + dir + "/a",
          ok + " --model advect --dt 1e-9",
          // A camera the file does not have (found by the frames tasks before).
          std::string("scenes/tower/tower.gltf --camera 2 --duration 90 --fps 0.1 --out ") + dir + "/a"}) {
        r = test::run_command(base + bad + " --count-frames 2>&1");
        EXPECT_NE(r.exit_code, 0) << bad << "\n" << r.output;
        EXPECT_EQ(r.output.find("\n9\n"), std::string::npos) << bad;
    }
    r = test::run_command(base + "scenes/tower/tower.gltf --camera 1 --duration 90 --fps 0.1 --out " + dir +
                          "/a --count-frames");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(r.output, "9\n");
    r = test::run_command(base + "builtin --sky procedural:1 --sky-res 64 --duration 60 --fps 0.1 --out " + dir +
                          "/e --timeline " + dir + "/e --stage keys 2>&1");
    EXPECT_NE(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("give it a folder of its own"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir + "/e/timeline.json"));
    // Spelt with a trailing slash or a dot, before either exists: the same folder.
    for (const char* spelling : {"/f/", "/f/."}) {
        r = test::run_command(base + "builtin --sky procedural:1 --duration 60 --fps 0.1 --out " + dir +
                              "/f --timeline " + dir + spelling + " --count-frames 2>&1");
        EXPECT_NE(r.exit_code, 0) << spelling << "\n" << r.output;
        EXPECT_NE(r.output.find("give it a folder of its own"), std::string::npos) << r.output;
    }
    fs::remove_all(dir);
}

// A sky file keeps its own sun unless --time puts it on the clock: --lat and --lon alone changed
// nothing, silently (render refuses them); and --coverage on a clear sky, which has no clouds.
TEST(AnimateCli, OptionsASkyDoesNotUseAreSaidToBeIgnored) {
    const std::string dir = test::temp_dir("animate_ignored");
    auto r = test::run_command(std::string(DYNSKY_EXE) + " sky clear --sky-res 32 -q -o " + dir + "/clear.exr");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::string base = std::string(DYNSKY_EXE) + " animate builtin --count-frames --duration 10 --fps 0.1 ";
    r = test::run_command(base + "--sky " + dir + "/clear.exr --lat -60 --lon 100 2>&1");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("--lat and --lon place the sun only with --time"), std::string::npos) << r.output;
    r = test::run_command(base + "--sky " + dir + "/clear.exr --lat -60 --time 2026-06-21T12:00:00Z 2>&1");
    EXPECT_EQ(r.output.find("--lat and --lon place the sun only"), std::string::npos) << r.output;
    r = test::run_command(base + "--sky clear --coverage 0.9 2>&1");
    EXPECT_NE(r.output.find("'clear' has no clouds: --coverage is ignored"), std::string::npos) << r.output;
    r = test::run_command(base + "--sky " + dir + "/clear.exr --turbidity 6 2>&1");
    EXPECT_NE(r.output.find("--turbidity is ignored"), std::string::npos) << r.output;
    fs::remove_all(dir);
}

// A Delta t over which the wind moves the clouds more than half their height is warned about: the
// frames between steps broke into speckle that snapped back at every step (--dt 600, 12 m/s).
TEST(AnimateCli, ALongDeltaTUnderAWindIsSaid) {
    const std::string dir = test::temp_dir("animate_long_dt");
    const std::string base = std::string(DYNSKY_EXE) +
                             " animate builtin --sky procedural:3 --model advect --duration 600 --fps 0.005 --res 8x4 "
                             "--spp 1 --sky-res 32 --no-video -q -o " +
                             dir;
    auto r = test::run_command(base + "/a --dt 600 2>&1");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("--dt 600 s: the wind (12 m/s, clouds at 1500 m) moves the clouds 4.8 x their height"),
              std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("--dt 62 or less"), std::string::npos) << r.output;
    r = test::run_command(base + "/b --dt 30 2>&1");
    EXPECT_EQ(r.output.find("will ghost"), std::string::npos) << r.output;
    // Beyond what a sky can show (a thousand heights a step) it is refused before any frame, naming
    // --dt and a Delta t that works: the first step failed after frame 0, naming the wind given, and
    // the warning's advice read "--dt 0" (the model's own 30 s).
    r = test::run_command(base + "/c --dt 60 --wind-speed 300 --cloud-height 10 2>&1");
    EXPECT_NE(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("1800 times their height a step"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("give --dt 0.017 s or less"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir + "/c/frame_0000.exr"));
    // --drift shapes the flow model's first step only: another model ignored it without a word.
    r = test::run_command(base + "/d --dt 30 --drift 1 2>&1");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("the advect model moves the clouds by its own motion"), std::string::npos) << r.output;
    r = test::run_command(base + "/e --dt 30 --model flow --drift 1 2>&1");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(r.output.find("--drift is ignored"), std::string::npos) << r.output;
    fs::remove_all(dir);
}

// Through sunrise one exposure from t = 0 clipped the PNGs white within 20 minutes; with
// --exposure-follows-sun it follows the clear sky's light: the last frame's PNG is about as bright
// as the first's, the EXRs are the same either way.
TEST(AnimateCli, TheExposureCanFollowTheSunThroughSunrise) {
    const std::string dir = test::temp_dir("animate_sunrise");
    const std::string base = std::string(DYNSKY_EXE) +
                             " animate builtin --sky clear --time 2026-06-21T03:15:00Z --duration 3600 --fps 0.00055 "
                             "--res 16x9 --spp 2 --sky-res 32 --no-video -q -o " +
                             dir;
    auto r = test::run_command(base + "/fixed 2>&1");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    r = test::run_command(base + "/follow --exposure-follows-sun 2>&1");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    auto mean = [](const std::string& png) {
        const Image img = read_image(png);
        double sum = 0;
        for (float v : img.pixels) sum += v;
        return sum / double(img.pixels.size());
    };
    const double fixed0 = mean(dir + "/fixed/frame_0000.png"), fixed1 = mean(dir + "/fixed/frame_0001.png");
    const double follow0 = mean(dir + "/follow/frame_0000.png"), follow1 = mean(dir + "/follow/frame_0001.png");
    std::printf("PNG means at 0 and 30 min: one exposure %.3f %.3f, following the sun %.3f %.3f\n", fixed0, fixed1,
                follow0, follow1);
    EXPECT_GT(fixed1, 1.3 * fixed0);  // the light rises 100-fold: the fixed exposure clips towards white
    EXPECT_NEAR(follow0, fixed0, 1e-6);
    EXPECT_NEAR(follow1 / follow0, 1.0, 0.35);
    EXPECT_EQ(read_image(dir + "/fixed/frame_0001.exr").pixels, read_image(dir + "/follow/frame_0001.exr").pixels);
    fs::remove_all(dir);
}

// compare's clear sky of a sky made here has the turbidity it was made with: that of cumulus at
// --turbidity 8 is the clear sky at 8 (it was turbidity 3's, as for a photograph).
TEST(CompareCli, TheClearSkyOfASkyMadeHereHasItsTurbidity) {
    const std::string dir = test::temp_dir("compare_turbidity");
    auto clear_light = [&](const std::string& sky) {
        auto r =
            test::run_command(std::string(DYNSKY_EXE) + " compare builtin --sky " + sky +
                              " --coverage 0.4 --turbidity 8 --res 16x9 --spp 1 --sky-res 32 --duration 10 -q -o " +
                              dir + "/" + sky.substr(0, 5) + " 2>&1");
        EXPECT_EQ(r.exit_code, 0) << r.output;
        std::ifstream csv(dir + "/" + sky.substr(0, 5) + "/illuminance.csv");
        std::string header, row;
        std::getline(csv, header), std::getline(csv, row);
        double t = 0, clear = 0;
        EXPECT_EQ(std::sscanf(row.c_str(), "%lf,%lf", &t, &clear), 2) << row;
        return clear;
    };
    const double of_cumulus = clear_light("procedural:3"), of_clear = clear_light("clear");
    EXPECT_NEAR(of_cumulus / of_clear, 1.0, 0.05);  // 0.98 (its own sun patch); 0.75 at turbidity 3
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

// Output folders with ordinary names ffmpeg reads as its own syntax ('%' as a pattern, a leading
// '-' as an option, 'word:' as a protocol) get their videos and contact sheet: they lost them after
// the render.
TEST(AnimateCli, VideosOfFoldersWithPercentDashOrColonNames) {
    const std::string dir = test::temp_dir("animate_odd_names");
    for (const std::string name : {"100% cover", "-take2", "shot:2"}) {
        const std::string cmd = std::string(DYNSKY_EXE) +
                                " animate builtin --sky procedural:3 --model procedural --sky-res 32 --res 16x10 "
                                "--spp 1 --duration 0.5 --fps 4 --threads 2 -q --out='" +
                                name + "'";
        auto r = test::run_command("cd '" + dir + "' && " + cmd);
        EXPECT_EQ(r.exit_code, 0) << name << "\n" << r.output;
        for (const char* f : {"/animation.mp4", "/sky.mp4", "/contact_sheet.png"})
            EXPECT_TRUE(fs::exists(dir + "/" + name + f)) << name << f;
    }
    fs::remove_all(dir);
}

// A shorter animation rendered into the folder of a longer one: its videos hold its own frames
// only (the 8 of the first run were encoded as well), and its timings.csv rows; frames numbered
// from 10000 on count for `temporal` (it read only four-digit names).
TEST(AnimateCli, AShorterRunEncodesItsOwnFramesOnly) {
    std::string dir = test::temp_dir("animate_shorter");
    const std::string out = dir + "/a";
    ASSERT_EQ(test::run_command(animate(out)).exit_code, 0);
    std::string with_video = animate(out, "--duration 0.5");
    with_video.replace(with_video.find(" --no-video"), 11, "");
    auto r = test::run_command(with_video);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    for (const char* video : {"/animation.mp4", "/sky.mp4"}) {
        auto probe = test::run_command(
            "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
            "stream=nb_read_frames -of default=noprint_wrappers=1:nokey=1 " +
            out + video);
        ASSERT_EQ(probe.exit_code, 0) << probe.output;
        EXPECT_EQ(std::stoi(probe.output), 4) << video;
    }
    std::ifstream timings(out + "/timings.csv");
    int rows = -1;
    for (std::string line; std::getline(timings, line);) ++rows;
    EXPECT_EQ(rows, 4);
    const std::string big = dir + "/big";
    r = test::run_command(std::string(DYNSKY_EXE) +
                          " animate builtin --sky procedural:1 --model procedural --sky-res 16 --duration 1001 "
                          "--fps 10 --res 8x8 --spp 1 --frames 9997-10001 --no-video -q --out " +
                          big);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    // A `sky procedural` folder (frames and their flows, at the same times) moves as a captured
    // sequence: its last frame the input, the one before it the previous frame (a flow was taken).
    const std::string proc = dir + "/proc";
    r = test::run_command(std::string(DYNSKY_EXE) + " sky procedural --sky-res 32 --duration 30 --dt 10 -q -o " + proc);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    r = test::run_command(std::string(DYNSKY_EXE) + " animate builtin --sky " + proc +
                          " --model advect --res 16x16 --spp 1 --fps 4 --duration 0.5 --no-video -q -o " + dir +
                          "/from_proc");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    r = test::run_command(std::string(DYNSKY_EXE) + " temporal " + big);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("frames: 5"), std::string::npos) << r.output;
    fs::remove_all(dir);
}

std::string bytes_of(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

// The render farm's commands (docs/render-farm.md): `sky timeline` with the animation's sky options,
// then ranges rendered from it, then encode: every frame file the same bytes as one run's.
// The network model with no wind, stored and read back (keys, then frames), gives one run's frames:
// the sun's weight read how far the clouds at the sun had moved from flows only a computed timeline
// kept, and a stored one took them as far (its frames 1-2 darker: mean 7.7 for 9.7).
TEST(AnimateCli, AStillSkyFromAStoredTimelineEqualsOneRun) {
    const std::string dir = test::temp_dir("animate_still");
    const std::string base = std::string(DYNSKY_EXE) +
                             " animate builtin --sky procedural:1 --wind-speed 0 --duration 60 --fps 0.05 --res 32x18"
                             " --spp 1 --sky-res 128 --no-video -q --out ";
    ASSERT_EQ(test::run_command(base + dir + "/one").exit_code, 0);
    ASSERT_EQ(test::run_command(base + dir + "/farm --timeline " + dir + "/tl --stage keys").exit_code, 0);
    ASSERT_EQ(test::run_command(base + dir + "/farm --timeline " + dir + "/tl --stage frames").exit_code, 0);
    expect_same_frames(dir + "/one", dir + "/farm", 3);
    fs::remove_all(dir);
}

TEST(AnimateCli, FramesFromSkyTimelineEqualOneRunByteForByte) {
    std::string dir = test::temp_dir("animate_farm");
    std::string full = dir + "/full", farm = dir + "/farm", timeline = dir + "/timeline";
    ASSERT_EQ(test::run_command(animate(full)).exit_code, 0);
    auto r = test::run_command(std::string(DYNSKY_EXE) +
                               " sky timeline --sky procedural:3 --model procedural --sky-res 96 --dt 0.5 --duration 1"
                               " --quiet --out " +
                               timeline);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    // A requeued keys job keeps a whole timeline, and makes a damaged one again (a step deleted,
    // a flow cut short) before any frame reads it.
    {
        const std::string keys = std::string(DYNSKY_EXE) +
                                 " sky timeline --sky procedural:3 --model procedural --sky-res 96 --dt 0.5 "
                                 "--duration 1 --out " +
                                 timeline;
        const std::string step1 = bytes_of(timeline + "/step_0001.exr"), flow0 = bytes_of(timeline + "/flow_0000.npy");
        r = test::run_command(keys);
        EXPECT_NE(r.output.find("covers 1 s: kept"), std::string::npos) << r.output;
        fs::remove(timeline + "/step_0001.exr");
        std::ofstream(timeline + "/flow_0000.npy", std::ios::binary | std::ios::trunc) << flow0.substr(0, 100);
        r = test::run_command(keys);
        ASSERT_EQ(r.exit_code, 0) << r.output;
        EXPECT_NE(r.output.find("flow_0000.npy: truncated"), std::string::npos) << r.output;
        EXPECT_NE(r.output.find("made again"), std::string::npos) << r.output;
        EXPECT_EQ(bytes_of(timeline + "/step_0001.exr"), step1);
        EXPECT_EQ(bytes_of(timeline + "/flow_0000.npy"), flow0);
    }
    r = test::run_command(animate(farm, "--count-frames"));
    EXPECT_EQ(r.exit_code, 0);
    EXPECT_EQ(r.output, "8\n");
    for (const char* range : {"4-7", "0-3"}) {
        r = test::run_command(animate(farm,
                                      std::string("--stage frames --frames ") + range + " --timeline " + timeline));
        ASSERT_EQ(r.exit_code, 0) << r.output;
    }
    EXPECT_FALSE(fs::exists(farm + "/contact_sheet.png"));
    r = test::run_command(animate(farm, "--stage encode --timeline " + timeline));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    for (int k = 0; k < 8; ++k)
        for (const char* prefix : {"frame", "sky"})
            for (const char* ext : {".exr", ".png"}) {
                if (std::string(prefix) == "sky" && std::string(ext) == ".exr") continue;
                EXPECT_TRUE(bytes_of(numbered(full, prefix, k, ext)) == bytes_of(numbered(farm, prefix, k, ext)))
                    << numbered(farm, prefix, k, ext);
            }
    EXPECT_TRUE(bytes_of(full + "/contact_sheet.png") == bytes_of(farm + "/contact_sheet.png"));
    // Another sky than the timeline's: refused, naming what differs (exit 1, runtime error).
    r = test::run_command(animate(farm, "--stage frames --coverage 0.7 --timeline " + timeline));
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.output.find("coverage"), std::string::npos) << r.output;
    EXPECT_EQ(test::run_command(animate(farm, "--stage nope")).exit_code, 2);
    fs::remove_all(dir);
}

// The main job's default moves the clouds with the shipped networks (issue 4), recorded per frame.
// A frame is what `render` makes of its sky: the same sampler (cdf+mis; the frames used plain cdf,
// noisier than documented, and no frame could be rendered again with `render`).
TEST(AnimateCli, FrameZeroIsRendersImageOfTheSameSky) {
    const std::string dir = test::temp_dir("animate_is_render");
    const std::string common = " builtin --sky clear --sky-res 64 --res 48x27 --spp 4 --threads 2 -q ";
    auto a = test::run_command(std::string(DYNSKY_EXE) + " animate" + common + "--duration 1 --fps 1 --no-video -o " +
                               dir + "/anim");
    ASSERT_EQ(a.exit_code, 0) << a.output;
    auto r = test::run_command(std::string(DYNSKY_EXE) + " render" + common + "-o " + dir + "/r.exr");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(read_image(dir + "/r.exr").pixels == read_image(frame(dir + "/anim", 0)).pixels);
    // A model folder as `sky predict` takes it (network: optional; a bare folder was a usage error).
    const std::string model = std::string(DYNSKY_SOURCE_DIR) + "/networks/models/advect_residual";
    auto bare = test::run_command(std::string(DYNSKY_EXE) + " animate" + common +
                                  "--duration 20 --fps 0.1 --no-video --model " + model + " -o " + dir + "/bare");
    ASSERT_EQ(bare.exit_code, 0) << bare.output;
    auto named = test::run_command(std::string(DYNSKY_EXE) + " animate" + common +
                                   "--duration 20 --fps 0.1 --no-video --model network:" + model + " -o " + dir +
                                   "/named");
    ASSERT_EQ(named.exit_code, 0) << named.output;
    EXPECT_TRUE(read_image(frame(dir + "/bare", 1)).pixels == read_image(frame(dir + "/named", 1)).pixels);
    fs::remove_all(dir);
}

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
