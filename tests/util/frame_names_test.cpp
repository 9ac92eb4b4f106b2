#include "util/frame_names.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

namespace dynsky {
namespace {

TEST(FrameNames, NumberedNamesRoundTrip) {
    EXPECT_EQ(numbered_name("frame", 7, ".exr"), "frame_0007.exr");
    EXPECT_EQ(numbered_index("/a/b/frame_0007.exr", "frame"), 7);
    EXPECT_EQ(numbered_index("frame_12345.png", "frame"), 12345);
    EXPECT_FALSE(numbered_index("frame_7.exr", "frame"));  // fewer than four digits
    EXPECT_FALSE(numbered_index("sky_0007.exr", "frame"));
}

// A set of more than 10000 names pads every one to its largest number's width, so that they sort
// in order (frame_10000 sorted between frame_1000 and frame_1001), and ffmpeg's pattern follows.
TEST(FrameNames, LargeSetsArePaddedToSortInOrder) {
    EXPECT_EQ(numbered_name("frame", 7, ".exr", 10000), "frame_0007.exr");
    EXPECT_EQ(numbered_name("frame", 7, ".exr", 10001), "frame_00007.exr");
    EXPECT_EQ(numbered_name("frame", 10000, ".exr", 10001), "frame_10000.exr");
    EXPECT_EQ(numbered_name("frame", 7, ".exr", 100001), "frame_000007.exr");
    EXPECT_EQ(numbered_pattern("frame", ".png", 10000), "frame_%04d.png");
    EXPECT_EQ(numbered_pattern("frame", ".png", 10001), "frame_%05d.png");
    std::vector<std::string> names;
    for (int k : {999, 1000, 1001, 9999, 10000, 10001}) names.push_back(numbered_name("frame", k, ".png", 10002));
    EXPECT_TRUE(std::is_sorted(names.begin(), names.end())) << names[1] << " " << names[4];
    EXPECT_EQ(numbered_index(names[0], "frame"), 999);
}

// Folders of frames whose files say no time are taken in the order people number them: "img 10"
// after "img 9" (plain string order put it first, and a captured sequence moved on from the wrong
// last sky, its motion measured backwards).
TEST(FrameNames, NaturalOrderComparesNumbersAsNumbers) {
    const std::vector<std::string> want = {"img 2.exr",   "img 9.exr",   "img 10.exr",   "img 11.exr",
                                           "img 100.exr", "sky (2).jpg", "sky (11).jpg", "sky 007.exr",
                                           "sky 7.exr",   "sky 8.exr",   "skyA.exr",     "skyb.exr"};
    std::vector<std::string> got = want;
    std::mt19937 rng(3);
    for (int trial = 0; trial < 20; ++trial) {
        std::shuffle(got.begin(), got.end(), rng);
        std::sort(got.begin(), got.end(), natural_less);
        EXPECT_EQ(got, want);
    }
    // A strict weak order: irreflexive, asymmetric (std::sort's requirement).
    for (const std::string& a : want) {
        EXPECT_FALSE(natural_less(a, a)) << a;
        for (const std::string& b : want)
            if (a != b) {
                EXPECT_NE(natural_less(a, b), natural_less(b, a)) << a << " / " << b;
            }
    }
    // Timestamps with zero padding keep their plain order.
    EXPECT_TRUE(natural_less("tsi_sgpC1_20170524154000Z.jpg", "tsi_sgpC1_20170524154030Z.jpg"));
    EXPECT_TRUE(natural_less("2020-08-12_09_59.jpg", "2020-08-12_10_00.jpg"));
}

}  // namespace
}  // namespace dynsky
