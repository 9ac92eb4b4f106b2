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

std::string read_text(const std::string& path) {
    std::ifstream f(path);
    std::ostringstream s;
    s << f.rdbuf();
    return s.str();
}

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
    std::string csv1 = read_text(dir + "/accuracy.csv");
    auto second = test::run_command(cmd);
    ASSERT_EQ(second.exit_code, 0) << second.output;
    EXPECT_NE(second.output.find("finished earlier"), std::string::npos) << second.output;
    // The same rows (2 samplers x 3 spp levels x 2 seeds), read back instead of rendered again.
    std::string csv2 = read_text(dir + "/accuracy.csv");
    EXPECT_EQ(std::count(csv1.begin(), csv1.end(), '\n'), 1 + 2 * 3 * 2);
    EXPECT_EQ(csv1, csv2);
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
