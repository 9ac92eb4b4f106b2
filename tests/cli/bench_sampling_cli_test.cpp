// `dynsky bench sampling`: a stopped long run resumes from its finished cases, and bad
// selections fail before any work.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "tests/test_support.h"

namespace dynsky {
namespace {

namespace fs = std::filesystem;

using test::read_text;

TEST(BenchSamplingCli, FinishedCasesAreKeptAndReused) {
    DYNSKY_REQUIRE_SHARED();
    std::string dir = test::temp_dir("bench_resume");
    std::string cmd =
        std::string(DYNSKY_EXE) +
        " bench sampling --quick --skies clear --scenes diffuse --samplers cdf,cdf+mis --parts accuracy --out " + dir +
        " 2>&1";
    auto first = test::run_command(cmd);
    ASSERT_EQ(first.exit_code, 0) << first.output;
    EXPECT_EQ(first.output.find("finished earlier"), std::string::npos) << first.output;
    std::string csv1 = read_text(dir + "/accuracy.csv"), summary1 = read_text(dir + "/accuracy_summary.csv");
    auto second = test::run_command(cmd);
    ASSERT_EQ(second.exit_code, 0) << second.output;
    EXPECT_NE(second.output.find("finished earlier"), std::string::npos) << second.output;
    // The same rows (2 samplers x 3 spp levels x 2 seeds), read back instead of rendered again.
    std::string csv2 = read_text(dir + "/accuracy.csv");
    EXPECT_EQ(std::count(csv1.begin(), csv1.end(), '\n'), 1 + 2 * 3 * 2);
    EXPECT_EQ(csv1, csv2);
    // And the summary made from them: the cache once kept six digits, and 64 summary numbers moved.
    EXPECT_EQ(summary1, read_text(dir + "/accuracy_summary.csv"));
    // Charts that cannot be written (files limited to 40 KB: a full disk) fail the run, naming why;
    // the chart of the earlier run stays whole and no temporary is left.
    const std::string chart = dir + "/rmse_diffuse_clear.png", before = read_text(chart);
    ASSERT_GT(before.size(), 41000u) << "the chart is too small for this test's limit";
    auto third = test::run_command("bash -c 'ulimit -f 40; " + cmd + "'");
    EXPECT_EQ(third.exit_code, 1) << third.output;
    EXPECT_NE(third.output.find("the charts were not written"), std::string::npos) << third.output;
    EXPECT_NE(third.output.find("File too large"), std::string::npos) << third.output;
    EXPECT_EQ(read_text(chart), before);
    for (const auto& e : fs::directory_iterator(dir))
        EXPECT_NE(e.path().filename().string().rfind(".tmp-", 0), 0u) << e.path();
    fs::remove_all(dir);
}

TEST(BenchSamplingCli, BadSelectionsFail) {
    std::string dir = test::temp_dir("bench_bad");
    for (const char* bad :
         {"--skies cloudy", "--scenes sponza", "--samplers nonsense", "--parts everything", "--seeds 0"}) {
        auto r = test::run_command(std::string(DYNSKY_EXE) + " bench sampling --quick " + bad + " --out " + dir +
                                   "/x 2>&1");
        EXPECT_NE(r.exit_code, 0) << bad << ": " << r.output;
        EXPECT_FALSE(fs::exists(dir + "/x")) << bad << ": nothing may be written";
    }
    // A data folder without the scenes: an input missing (exit 1, naming it), not a usage error,
    // and no empty report or cache folder left behind.
    auto r = test::run_command(std::string(DYNSKY_EXE) +
                               " bench sampling --quick --parts accuracy --skies clear --scenes diffuse --shared " +
                               dir + "/nowhere --out " + dir + "/y 2>&1");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find(dir + "/nowhere"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir + "/y")) << r.output;
    fs::remove_all(dir);
}

}  // namespace
}  // namespace dynsky
