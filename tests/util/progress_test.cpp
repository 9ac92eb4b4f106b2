#include "util/progress.h"

#include <gtest/gtest.h>

namespace dynsky {
namespace {

// The time left is extrapolated from the rate so far: 25 % done in 10 s leaves 30 s.
TEST(Progress, LineGivesElapsedAndTimeLeftFromTheRateSoFar) {
    std::string line = format_progress("render", 0.25, 10.0);
    EXPECT_NE(line.find(" 25.0%"), std::string::npos) << line;
    EXPECT_NE(line.find("10.0s elapsed"), std::string::npos) << line;
    EXPECT_NE(line.find("30.0s left"), std::string::npos) << line;
    EXPECT_NE(line.find("[#######......................."), std::string::npos) << line;  // 7 of 30 filled
}

TEST(Progress, NoEstimateBeforeAnyProgressAndNoneLeftAtTheEnd) {
    EXPECT_NE(format_progress("x", 0.0, 3.0).find("? left"), std::string::npos);
    EXPECT_NE(format_progress("x", 1.0, 3.0).find("0.0s left"), std::string::npos);
    EXPECT_NE(format_progress("x", 1.7, 3.0).find("100.0%"), std::string::npos);  // clamped
}

}  // namespace
}  // namespace dynsky
