#include <gtest/gtest.h>

#include "tests/test_support.h"

namespace dynsky {
namespace {

TEST(Cli, HelpListsSubcommands) {
    auto r = test::run_command(std::string(DYNSKY_EXE) + " --help");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("render"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("sky"), std::string::npos) << r.output;
}

TEST(Cli, UnknownSubcommandFails) {
    auto r = test::run_command(std::string(DYNSKY_EXE) + " frobnicate");
    EXPECT_NE(r.exit_code, 0) << r.output;
}

}  // namespace
}  // namespace dynsky
