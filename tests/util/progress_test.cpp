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
    // A render stopping at --time-limit 15 said "85.7s left" 10 s in: at most what the limit leaves.
    EXPECT_NE(format_progress("render", 0.1, 10.0, 15.0).find("5.0s left"), std::string::npos);
    EXPECT_NE(format_progress("render", 0.9, 9.0, 15.0).find("1.0s left"), std::string::npos);  // the rate's
    EXPECT_NE(format_progress("render", 0.0, 2.0, 15.0).find("at most 13.0s left"), std::string::npos);
}

// On a terminal narrower than the line, every redraw wrapped and scrolled a new line (an audit at
// 40 columns): the line fits in the width less one, the bar shrinking, then going, then the cut.
TEST(Progress, TheLineFitsTheTerminal) {
    const std::string wide = format_progress("render", 0.5, 1.0, 0, 200);
    EXPECT_NE(wide.find("[###############...............]"), std::string::npos) << wide;
    EXPECT_EQ(wide, format_progress("render", 0.5, 1.0));
    for (int columns : {70, 60, 50, 40, 20, 8, 1}) {
        const std::string line = format_progress("render", 0.5, 1.0, 0, columns);
        EXPECT_LE(int(line.size()), columns - 1) << columns << ": " << line;
        if (columns >= 60) {
            EXPECT_NE(line.find("##"), std::string::npos) << columns << ": " << line;
        }
        if (columns == 40) {
            EXPECT_EQ(line, "render  50.0%  1.0s elapsed, 1.0s left") << line;
        }
    }
}

}  // namespace
}  // namespace dynsky
