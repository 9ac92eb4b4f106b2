#include "util/colour_space.h"

#include <gtest/gtest.h>

#include "util/error.h"

namespace dynsky {
namespace {

void expect_matrix_near(const Eigen::Matrix3d& m, const Eigen::Matrix3d& reference, double tolerance) {
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(m(r, c), reference(r, c), tolerance) << "row " << r << " col " << c;
}

TEST(ColourSpace, Rec709IsLeftAsItIs) {
    expect_matrix_near(rec709_from(rec709_chromaticities()), Eigen::Matrix3d::Identity(), 1e-6);
}

// Against the published ACES matrices to linear sRGB / Rec.709 (Bradford, D60 -> D65; the ACES
// project's and colour-science's figures to four decimals).
TEST(ColourSpace, AcesPrimariesGiveThePublishedMatrices) {
    Eigen::Matrix3d ap1;
    ap1 << 1.70505, -0.62179, -0.08326, -0.13026, 1.14080, -0.01055, -0.02400, -0.12897, 1.15297;
    expect_matrix_near(rec709_from(aces_ap1_chromaticities()), ap1, 2e-3);
    Eigen::Matrix3d ap0;
    ap0 << 2.52169, -1.13413, -0.38756, -0.27648, 1.37272, -0.09624, -0.01538, -0.15298, 1.16835;
    expect_matrix_near(rec709_from(aces_ap0_chromaticities()), ap0, 2e-3);
    // The white stays white (adapted), so a grey sky stays grey.
    const Eigen::Vector3d white = rec709_from(aces_ap1_chromaticities()) * Eigen::Vector3d::Ones();
    EXPECT_NEAR(white.x(), 1.0, 1e-3);
    EXPECT_NEAR(white.y(), 1.0, 1e-3);
    EXPECT_NEAR(white.z(), 1.0, 1e-3);
}

TEST(ColourSpace, PrimariesThatSpanNothingAreRefused) {
    Chromaticities flat = rec709_chromaticities();
    flat[2] = 0.395f, flat[3] = 0.195f;  // green halfway along the line from red to blue
    EXPECT_THROW(rec709_from(flat), Error);
    Chromaticities zero = rec709_chromaticities();
    zero[7] = 0.0f;
    EXPECT_THROW(rec709_from(zero), Error);
}

TEST(ColourSpace, WhatAHeaderSaysIsRead) {
    EXPECT_FALSE(file_primaries(std::nullopt, false, "Linear"));
    EXPECT_FALSE(file_primaries(rec709_chromaticities(), false, ""));
    EXPECT_EQ(describe_chromaticities(*file_primaries(std::nullopt, true, "")), "AP0 (ACES2065-1)");
    EXPECT_EQ(describe_chromaticities(*file_primaries(std::nullopt, false, "ACEScg")), "AP1 (ACEScg)");
    EXPECT_EQ(describe_chromaticities(*file_primaries(std::nullopt, false, "lin_ap0")), "AP0 (ACES2065-1)");
    // Chromaticities given win over the flag and the name.
    EXPECT_EQ(describe_chromaticities(*file_primaries(aces_ap1_chromaticities(), true, "")), "AP1 (ACEScg)");
}

}  // namespace
}  // namespace dynsky
