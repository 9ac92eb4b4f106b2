#include "util/chart.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "tests/test_support.h"
#include "util/error.h"

namespace dynsky {
namespace {

// A chart that cannot be made says why in one line (python's last), names the PNG and the data,
// and leaves no PNG.
TEST(LineChart, AFailedChartSaysWhyInOneLineAndLeavesNothing) {
    const std::string dir = test::temp_dir("chart");
    const std::string png = dir + "/chart.png";
    std::string message;
    try {
        make_line_chart(dir + "/no_such.csv", png, "t", "x", "y", false);
    } catch (const Error& e) {
        message = e.what();
    }
    EXPECT_NE(message.find(png), std::string::npos) << message;
    EXPECT_NE(message.find("no_such.csv"), std::string::npos) << message;
    EXPECT_NE(message.find("Error"), std::string::npos) << message;  // FileNotFoundError: ...
    EXPECT_EQ(message.find("Traceback"), std::string::npos) << message;
    EXPECT_FALSE(std::filesystem::exists(png));

    std::ofstream(dir + "/ok.csv") << "x,a\n0,1\n1,2\n";
    make_line_chart(dir + "/ok.csv", png, "t", "x", "y", false);
    EXPECT_GT(std::filesystem::file_size(png), 1000u);
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace dynsky
