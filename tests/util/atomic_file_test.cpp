// Output files (util/atomic_file.h, util/image.h): a failed write (here a file size limit, as a full
// disk) throws naming the file and leaves neither a file under the final name nor a temporary;
// temporaries of killed runs are recognised and removed, those of live processes kept; an output
// that is an input is refused; "did you mean" (util/suggest.h).
#include "util/atomic_file.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>

#include "tests/test_support.h"
#include "util/error.h"
#include "util/image.h"
#include "util/suggest.h"

namespace dynsky {
namespace {

namespace fs = std::filesystem;

int count_entries(const std::string& dir) {
    int n = 0;
    for (const auto& e : fs::directory_iterator(dir)) n += e.path().filename() != "" ? 1 : 0;
    return n;
}

// Runs `write` in a child process whose files may not exceed limit_bytes (RLIMIT_FSIZE, SIGXFSZ
// ignored: the write fails with EFBIG as on a full disk). Returns the child's exit status: 0 if the
// write threw a dynsky::Error naming `path`, 1 if it did not throw (it wrote), 2 if the message
// lacked the path.
int write_under_size_limit(rlim_t limit_bytes, const std::string& path, void (*write)(const std::string&)) {
    pid_t pid = ::fork();
    if (pid == 0) {
        ::signal(SIGXFSZ, SIG_IGN);
        rlimit r{limit_bytes, limit_bytes};
        ::setrlimit(RLIMIT_FSIZE, &r);
        try {
            write(path);
        } catch (const Error& e) {
            ::_exit(std::string(e.what()).find(path) != std::string::npos ? 0 : 2);
        }
        ::_exit(1);
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 100 + WTERMSIG(status);
}

void write_big_file(const std::string& path) { write_file_atomic(path, std::string(100000, 'x')); }
// Noise, so that compression keeps the files well over the limits.
Image noise(int size) {
    Image image(size, size, 3);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (float& v : image.pixels) v = u(rng);
    return image;
}
void write_big_exr(const std::string& path) { write_image(path, noise(128)); }
void write_big_png(const std::string& path) { write_image(path, noise(128)); }

TEST(AtomicFile, FailedWritesLeaveNothingAndNameTheFile) {
    const std::string dir = test::temp_dir("atomic_fsize");
    for (auto [name, write] : {std::pair{"report.csv", &write_big_file}, std::pair{"frame.exr", &write_big_exr},
                               std::pair{"frame.png", &write_big_png}}) {
        const std::string path = dir + "/" + name;
        EXPECT_EQ(write_under_size_limit(8192, path, write), 0) << name;
        EXPECT_FALSE(fs::exists(path)) << name;
        EXPECT_EQ(count_entries(dir), 0) << name << ": a temporary was left";
        // Without the limit the same write succeeds. (Every write runs in a child: a process that
        // started the image libraries' threads must not fork.)
        EXPECT_EQ(write_under_size_limit(RLIM_INFINITY, path, write), 1) << name;
        EXPECT_GT(fs::file_size(path), 8192u) << name;
        // A failed rewrite leaves the previous file as it was.
        auto before = fs::file_size(path);
        EXPECT_EQ(write_under_size_limit(4096, path, write), 0) << name;
        EXPECT_EQ(fs::file_size(path), before) << name;
        EXPECT_EQ(count_entries(dir), 1) << name;
        fs::remove(path);
    }
    fs::remove_all(dir);
}

// A failed write leaves no folders made for it (`render -o new/sub/x.exr` on a full disk left
// new/sub behind, empty); folders that were there, or that hold a file written with it, stay.
void write_pair_into_new_folders(const std::string& dir) {
    write_files_atomic({{dir + "/new/sub/r.exr", "small"}, {dir + "/new/sub/r.png", std::string(100000, 'x')}});
}
TEST(AtomicFile, AFailedWriteLeavesNoFoldersItMade) {
    const std::string dir = test::temp_dir("atomic_folders");
    EXPECT_EQ(write_under_size_limit(8192, dir + "/a/b/report.csv", write_big_file), 0);
    EXPECT_FALSE(fs::exists(dir + "/a"));
    EXPECT_EQ(write_under_size_limit(8192, dir, write_pair_into_new_folders), 0);  // the second fails
    EXPECT_FALSE(fs::exists(dir + "/new"));
    EXPECT_EQ(count_entries(dir), 0);
    fs::create_directories(dir + "/kept");
    EXPECT_EQ(write_under_size_limit(8192, dir + "/kept/report.csv", write_big_file), 0);
    EXPECT_TRUE(fs::is_directory(dir + "/kept"));
    EXPECT_EQ(write_under_size_limit(RLIM_INFINITY, dir + "/a/b/report.csv", write_big_file), 1);
    EXPECT_TRUE(fs::exists(dir + "/a/b/report.csv"));
    fs::remove_all(dir);
}

// Files written together (a render's EXR and PNG): the second failing (over the size limit) leaves
// the first as an earlier run wrote it, and no temporary (it replaced the earlier EXR, then deleted
// it when its PNG failed).
void write_pair(const std::string& dir) {
    write_files_atomic({{dir + "/r.exr", "small"}, {dir + "/r.png", std::string(100000, 'x')}});
}
TEST(AtomicFile, FilesWrittenTogetherChangeNoneWhenOneFails) {
    const std::string dir = test::temp_dir("atomic_pair");
    write_file_atomic(dir + "/r.exr", "earlier");
    EXPECT_EQ(write_under_size_limit(8192, dir, write_pair), 0);  // the error names the PNG, under dir
    std::ifstream f(dir + "/r.exr");
    std::string back((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    EXPECT_EQ(back, "earlier");
    EXPECT_FALSE(fs::exists(dir + "/r.png"));
    EXPECT_EQ(count_entries(dir), 1) << "a temporary was left";
    EXPECT_EQ(write_under_size_limit(RLIM_INFINITY, dir, write_pair), 1);
    EXPECT_EQ(fs::file_size(dir + "/r.exr"), 5u);
    EXPECT_EQ(fs::file_size(dir + "/r.png"), 100000u);
    fs::remove_all(dir);
}

// A file the command reads that one of its numbered outputs would overwrite is refused: named so in
// the output folder, a link there named so (written through), or named so by a link to it.
TEST(AtomicFile, NumberedOutputsSpareTheInputsWhateverTheirLinks) {
    const std::string dir = test::temp_dir("atomic_numbered");
    fs::create_directories(dir + "/out");
    write_file_atomic(dir + "/sky.exr", "sky");
    EXPECT_NO_THROW(check_numbered_outputs_spare(dir + "/out", {"frame"}, {dir + "/sky.exr"}));
    write_file_atomic(dir + "/out/frame_0001.exr", "a frame");
    EXPECT_NO_THROW(check_numbered_outputs_spare(dir + "/out", {"frame"}, {dir + "/sky.exr"}));
    EXPECT_THROW(check_numbered_outputs_spare(dir + "/out", {"frame"}, {dir + "/out/frame_0001.exr"}), Error);
    EXPECT_NO_THROW(check_numbered_outputs_spare(dir + "/out", {"step"}, {dir + "/out/frame_0001.exr"}));
    // Not one of the names written (a scene, a CSV named so): nothing to spare.
    EXPECT_NO_THROW(check_numbered_outputs_spare(dir + "/out", {"frame"}, {dir + "/out/frame_0001.glb"}));
    fs::create_symlink("../sky.exr", dir + "/out/frame_0000.exr");
    EXPECT_THROW(check_numbered_outputs_spare(dir + "/out", {"frame"}, {dir + "/out/frame_0000.exr"}), Error);
    EXPECT_THROW(check_numbered_outputs_spare(dir + "/out", {"frame"}, {dir + "/sky.exr"}), Error);
    fs::remove_all(dir);
}

TEST(AtomicFile, WritesExactBytesAndEmptyFiles) {
    const std::string dir = test::temp_dir("atomic_bytes");
    std::string bytes("a\0b\nc", 5);
    write_file_atomic(dir + "/sub/x.bin", bytes);
    std::ifstream f(dir + "/sub/x.bin", std::ios::binary);
    std::string back((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    EXPECT_EQ(back, bytes);
    write_file_atomic(dir + "/empty.csv", "");
    EXPECT_EQ(fs::file_size(dir + "/empty.csv"), 0u);
    EXPECT_THROW(write_file_atomic(dir + "/empty.csv/inside", "x"), Error);  // a file is no folder
    // Names up to the 255 bytes a file name may have: 82 CJK characters failed (the temporary's name
    // was 11 bytes longer); two long names alike but at their end stay apart.
    std::string long_name;
    for (int k = 0; k < 41; ++k) long_name += "\u65e5\u672c";  // 246 bytes
    for (const char* end : {"x.exr", "y.exr"}) {
        write_file_atomic(dir + "/" + long_name + end, end);
        EXPECT_EQ(fs::file_size(dir + "/" + long_name + end), 5u) << end;
        EXPECT_LE(fs::path(temporary_path(dir + "/" + long_name + end)).filename().string().size(), 255u);
    }
    EXPECT_NE(temporary_path(dir + "/" + long_name + "x.exr"), temporary_path(dir + "/" + long_name + "y.exr"));
    fs::remove_all(dir);
}

// An output named by a symbolic link is written to the file the link names (the link kept); a FIFO
// (or a device) in its place is refused naming it, not replaced by a plain file.
TEST(AtomicFile, OutputsThroughLinksAndOverSpecialFiles) {
    const std::string dir = test::temp_dir("atomic_special");
    write_file_atomic(dir + "/real.csv", "old\n");
    fs::create_symlink("real.csv", dir + "/link.csv");
    write_file_atomic(dir + "/link.csv", "new\n");
    EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir + "/link.csv")));
    std::ifstream f(dir + "/real.csv");
    std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    EXPECT_EQ(text, "new\n");
    ASSERT_EQ(::mkfifo((dir + "/pipe.csv").c_str(), 0600), 0);
    try {
        write_file_atomic(dir + "/pipe.csv", "x\n");
        FAIL() << "a FIFO was replaced";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("pipe.csv"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("is a FIFO"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(fs::is_fifo(fs::status(dir + "/pipe.csv")));
    // The temporary is named after the name given (tools take the format from its extension), and
    // lies beside the linked file; a loop of links is refused.
    fs::create_directories(dir + "/store");
    fs::create_symlink("store/anim", dir + "/animation.mp4");
    TemporaryFile tmp(dir + "/animation.mp4");
    EXPECT_EQ(fs::path(tmp.path()).extension(), ".mp4");
    EXPECT_EQ(fs::path(tmp.path()).parent_path(), fs::path(dir) / "store");
    fs::create_symlink("loop_b", dir + "/loop_a");
    fs::create_symlink("loop_a", dir + "/loop_b");
    EXPECT_THROW(write_file_atomic(dir + "/loop_a", "x"), Error);
    EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir + "/loop_a")));
    fs::remove_all(dir);
}

TEST(AtomicFile, StaleTemporariesOfDeadProcessesAreRemoved) {
    const std::string dir = test::temp_dir("atomic_stale");
    pid_t dead = ::fork();
    if (dead == 0) ::_exit(0);
    ::waitpid(dead, nullptr, 0);
    const std::string d = std::to_string(dead), live = std::to_string(::getppid()), self = std::to_string(::getpid());
    for (const std::string& name : {".tmp-frame_0003-" + d + ".exr", ".tmp-timings-" + d + ".csv",
                                    ".tmp-frame_0004-" + live + ".exr", ".tmp-sky_0001-" + self + ".png",
                                    std::string(".tmp-notours.exr"), std::string("frame_0000.exr"), ".tmp-x-" + d})
        std::ofstream(dir + "/" + name) << "x";
    std::vector<std::string> removed = remove_stale_temporaries(dir);
    std::sort(removed.begin(), removed.end());
    ASSERT_EQ(removed.size(), 3u);
    EXPECT_EQ(removed[0], ".tmp-frame_0003-" + d + ".exr");
    EXPECT_EQ(removed[1], ".tmp-timings-" + d + ".csv");
    EXPECT_EQ(removed[2], ".tmp-x-" + d);
    EXPECT_TRUE(fs::exists(dir + "/.tmp-frame_0004-" + live + ".exr"));  // a live process's
    EXPECT_TRUE(fs::exists(dir + "/.tmp-sky_0001-" + self + ".png"));
    EXPECT_TRUE(fs::exists(dir + "/.tmp-notours.exr"));
    EXPECT_TRUE(fs::exists(dir + "/frame_0000.exr"));
    EXPECT_EQ(fs::path(temporary_path(dir + "/frame_0007.exr")).filename().string(),
              ".tmp-frame_0007-" + self + ".exr");
    fs::remove_all(dir);
}

TEST(AtomicFile, OutputsThatAreInputsAreRefused) {
    const std::string dir = test::temp_dir("atomic_inputs");
    std::ofstream(dir + "/a.exr") << "x";
    fs::create_directories(dir + "/seq");
    fs::create_hard_link(dir + "/a.exr", dir + "/link.exr");
    EXPECT_THROW(check_outputs_are_not_inputs({dir + "/a.exr"}, {dir + "/a.exr"}), Error);
    EXPECT_THROW(check_outputs_are_not_inputs({dir + "/./seq/../a.exr"}, {dir + "/a.exr"}), Error);
    EXPECT_THROW(check_outputs_are_not_inputs({dir + "/link.exr"}, {dir + "/a.exr"}), Error);  // the same file
    EXPECT_THROW(check_outputs_are_not_inputs({dir + "/seq"}, {dir + "/seq/"}), Error);
    EXPECT_THROW(check_outputs_are_not_inputs({dir + "/seq/out"}, {dir + "/seq"}), Error);
    try {
        check_outputs_are_not_inputs({"", dir + "/a.exr"}, {"procedural:3", dir + "/a.exr"});
        ADD_FAILURE() << "not refused";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("is also an input"), std::string::npos) << e.what();
    }
    EXPECT_NO_THROW(check_outputs_are_not_inputs({dir + "/b.exr", dir + "/seq2", ""},
                                                 {dir + "/a.exr", dir + "/seq", "builtin"}));
    EXPECT_NO_THROW(check_outputs_are_not_inputs({dir}, {dir + "/a.exr"}));  // a folder holding an input file
    fs::remove_all(dir);
}

TEST(Suggest, ClosestNames) {
    EXPECT_EQ(edit_distance("render", "render"), 0);
    EXPECT_EQ(edit_distance("rendr", "render"), 1);
    EXPECT_EQ(edit_distance("redner", "render"), 1);  // a swap of neighbours is one edit
    EXPECT_EQ(edit_distance("", "sky"), 3);
    std::vector<std::string> commands{"render", "sky", "bench", "animate", "compare", "temporal"};
    EXPECT_EQ(closest_name("rendr", commands), "render");
    EXPECT_EQ(closest_name("animte", commands), "animate");
    EXPECT_EQ(closest_name("skz", commands), "sky");
    EXPECT_EQ(closest_name("anim", commands), "animate");  // the start of a name
    EXPECT_EQ(closest_name("xyzzy", commands), "");
    EXPECT_EQ(closest_name("--sppp", {"--spp", "--seed", "--sky"}), "--spp");
    EXPECT_EQ(closest_name("--outdir", {"--out", "--steps", "--in"}), "--out");  // a longer spelling
    // The qualified name of the same thing, and the longest name a longer spelling starts with
    // (they suggested --lens and --sky).
    EXPECT_EQ(closest_name("--res", {"--lens", "--sky-res", "--out"}), "--sky-res");
    EXPECT_EQ(closest_name("--sky-resolution", {"--sky", "--sky-res", "--spp"}), "--sky-res");
    EXPECT_EQ(closest_name("--output-file", {"--out", "--steps"}), "--out");
    EXPECT_EQ(closest_name("skyfall", {"sky", "render"}), "");  // too short a name to say so
}

}  // namespace
}  // namespace dynsky

namespace dynsky {
namespace {

// A failed command leaves no empty output folders; one with any file in it stays, and so does a
// folder that was there before.
TEST(OutputFolder, RemovesOnlyTheEmptyFoldersItMade) {
    namespace fs = std::filesystem;
    const std::string dir = test::temp_dir("output_folder");
    {
        const OutputFolder f(dir + "/a/b/c");
        EXPECT_TRUE(fs::is_directory(dir + "/a/b/c"));
    }
    EXPECT_FALSE(fs::exists(dir + "/a"));
    EXPECT_TRUE(fs::is_directory(dir));
    {
        const OutputFolder f(dir + "/a/b");
        std::ofstream(dir + "/a/b/frame.exr") << "x";
    }
    EXPECT_TRUE(fs::exists(dir + "/a/b/frame.exr"));
    fs::create_directories(dir + "/kept");
    { const OutputFolder f(dir + "/kept"); }
    EXPECT_TRUE(fs::is_directory(dir + "/kept"));
    fs::remove_all(dir);
}

// Two runs writing one folder at once each finished "successfully" with the other's files mixed
// into theirs: a run holds its folder, and a second is refused naming it while the first lives.
// A farm's frame tasks share one; the folder is free again once its holder is gone.
TEST(OutputFolder, IsHeldByOneRunAtATime) {
    namespace fs = std::filesystem;
    const std::string dir = test::temp_dir("output_folder_lock");
    {
        const OutputFolder first(dir + "/out");
        try {
            const OutputFolder second(dir + "/out");
            FAIL() << "a second run into a held folder was let in";
        } catch (const Error& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find(dir + "/out"), std::string::npos) << what;
            EXPECT_NE(what.find("another dynsky run is writing into this folder"), std::string::npos) << what;
        }
        EXPECT_THROW(OutputFolder(dir + "/out", FolderUse::shared), Error);
        EXPECT_NO_THROW(OutputFolder(dir + "/other"));  // another folder is free
    }
    {
        const OutputFolder task1(dir + "/out", FolderUse::shared), task2(dir + "/out", FolderUse::shared);
        EXPECT_THROW(OutputFolder(dir + "/out"), Error);  // a whole run waits for the farm's tasks
    }
    EXPECT_NO_THROW(OutputFolder(dir + "/out"));  // released
    fs::remove_all(dir);
}

// An earlier run's outputs go before this run writes its own: files only, missing names skipped.
TEST(AtomicFile, EarlierOutputsAreRemovedFilesOnly) {
    namespace fs = std::filesystem;
    const std::string dir = test::temp_dir("earlier_outputs");
    std::ofstream(dir + "/a.png") << "old";
    fs::create_directories(dir + "/sub");
    std::ofstream(dir + "/kept.csv") << "not ours";
    std::ofstream(dir + "/target.exr") << "the user's";
    fs::create_symlink(dir + "/target.exr", dir + "/link.exr");
    remove_earlier_outputs({dir + "/a.png", dir + "/missing.csv", dir + "/sub", "", dir + "/link.exr"});
    EXPECT_FALSE(fs::exists(dir + "/a.png"));
    EXPECT_TRUE(fs::is_symlink(dir + "/link.exr"));  // written through when replaced
    EXPECT_TRUE(fs::exists(dir + "/target.exr"));
    EXPECT_TRUE(fs::is_directory(dir + "/sub"));
    EXPECT_TRUE(fs::exists(dir + "/kept.csv"));
    fs::remove_all(dir);
}

}  // namespace
}  // namespace dynsky
