#include "util/math.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

namespace dynsky {
namespace {

TEST(Median, OddSizesGiveTheMiddleValue) {
    EXPECT_EQ(median(std::vector<int>{7}), 7);
    EXPECT_EQ(median(std::vector<int>{3, 1, 2}), 2);
    EXPECT_EQ(median(std::vector<double>{5.5, -1.0, 9.0, 2.0, 2.5}), 2.5);
    EXPECT_EQ(median(std::vector<float>{4, 4, 1, 4, 0}), 4.0f);  // ties
}

TEST(Median, EvenSizesGiveTheUpperOfTheTwoMiddleValues) {
    // Rank n / 2 (from 0): the upper middle value, not the mean of the two.
    EXPECT_EQ(median(std::vector<int>{2, 1}), 2);
    EXPECT_EQ(median(std::vector<int>{4, 1, 3, 2}), 3);
    EXPECT_EQ(median(std::vector<double>{10, 40, 20, 30, 60, 50}), 40.0);
}

TEST(Median, MiddleMeanIsTheStatisticalMedian) {
    // What reports call the median: four scenes' speed-ups 3.51, 2.04, 2.51, 2.20 give 2.355, not 2.51.
    EXPECT_DOUBLE_EQ(middle_mean({3.51, 2.04, 2.51, 2.20}), 2.355);
    EXPECT_DOUBLE_EQ(middle_mean({2.34, 1.62}), 1.98);
    EXPECT_DOUBLE_EQ(middle_mean({5.0, 1.0, 3.0}), 3.0);
    EXPECT_DOUBLE_EQ(middle_mean({7.0}), 7.0);
}

TEST(Median, LeavesTheCallersVectorAlone) {
    const std::vector<int> v = {9, 3, 7, 1, 5};
    std::vector<int> copy = v;
    EXPECT_EQ(median(copy), 5);
    EXPECT_EQ(copy, v);
}

TEST(Quantile, RankIsTheFloorOfQTimesNMinusOne) {
    std::vector<int> v;
    for (int k = 100; k >= 1; --k) v.push_back(k);  // 1..100, reversed
    EXPECT_EQ(quantile(v, 0.0), 1);                 // rank 0: the minimum
    EXPECT_EQ(quantile(v, 1.0), 100);               // rank n - 1: the maximum
    EXPECT_EQ(quantile(v, 0.5), 50);                // floor(49.5) = 49
    EXPECT_EQ(quantile(v, 0.25), 25);               // floor(24.75) = 24
    EXPECT_EQ(quantile(v, 0.9), 90);                // floor(89.1) = 89
    // 11 values 0, 10, ..., 100: q (n - 1) = 10 q is a whole rank for q = 0.1 k.
    std::vector<double> w;
    for (int k = 10; k >= 0; --k) w.push_back(10.0 * k);
    EXPECT_EQ(quantile(w, 0.3), 30.0);
    EXPECT_EQ(quantile(w, 0.75), 70.0);  // floor(7.5) = 7
    EXPECT_EQ(quantile(std::vector<float>{3.5f}, 0.99), 3.5f);
}

TEST(Quantile, EightBitValuesWork) {
    // As photo import uses it on grey levels: 0..255 once each, 99th percentile at rank 252.
    std::vector<unsigned char> v;
    for (int k = 255; k >= 0; --k) v.push_back((unsigned char)k);
    EXPECT_EQ(quantile(v, 0.99), 252);  // floor(0.99 * 255) = floor(252.45)
    EXPECT_EQ(median(v), 128);
}

// On random data (with ties, odd and even sizes), both equal the element of that rank in a
// fully sorted copy.
TEST(Quantile, MatchesTheSortedSampleOnRandomData) {
    std::mt19937 gen(42);
    for (size_t n : {1u, 2u, 3u, 4u, 5u, 10u, 11u, 100u, 101u, 1000u, 4097u}) {
        for (int trial = 0; trial < 5; ++trial) {
            std::vector<float> v(n);
            std::uniform_int_distribution<int> coarse(0, 20);
            std::normal_distribution<float> fine(0.0f, 3.0f);
            for (float& x : v) x = trial % 2 ? float(coarse(gen)) : fine(gen);
            std::vector<float> sorted = v;
            std::sort(sorted.begin(), sorted.end());
            EXPECT_EQ(median(v), sorted[n / 2]) << "n " << n;
            for (double q : {0.0, 0.01, 0.1, 0.5, 0.75, 0.99, 1.0}) {
                const size_t k = size_t(q * double(n - 1));
                ASSERT_LT(k, n);
                EXPECT_EQ(quantile(v, q), sorted[k]) << "n " << n << " q " << q;
            }
        }
    }
}

}  // namespace
}  // namespace dynsky
