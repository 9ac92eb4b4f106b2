#include "renderer/sampling.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace dynsky {
namespace {

// The largest float below 1: what Rng::uniform() returns at most.
constexpr float kOneMinus = 0x1.fffffep-1f;

TEST(InCell, ExactFractionsGiveTheExactQuotient) {
    // Dyadic values are exact in float, so (cell + frac) / n comes out exactly.
    EXPECT_EQ(in_cell(3, 0.5f, 8), 0.4375f);
    EXPECT_EQ(in_cell(0, 0.0f, 8), 0.0f);
    EXPECT_EQ(in_cell(7, 0.0f, 8), 0.875f);
    EXPECT_EQ(in_cell(1, 0.25, 4), 0.3125f);  // double fraction
    EXPECT_EQ(in_cell(0, 0.5f, 1), 0.5f);
    // Not dyadic: 1.5 / 3 = 0.5, correctly rounded in either precision.
    EXPECT_EQ(in_cell(1, 0.5f, 3), 0.5f);
    EXPECT_EQ(in_cell(1, 0.5, 3), 0.5f);
}

TEST(InCell, ValuesAtTheEdgesOfACellStayInsideIt) {
    // The naive float quotient rounds up to 1 (outside [0, 1)) for a large last cell...
    const int n = 1 << 20;
    ASSERT_EQ(float((n - 1) + kOneMinus) / n, 1.0f) << "the case this test relies on no longer rounds up";
    // ...in_cell keeps it below 1 and in the last cell, in both precisions.
    float v = in_cell(n - 1, kOneMinus, n);
    EXPECT_LT(v, 1.0f);
    EXPECT_EQ(int(v * n), n - 1);
    float vd = in_cell(n - 1, double(kOneMinus), n);
    EXPECT_LT(vd, 1.0f);
    EXPECT_EQ(int(vd * n), n - 1);
    // n not a power of two: 502 / 1000 rounds down to 0.50199997, which reads back as cell 501;
    // a zero fraction must still give a value in cell 502.
    ASSERT_EQ(int(float(502) / 1000 * 1000), 501) << "the case this test relies on no longer rounds down";
    EXPECT_EQ(int(in_cell(502, 0.0f, 1000) * 1000), 502);
    EXPECT_EQ(int(in_cell(502, 0.0, 1000) * 1000), 502);
    // One cell: the result is the fraction itself.
    EXPECT_EQ(in_cell(0, kOneMinus, 1), kOneMinus);
}

// For every size (powers of two and not, up to 2^24 cells) and cell, fractions from 0 to just
// below 1 land in [0, 1), in that cell (as int(v * n) reads it back), monotonically, and within
// a few ulps of the exact quotient.
TEST(InCell, EveryResultLiesInItsCellNearTheExactQuotient) {
    Rng rng(11, 3);
    for (int n : {1, 2, 3, 7, 10, 255, 1000, 4097, 65536, 99991, 1 << 20, 16777215, 1 << 24}) {
        for (int trial = 0; trial < 300; ++trial) {
            int cell = trial == 0 ? 0 : trial == 1 ? n - 1 : int(rng.next_u32() % uint32_t(n));
            std::vector<float> fracs = {0.0f, 1e-7f, 0.25f, rng.uniform(), 0.5f, 0.999f, 0.9999999f, kOneMinus};
            std::sort(fracs.begin(), fracs.end());
            float previous = -1.0f;
            for (float frac : fracs) {
                float vf = in_cell(cell, frac, n);
                float vd = in_cell(cell, double(frac), n);
                const long double exact = ((long double)cell + frac) / n;
                for (float v : {vf, vd}) {
                    ASSERT_GE(v, 0.0f);
                    ASSERT_LT(v, 1.0f);
                    ASSERT_EQ(int(v * n), cell) << "n " << n << " cell " << cell << " frac " << frac << " v " << v;
                }
                // Within two ulps of the exact quotient in either precision: one rounding (two in
                // float), or, at a cell's edge, the nearest float that still reads back in the cell.
                const long double ulp = std::nextafter(float(exact), 2.0f) - float(exact);
                EXPECT_LE(std::abs((long double)vd - exact), 2.0L * ulp) << n << " " << cell << " " << frac;
                EXPECT_LE(std::abs((long double)vf - exact), 2.0L * ulp) << n << " " << cell << " " << frac;
                EXPECT_GE(vd, previous) << "not monotonic in the fraction";
                previous = vd;
            }
        }
    }
}

}  // namespace
}  // namespace dynsky
