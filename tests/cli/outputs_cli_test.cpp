// End-to-end: outputs are never half-written and exit codes say what went wrong (docs/exit-codes.md).
// A full disk is a file size limit (ulimit -f: writes fail with EFBIG, dynsky ignores SIGXFSZ) on
// every output format: each command exits 1 naming the file, with no file cut short under its
// final name and no temporary left. An interrupt removes the file being written (exit 3); an
// output that is an input is refused; misspelt commands and options get a "did you mean" (exit 2).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

#include "tests/test_support.h"
#include "util/atomic_file.h"
#include "util/data_path.h"
#include "util/error.h"
#include "util/image.h"

namespace dynsky {
namespace {

namespace fs = std::filesystem;

const std::string kExe = DYNSKY_EXE;

// The command under a file size limit of 8 blocks (4 kB in dash's 512-byte blocks, 8 kB in bash's).
test::CommandResult run_with_full_disk(const std::string& args) {
    return test::run_command("ulimit -f 8; exec " + kExe + " " + args);
}

// Every file left in dir is whole (images decode, JSON parses, text ends in a newline) and no
// temporary (.tmp-*) is left.
void expect_nothing_half_written(const std::string& dir) {
    for (const auto& e : fs::recursive_directory_iterator(dir)) {
        if (!e.is_regular_file()) continue;
        const std::string name = e.path().filename().string(), path = e.path().string();
        EXPECT_NE(name.rfind(".tmp-", 0), 0u) << "temporary left: " << path;
        EXPECT_GT(fs::file_size(path), 0u) << path;
        const std::string ext = file_extension(path);
        if (ext == ".exr" || ext == ".png") {
            EXPECT_NO_THROW(read_image(path)) << path;
        } else if (ext == ".json") {
            std::ifstream f(path);
            EXPECT_TRUE(nlohmann::json::accept(f)) << path;
        } else if (ext == ".csv" || ext == ".md") {
            std::ifstream f(path, std::ios::binary);
            std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
            EXPECT_TRUE(!text.empty() && text.back() == '\n') << path;
        }
    }
}

// A failure under the limit: exit 1, the message names `file`, which does not exist.
void expect_clean_failure(const test::CommandResult& r, const std::string& file, const std::string& dir) {
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find(file), std::string::npos) << "message does not name " << file << ": " << r.output;
    EXPECT_EQ(r.output.find("wrote " + file), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(file)) << file;
    expect_nothing_half_written(dir);
}

const std::string kAnimate =
    " animate builtin --sky procedural:3 --model procedural --sky-res 96 --res 64x36 --spp 2 --duration 0.375 "
    "--fps 8 --dt 0.5 --threads 2 --quiet --out ";

TEST(OutputsCli, FullDiskFailsCleanlyForEveryFormat) {
    const std::string dir = test::temp_dir("outputs_full_disk");
    // render: EXR (and the PNG beside it), PNG.
    auto r = run_with_full_disk("render builtin --res 96x54 --spp 2 --out " + dir + "/r.exr");
    expect_clean_failure(r, dir + "/r.exr", dir);
    r = run_with_full_disk("render builtin --res 96x54 --spp 2 --out " + dir + "/r.png");
    expect_clean_failure(r, dir + "/r.png", dir);
    // The same without the limit: the outputs are well over the limit, so the limit is what failed.
    ASSERT_EQ(test::run_command(kExe + " render builtin --res 96x54 --spp 2 -q --out " + dir + "/ok.png").exit_code, 0);
    EXPECT_GT(fs::file_size(dir + "/ok.png"), 8192u);

    // sky commands: an EXR, its preview PNG, a lat-long EXR from an input sky.
    r = run_with_full_disk("sky clear --lat 48.85 --lon 2.35 --time 2026-06-21T16:00:00Z --sky-res 64 --out " + dir +
                           "/clear.exr");
    expect_clean_failure(r, dir + "/clear.exr", dir);
    ASSERT_EQ(test::run_command(kExe +
                                " sky clear --lat 48.85 --lon 2.35 --time 2026-06-21T16:00:00Z --sky-res 64 "
                                "-q --out " +
                                dir + "/clear.exr")
                  .exit_code,
              0);
    r = run_with_full_disk("sky latlong " + dir + "/clear.exr --out " + dir + "/ll.exr");
    expect_clean_failure(r, dir + "/ll.exr", dir);
    // A folder of outputs: procedural frames, flows, manifest.json.
    r = run_with_full_disk("sky procedural --duration 10 --dt 10 --sky-res 64 --previews --out " + dir + "/proc");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find(dir + "/proc/"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir + "/proc/manifest.json"));
    expect_nothing_half_written(dir);
    // A CSV (sky predict --stats): 200 rows are over 8 kB; the step EXR of a uniform sky compresses to
    // well under 4 kB.
    Image uniform(64, 64, 3);
    uniform.pixels.assign(uniform.pixels.size(), 1.0f);
    write_image(dir + "/uniform.exr", uniform);
    ASSERT_LT(fs::file_size(dir + "/uniform.exr"), 4096u);
    r = run_with_full_disk("sky predict --sky " + dir +
                           "/uniform.exr --model advect --steps 200 --every 1000 --stats " + dir +
                           "/stats.csv -q --out " + dir + "/pred");
    expect_clean_failure(r, dir + "/stats.csv", dir);

    // animate: frames (the PNGs first, the EXR that says a frame is complete last), then (all frames there) the contact sheet, then the chart of `temporal`.
    const std::string anim = dir + "/anim";
    r = run_with_full_disk(kAnimate + anim + " --no-video");
    expect_clean_failure(r, anim + "/frame_0000.png", dir);
    ASSERT_EQ(test::run_command(kExe + kAnimate + anim + " --no-video").exit_code, 0);
    fs::remove(anim + "/contact_sheet.png");
    r = run_with_full_disk(kAnimate + anim + " --no-video");
    expect_clean_failure(r, anim + "/contact_sheet.png", dir);
    r = run_with_full_disk("temporal " + anim);
    expect_clean_failure(r, anim + "/temporal.png", dir);
    // A frame's PNG written, its sky's not (a tiny frame, a large sky): the frame's PNG goes too (it
    // stayed without its EXR).
    const std::string tiny = dir + "/tiny";
    r = run_with_full_disk(
        "animate builtin --sky procedural:3 --model procedural --sky-res 256 --res 8x6 --spp 1 --duration 0.1 --fps 8 "
        "--no-video --quiet --out " +
        tiny);
    expect_clean_failure(r, tiny + "/sky_0000.png", dir);
    EXPECT_FALSE(fs::exists(tiny + "/frame_0000.png"));
    fs::remove_all(dir);
}

// ffmpeg's part: its exit status and its file are checked (a fake ffmpeg first on the PATH, then
// the real one under the size limit; the videos are made before the contact sheet).
// A folder's "complete" marker (a timeline's timeline.json, a procedural sequence's manifest.json)
// goes before a run replaces any of the files it describes: a run into the same folder that stopped
// midway (here a full disk) left the old marker over new files, and the next run kept them.
// What a command prints is an output too: a farm script reading `$(dynsky animate --count-frames)`
// from a full disk or a closed stdout got an empty string and exit 0.
TEST(OutputsCli, StandardOutputThatCannotBeWrittenFails) {
    for (const std::string c : {"animate --count-frames", "sky sun -q", "--version", "--help"}) {
        for (const std::string redirect : {" >/dev/full", " >&-"}) {
            // Grouped: run_command's own 2>&1 then takes stderr alone.
            const auto r = test::run_command("{ " + std::string(DYNSKY_EXE) + " " + c + redirect + "; }");
            EXPECT_EQ(r.exit_code, 1) << c << redirect << "\n" << r.output;
            EXPECT_NE(r.output.find("dynsky: error: standard output:"), std::string::npos) << c << redirect;
        }
        const auto r = test::run_command(std::string(DYNSKY_EXE) + " " + c + " >/dev/null");
        EXPECT_EQ(r.exit_code, 0) << c << "\n" << r.output;
    }
    // A command that prints nothing to stdout does not mind it closed.
    const std::string dir = test::temp_dir("stdout_closed");
    const auto r = test::run_command("{ " + std::string(DYNSKY_EXE) + " sky clear --sky-res 16 -q -o " + dir +
                                     "/c.exr >&-; }");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    fs::remove_all(dir);
}

TEST(OutputsCli, AStoppedRunLeavesNoMarkerOverItsFiles) {
    const std::string dir = test::temp_dir("outputs_marker");
    const std::string tl = dir + "/tl", proc = dir + "/proc";
    ASSERT_EQ(
        test::run_command(kExe + " sky timeline --sky procedural:1 --sky-res 64 --duration 60 -q -o " + tl).exit_code,
        0);
    ASSERT_TRUE(fs::exists(tl + "/timeline.json"));
    auto r = run_with_full_disk("sky timeline --sky procedural:9 --sky-res 64 --duration 60 -q -o " + tl);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_FALSE(fs::exists(tl + "/timeline.json")) << "the old description stayed over new steps";
    ASSERT_EQ(test::run_command(kExe + " sky procedural --sky-res 64 --duration 20 -q -o " + proc).exit_code, 0);
    ASSERT_TRUE(fs::exists(proc + "/manifest.json"));
    r = run_with_full_disk("sky procedural --cloud-seed 7 --sky-res 64 --duration 20 -q -o " + proc);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_FALSE(fs::exists(proc + "/manifest.json")) << "the old manifest stayed over new frames";
    fs::remove_all(dir);
}

// A run holds its output folder: a second run into it while the first works is refused (exit 1,
// naming the folder) before it touches anything there; two at once had each finished
// "successfully" with the other's files mixed into theirs (frames of two seeds under one manifest,
// compare's images of one run beside the other's illuminance chart).
TEST(OutputsCli, ASecondRunIntoAFolderInUseIsRefused) {
    const std::string dir = test::temp_dir("outputs_held"), out = dir + "/out";
    ASSERT_EQ(test::run_command(kExe + " sky clear --sky-res 32 --lat 48 --lon 2 --time 2026-06-21T12:00Z -q -o " +
                                dir + "/in.exr")
                  .exit_code,
              0);
    const OutputFolder held(out);  // as the first run holds it
    std::ofstream(out + "/frame_0000.exr") << "the first run's";
    for (const std::string& args :
         {"sky procedural --sky-res 32 --duration 10 -q -o " + out,
          "sky timeline --sky-res 32 --duration 30 -q -o " + out,
          "sky predict --model advect --in " + dir + "/in.exr --steps 1 -q --out " + out,
          "compare builtin --res 16x9 --spp 1 --sky-res 32 --duration 10 -q -o " + out,
          "animate builtin --res 16x9 --spp 1 --sky-res 32 --duration 1 --fps 1 -q --no-video --out " + out}) {
        const auto r = test::run_command(kExe + " " + args + " 2>&1");
        EXPECT_EQ(r.exit_code, 1) << args << ": " << r.output;
        EXPECT_NE(r.output.find(out + ": another dynsky run is writing into this folder"), std::string::npos)
            << args << ": " << r.output;
    }
    std::ifstream f(out + "/frame_0000.exr");
    std::string kept((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    EXPECT_EQ(kept, "the first run's");
    fs::remove_all(dir);
}

// compare is not resumable: a run that stops midway (here a full disk) leaves no earlier run's
// outputs beside its own (its new images beside an old illuminance chart read as one result).
TEST(OutputsCli, AStoppedCompareLeavesNoEarlierRunsFiles) {
    const std::string dir = test::temp_dir("outputs_compare_mix"), out = dir + "/cmp";
    ASSERT_EQ(test::run_command(kExe + " compare builtin --res 16x9 --spp 1 --sky-res 32 --duration 10 -q -o " + out)
                  .exit_code,
              0);
    ASSERT_TRUE(fs::exists(out + "/illuminance.csv"));
    const auto r = run_with_full_disk("compare builtin --res 160x90 --spp 1 --sky-res 64 --duration 10 -q -o " + out);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_FALSE(fs::exists(out + "/illuminance.csv")) << "the earlier run's chart data stayed: " << r.output;
    EXPECT_FALSE(fs::exists(out + "/illuminance.png"));
    expect_nothing_half_written(dir);
    fs::remove_all(dir);
}

// An output that cannot be written is found before the work, not after it (minutes of render).
TEST(OutputsCli, AnUnwritableOutputIsRefusedBeforeAnyWork) {
    const std::string dir = test::temp_dir("outputs_blocked");
    std::ofstream(dir + "/afile") << "x\n";
    fs::create_directories(dir + "/taken.exr");
    fs::create_directories(dir + "/report.md");
    fs::create_directories(dir + "/cmp/illuminance.png");  // compare found it after all its rendering
    struct Case {
        std::string args, message;
    } cases[] = {
        {"render builtin --res 16x9 --spp 1 -q -o " + dir + "/afile/x.exr", "is a file"},
        {"render builtin --res 16x9 --spp 1 -q -o " + dir + "/taken.exr", "a folder of that name is in the way"},
        {"sky evaluate --model advect --no-paper --sequence arm-clear --limit 1 --resolutions 64 --horizons 1 -q -o " +
             dir + "/report.md",
         "a folder of that name is in the way"},
        {"compare builtin --res 16x9 --spp 1 --chart-res 8x4 --chart-spp 1 -q -o " + dir + "/cmp",
         "a folder of that name is in the way"},
    };
    for (const Case& c : cases) {
        const auto r = test::run_command(kExe + " " + c.args + " 2>&1");
        EXPECT_EQ(r.exit_code, 1) << c.args << "\n" << r.output;
        EXPECT_NE(r.output.find(c.message), std::string::npos) << c.args << "\n" << r.output;
    }
    EXPECT_FALSE(fs::exists(dir + "/report.csv"));  // nothing of the report written beside it
    EXPECT_FALSE(fs::exists(dir + "/report_64.csv"));
    EXPECT_FALSE(fs::exists(dir + "/cmp/clear.exr"));  // nothing rendered
    fs::remove_all(dir);
}

TEST(OutputsCli, FailedVideoFailsCleanly) {
    const std::string dir = test::temp_dir("outputs_video");
    const std::string anim = dir + "/anim", bin = dir + "/bin";
    const std::string animate = kAnimate + anim + " --res 320x180 --spp 1";
    ASSERT_EQ(test::run_command(kExe + animate + " --no-video").exit_code, 0);
    fs::create_directories(bin);
    // Writes half a file to its last argument and fails, as ffmpeg does on a full disk.
    std::ofstream(bin + "/ffmpeg") << "#!/bin/sh\nfor a; do out=$a; done\nprintf 'half' > \"$out\"\nexit 1\n";
    fs::permissions(bin + "/ffmpeg", fs::perms::owner_all);
    auto r = test::run_command("PATH=" + bin + ":$PATH " + kExe + animate);
    expect_clean_failure(r, anim + "/animation.mp4", dir);
    EXPECT_NE(r.output.find("ffmpeg failed (exit 1)"), std::string::npos) << r.output;
    // Exits 0 but writes nothing: still an error.
    std::ofstream(bin + "/ffmpeg") << "#!/bin/sh\nexit 0\n";
    r = test::run_command("PATH=" + bin + ":$PATH " + kExe + animate);
    expect_clean_failure(r, anim + "/animation.mp4", dir);
    EXPECT_NE(r.output.find("wrote no file"), std::string::npos) << r.output;
    // ffmpeg exits 0 here though its trailer's write fails: the file is checked.
    r = run_with_full_disk(animate);
    expect_clean_failure(r, anim + "/animation.mp4", dir);
    EXPECT_NE(r.output.find("incomplete"), std::string::npos) << r.output;
    ASSERT_EQ(test::run_command(kExe + animate).exit_code, 0);
    EXPECT_GT(fs::file_size(anim + "/animation.mp4"), 8192u);  // so the limit is what failed
    fs::remove_all(dir);
}

// Interrupted while ffmpeg encodes: dynsky stops it, removes the video's temporary and exits 3
// (docs/exit-codes.md). Under std::system a kill -INT of dynsky was ignored until ffmpeg ended, and a
// SIGTERM left ffmpeg running on with its temporary.
TEST(OutputsCli, InterruptedWhileEncodingStopsTheEncoderAndLeavesNothing) {
    const std::string dir = test::temp_dir("outputs_encode_interrupt");
    const std::string anim = dir + "/anim", bin = dir + "/bin";
    const std::string animate = kAnimate + anim + " --res 64x36 --spp 1";
    ASSERT_EQ(test::run_command(kExe + animate + " --no-video").exit_code, 0);
    fs::create_directories(bin);
    // Starts its output and then takes its time, as a long encode does.
    std::ofstream(bin + "/ffmpeg") << "#!/bin/sh\nfor a; do out=$a; done\nprintf 'half' > \"$out\"\nexec sleep 41.5\n";
    fs::permissions(bin + "/ffmpeg", fs::perms::owner_all);
    for (const char* sig : {"INT", "TERM"}) {
        auto r =
            test::run_command("PATH=" + bin + ":$PATH " + kExe + animate + " & p=$!; sleep 3; kill -" + sig +
                              " $p; wait $p; echo \"rc=$?\"; sleep 0.5; pgrep -f 'sleep 41[.]5' || echo 'no encoder'");
        EXPECT_NE(r.output.find("rc=3"), std::string::npos) << sig << ": " << r.output;
        EXPECT_NE(r.output.find("no encoder"), std::string::npos) << sig << ": " << r.output;
        EXPECT_FALSE(fs::exists(anim + "/animation.mp4")) << sig;
        for (const auto& e : fs::directory_iterator(anim))
            EXPECT_NE(e.path().filename().string().rfind(".tmp-", 0), 0u) << sig << ": " << e.path();
    }
    fs::remove_all(dir);
}

// Long runs never lose finished work: an interrupted render (Ctrl-C, a farm's SIGTERM) finishes its
// round of samples and writes the image of the samples taken, marked so, and exits 3. It wrote
// nothing before, however many hours it had run.
TEST(OutputsCli, AnInterruptedRenderWritesTheImageOfTheSamplesTaken) {
    const std::string dir = test::temp_dir("outputs_render_interrupt");
    for (const char* sig : {"INT", "TERM"}) {
        const std::string out = dir + "/r_" + sig + ".exr", log = dir + "/log_" + sig;
        // Interrupted once the render is under way (its progress line is out).
        auto r = test::run_command(kExe + " render builtin --res 48x27 --sky-res 64 --spp 1000000 --out " + out +
                                   " 2> " + log + " & p=$!; for i in $(seq 600); do grep -qF 'render [' " + log +
                                   " && break; sleep 0.1; done; sleep 0.5; kill -" + sig +
                                   " $p; wait $p; echo \"rc=$?\"; cat " + log);
        EXPECT_NE(r.output.find("rc=3"), std::string::npos) << sig << ": " << r.output;
        EXPECT_NE(r.output.find("writing the image of the"), std::string::npos) << sig << ": " << r.output;
        ASSERT_TRUE(fs::exists(out)) << sig << ": " << r.output;
        EXPECT_TRUE(fs::exists(dir + "/r_" + std::string(sig) + ".png")) << sig;
        const Image im = read_image(out);
        EXPECT_EQ(im.metadata.numbers.at("dynsky:interrupted"), 1.0) << sig;
        EXPECT_GE(im.metadata.numbers.at("dynsky:spp_mean"), 16.0) << sig;  // whole rounds
        EXPECT_LT(im.metadata.numbers.at("dynsky:spp_mean"), 1e6) << sig;
        double sum = 0;
        for (float v : im.pixels) sum += v;
        EXPECT_GT(sum, 0.0) << sig;
        for (const auto& e : fs::directory_iterator(dir))
            EXPECT_NE(e.path().filename().string().rfind(".tmp-", 0), 0u) << sig << ": " << e.path();
    }
    fs::remove_all(dir);
}

// An interrupted evaluation (a long folder of photographs) writes the report of the start frames
// it scored, saying so; before, it wrote nothing until the end.
TEST(OutputsCli, AnInterruptedEvaluationWritesTheReportOfTheFramesScored) {
    DYNSKY_REQUIRE_SHARED();
    const std::string dir = test::temp_dir("outputs_evaluate_interrupt"), log = dir + "/log";
    auto r = test::run_command(kExe + " sky evaluate --sequence arm-tsi --model advect --no-paper --out " + dir +
                               "/e.md 2> " + log + " & p=$!; for i in $(seq 1200); do grep -qF 'evaluate [' " + log +
                               " && break; sleep 0.1; done; sleep 0.5; kill -INT $p; wait $p; echo \"rc=$?\"; cat " +
                               log);
    EXPECT_NE(r.output.find("rc=3"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("finishing the start frame under way, then writing the report"), std::string::npos)
        << r.output;
    std::ifstream in(dir + "/e.md");
    const std::string md((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(md.find("STOPPED by an interrupt after start frame"), std::string::npos) << md;
    EXPECT_NE(md.find("| 6 | 180 s |"), std::string::npos) << md;
    for (const char* f : {"/e.csv", "/e_64.png", "/e_256.png"}) EXPECT_TRUE(fs::exists(dir + f)) << f;
    fs::remove_all(dir);
}

TEST(OutputsCli, OutputThatIsAnInputIsRefusedBeforeAnyWork) {
    const std::string dir = test::temp_dir("outputs_same");
    ASSERT_EQ(test::run_command(kExe +
                                " sky clear --lat 48.85 --lon 2.35 --time 2026-06-21T16:00:00Z --sky-res 32 "
                                "-q --out " +
                                dir + "/a.exr")
                  .exit_code,
              0);
    const auto before = fs::file_size(dir + "/a.exr");
    const auto mtime = fs::last_write_time(dir + "/a.exr");
    for (const std::string& args :
         {"render builtin --res 16x8 --spp 1 --sky " + dir + "/a.exr --out " + dir + "/a.exr",
          "render builtin --res 16x8 --spp 1 --sky " + dir + "/a.exr --out " + dir + "/../" +
              fs::path(dir).filename().string() + "/a.exr",
          "sky latlong " + dir + "/a.exr --out " + dir + "/a.exr",
          "sky import " + dir + "/a.exr --lat 0 --lon 0 --time 2026-06-21T16:00:00Z --radius 10 --center 16,16 --out " +
              dir + "/a.exr"}) {
        auto r = test::run_command(kExe + " " + args);
        EXPECT_EQ(r.exit_code, 1) << args << ": " << r.output;
        EXPECT_NE(r.output.find("is also an input"), std::string::npos) << args << ": " << r.output;
        EXPECT_EQ(fs::file_size(dir + "/a.exr"), before);
        EXPECT_EQ(fs::last_write_time(dir + "/a.exr"), mtime);
    }
    // An animation into the folder of its input sequence.
    fs::create_directories(dir + "/seq");
    fs::copy_file(dir + "/a.exr", dir + "/seq/sky_0000.exr");
    auto r = test::run_command(kExe + " animate builtin --sky " + dir + "/seq --res 16x8 --out " + dir + "/seq");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_FALSE(fs::exists(dir + "/seq/frame_0000.exr"));
    fs::remove_all(dir);
}

TEST(OutputsCli, CompareBenchAndEvaluateRefuseAnOutputThatIsAnInput) {
    const std::string dir = test::temp_dir("outputs_same_reports");
    fs::create_directories(dir + "/cmp");
    ASSERT_EQ(test::run_command(kExe +
                                " sky clear --lat 48.85 --lon 2.35 --time 2026-06-21T16:00:00Z --sky-res 32 -q "
                                "--out " +
                                dir + "/cmp/clear.exr")
                  .exit_code,
              0);
    const std::string sky = dir + "/cmp/clear.exr";
    const auto before = fs::file_size(sky);
    const auto mtime = fs::last_write_time(sky);
    fs::create_directories(dir + "/photos");
    fs::create_directories(dir + "/shared/scenes");
    std::ofstream(dir + "/photos/tsi_sgpC1_20170524164530Z.jpg") << "not read";
    std::ofstream(dir + "/shared/scenes/keep.txt") << "kept\n";
    const std::string compare = " compare builtin --res 16x8 --spp 1 --chart-res 8x4 --chart-spp 1 --sky " + sky;
    struct Case {
        std::string args, says;
    } cases[] = {
        {compare + " --out " + dir + "/cmp", "is also an input"},  // would write cmp/clear.exr over the sky
        {compare + " --out " + sky, "is also an input"},
        {" bench sampling --quick --shared " + dir + "/shared --out " + dir + "/shared", "is also an input"},
        {" bench sampling --quick --shared " + dir + "/shared --out " + dir + "/shared/report",
         "is inside the input folder"},
        {" bench sampling --quick --shared " + dir + "/shared --out " + dir + "/r --cache " + dir + "/shared/scenes",
         "is inside the input folder"},
        {" sky evaluate --photos " + dir + "/photos --preset arm-tsi --out " + dir + "/photos/eval.md",
         "is inside the input folder"},
        {" sky evaluate --photos " + dir + "/photos --preset arm-tsi --out " + dir + "/photos", "is also an input"},
        {" sky evaluate --sequence arm-tsi --shared " + dir + "/shared --out " + dir + "/shared/eval.md",
         "is inside the input folder"},
    };
    for (const Case& c : cases) {
        auto r = test::run_command(kExe + c.args);
        EXPECT_EQ(r.exit_code, 1) << c.args << ": " << r.output;
        EXPECT_NE(r.output.find(c.says), std::string::npos) << c.args << ": " << r.output;
        EXPECT_EQ(fs::file_size(sky), before);
        EXPECT_EQ(fs::last_write_time(sky), mtime);
    }
    // Nothing was written into the input folders.
    EXPECT_EQ(std::distance(fs::directory_iterator(dir + "/cmp"), fs::directory_iterator()), 1);
    EXPECT_EQ(std::distance(fs::directory_iterator(dir + "/photos"), fs::directory_iterator()), 1);
    EXPECT_EQ(std::distance(fs::recursive_directory_iterator(dir + "/shared"), fs::recursive_directory_iterator()), 2);
    fs::remove_all(dir);
}

// Nor a file the scene was read from: `render house.gltf -o Textures/colormap.exr` wrote its PNG
// beside the EXR, over the scene's texture, and exited 0.
TEST(OutputsCli, ASceneTextureIsNeverOverwritten) {
    const std::string dir = test::temp_dir("outputs_texture");
    fs::copy(data_path("scenes/house"), dir + "/house", fs::copy_options::recursive);
    const std::string texture = dir + "/house/Textures/colormap.png";
    const auto before = fs::file_size(texture);
    const auto mtime = fs::last_write_time(texture);
    const std::string render = kExe + " render " + dir + "/house/house.gltf --res 16x8 --spp 1 -q --out ";
    for (const std::string& out : {dir + "/house/Textures/colormap.exr", texture}) {
        auto r = test::run_command(render + out);
        EXPECT_NE(r.exit_code, 0) << out << ": " << r.output;
        EXPECT_NE(r.output.find("is also an input"), std::string::npos) << out << ": " << r.output;
        EXPECT_EQ(fs::file_size(texture), before);
        EXPECT_EQ(fs::last_write_time(texture), mtime);
    }
    EXPECT_FALSE(fs::exists(dir + "/house/Textures/colormap.exr"));
    EXPECT_EQ(test::run_command(render + dir + "/beside.exr").exit_code, 0);  // elsewhere: rendered
    fs::remove_all(dir);
}

// --version names the commit the sources are at (it once named the commit of the first configure,
// 60 commits stale), as does the Software field of a render (util/version.h); a sky file has none
// (an input, hashed by content for resume: made again by another build it is the same sky). Built from a git
// checkout (CI's and the README's): the commit is known.
TEST(OutputsCli, VersionNamesTheCommitBuilt) {
    const auto git = test::run_command("git -C '" + std::string(DYNSKY_SOURCE_DIR) + "' rev-parse --short HEAD 2>&1");
    if (git.exit_code != 0) GTEST_SKIP() << "not a git checkout: " << git.output;
    const std::string head = git.output.substr(0, git.output.find_first_of("\r\n"));
    const auto r = test::run_command(kExe + " --version");
    EXPECT_NE(r.output.find("(commit " + head), std::string::npos) << r.output << " at " << head << " (rebuilt since?)";
    const std::string dir = test::temp_dir("outputs_version");
    ASSERT_EQ(test::run_command(kExe + " sky clear --lat 40 --lon 0 --time 2026-06-21T12:00:00Z --sky-res 16 -q -o " +
                                dir + "/s.exr")
                  .exit_code,
              0);
    EXPECT_EQ(read_image(dir + "/s.exr").metadata.strings.count("Software"), 0u);
    ASSERT_EQ(test::run_command(kExe + " render builtin --sky " + dir + "/s.exr --res 8x6 --spp 1 -q -o " + dir +
                                "/r.exr")
                  .exit_code,
              0);
    EXPECT_EQ(read_image(dir + "/r.exr").metadata.strings["Software"] + "\n", r.output);
    EXPECT_EQ(read_image(dir + "/r.png").metadata.strings["Software"] + "\n", r.output);
    fs::remove_all(dir);
}

// A sky file's header says what re-makes it: two procedural skies of other seeds and coverage, the
// steps of two models, and clear skies placed at other heights had identical headers.
TEST(OutputsCli, SkyFilesSayWhatMadeThem) {
    const std::string dir = test::temp_dir("outputs_sky_source");
    auto source = [&](const std::string& args, const std::string& file) {
        const auto r = test::run_command(kExe + " " + args + " -q");
        EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.output;
        return read_image(dir + "/" + file).metadata.strings["dynsky:source"];
    };
    const std::string clear = "sky clear --lat 48.85 --lon 2.35 --time 2026-06-21T19:30:00Z --sky-res 16 ";
    EXPECT_NE(source(clear + "--elevation 3000 -o " + dir + "/c.exr", "c.exr").find("elevation_m=3000"),
              std::string::npos);
    EXPECT_NE(source(clear + "--no-refraction -o " + dir + "/c.exr", "c.exr").find("refraction=off"),
              std::string::npos);
    const std::string p5 = source("sky procedural --sky-res 32 --duration 10 --cloud-seed 5 --coverage 0.8 -o " + dir +
                                      "/p5",
                                  "p5/frame_0001.exr");
    const std::string p6 = source("sky procedural --sky-res 32 --duration 0 --cloud-seed 6 --coverage 0.3 -o " + dir +
                                      "/p6",
                                  "p6/frame_0000.exr");
    EXPECT_NE(p5.find("seed 5, coverage 0.8"), std::string::npos) << p5;
    EXPECT_NE(p5.find("at t = 10 s"), std::string::npos) << p5;
    EXPECT_NE(p6.find("seed 6, coverage 0.3"), std::string::npos) << p6;
    const std::string step = source("sky predict --model advect --sky " + dir + "/p5/frame_0001.exr --prev " + dir +
                                        "/p5/frame_0000.exr --steps 2 -o " + dir + "/pr",
                                    "pr/step_0002.exr");
    EXPECT_NE(step.find("model advect"), std::string::npos) << step;
    EXPECT_NE(step.find("the motion from " + dir + "/p5/frame_0000.exr"), std::string::npos) << step;
    EXPECT_NE(step.find("step 2 of 2"), std::string::npos) << step;
    EXPECT_NE(step.find("seed 5"), std::string::npos) << "the input's own source: " << step;
    fs::remove_all(dir);
}

TEST(OutputsCli, ExitCodesAndDidYouMean) {
    struct Case {
        std::string args;
        int code;
        std::string says;
    };
    const std::string dir = test::temp_dir("outputs_exit");
    for (const Case& c : std::vector<Case>{
             {"--help", 0, "Exit codes: 0 done; 1 runtime error"},
             {"--version", 0, "dynsky 0."},
             {"", 2, "needs a command: render, sky"},
             {"rendr", 2, "did you mean 'render'?"},
             {"animte --out x", 2, "did you mean 'animate'?"},
             {"sky clera --out x.exr", 2, "did you mean 'clear'?"},
             {"xyzzy", 2, "'xyzzy' is not a command of dynsky"},
             {"render --sppp 4", 2, "did you mean --spp?"},
             {"sky clear --sky-rez 64 --out x.exr", 2, "did you mean --sky-res?"},
             {"render --spp abc", 2, "--spp"},                   // CLI11's 104
             {"sky clear --lat 1", 2, "is required"},            // CLI11's 106
             {"render builtin extra words", 2, "not expected"},  // CLI11's 109
             {"render builtin --spp 0", 2, "--spp: '0' is not a number in 1 .. "},
             {"render builtin --sky " + dir + "/missing.exr", 1, dir + "/missing.exr"},
             // A value left out: the next option was taken for it ("2: no such file", exit 1).
             {"render --sky --spp 2", 2, "--sky: its value is missing (the next word, --spp, is an option)"},
             {"animate --sky --spp 2", 2, "--sky: its value is missing"},
             {"render builtin -o -q", 2, "-o: its value is missing"},
             {"render --sky --help", 0, "Render a glTF 2.0 scene"},                 // help asked is shown
             {"sky import x.jpg --res 64 -o y.exr", 2, "did you mean --sky-res?"},  // --lens
             {"render --sky-resolution 64", 2, "did you mean --sky-res?"},          // --sky
         }) {
        auto r = test::run_command(kExe + " " + c.args);
        EXPECT_EQ(r.exit_code, c.code) << "dynsky " << c.args << ": " << r.output;
        EXPECT_NE(r.output.find(c.says), std::string::npos) << "dynsky " << c.args << ": " << r.output;
    }
    fs::remove_all(dir);
}

// SIGTERM while an output is being written (held mid-write: its temporary is a named pipe that this
// test reads 1000 bytes from and then stops reading): exit 3, the temporary removed, no output.
TEST(OutputsCli, InterruptedWriteLeavesNothing) {
    const std::string dir = test::temp_dir("outputs_interrupt");
    std::ofstream(dir + "/run.sh") << "mkfifo " << dir << "/.tmp-r-$$.exr && exec " << kExe
                                   << " render builtin --res 256x256 --spp 1 -q --out " << dir << "/r.exr\n";
    std::ofstream(dir + "/interrupt.sh") << "sh " << dir << "/run.sh & pid=$!\n"
                                         << "for i in $(seq 1 600); do [ -p " << dir
                                         << "/.tmp-r-$pid.exr ] && break; sleep 0.05; done\n"
                                         << "exec 3< " << dir << "/.tmp-r-$pid.exr\n"
                                         << "head -c 1000 <&3 | wc -c\n"
                                         << "kill -TERM $pid; wait $pid; echo rc=$?\n";
    auto r = test::run_command("sh " + dir + "/interrupt.sh");
    EXPECT_NE(r.output.find("1000"), std::string::npos) << "not held mid-write: " << r.output;
    EXPECT_NE(r.output.find("rc=3"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("interrupted"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir + "/r.exr"));
    for (const auto& e : fs::directory_iterator(dir))
        EXPECT_NE(e.path().filename().string().rfind(".tmp-", 0), 0u) << e.path();
    fs::remove_all(dir);
}

}  // namespace
}  // namespace dynsky
