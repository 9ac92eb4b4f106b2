#include "sky/noise.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <vector>

namespace dynsky {
namespace {

// Random points spread over many lattice periods (period 256), in lattice units.
struct Point {
    double x, y, t;
};
std::vector<Point> random_points(int count, uint64_t seed, double spread = 2000.0) {
    std::vector<Point> p;
    uint64_t s = seed;
    for (int k = 0; k < count; ++k) {
        double x = (noise_unit(s = noise_hash(s)) - 0.5) * spread;
        double y = (noise_unit(s = noise_hash(s)) - 0.5) * spread;
        double t = noise_unit(s = noise_hash(s)) * spread;
        p.push_back({x, y, t});
    }
    return p;
}

// Sum of the octaves' amplitudes: gain^k, doubled for billowy octaves (noise.h).
double amplitude_sum(int octaves, double gain, int billow_from) {
    double sum = 0, a = 1;
    for (int k = 0; k < octaves; ++k, a *= gain) sum += k >= billow_from ? 2 * a : a;
    return sum;
}

TEST(NoiseHash, IsDeterministicAndSpreadsNeighbouringInputs) {
    EXPECT_EQ(noise_hash(12345), noise_hash(12345));
    std::set<uint64_t> seen;
    int bits_set = 0;
    for (uint64_t k = 0; k < 1000; ++k) {
        uint64_t h = noise_hash(k);
        seen.insert(h);
        bits_set += __builtin_popcountll(h);
        double u = noise_unit(h);
        ASSERT_GE(u, 0.0);
        ASSERT_LT(u, 1.0);
    }
    EXPECT_EQ(seen.size(), 1000u);
    EXPECT_NEAR(bits_set / 1000.0, 32.0, 1.0);  // about half of the 64 bits set, on average
    EXPECT_EQ(noise_unit(0), 0.0);
    EXPECT_LT(noise_unit(~0ull), 1.0);
}

TEST(FractalNoise, IsDeterministicPerSeedAndDiffersBetweenSeeds) {
    FractalNoise a(7, 5, 0.5), b(7, 5, 0.5), c(8, 5, 0.5);
    double sum_ac = 0, sum_aa = 0, sum_cc = 0;
    for (const Point& p : random_points(2000, 1)) {
        float va = a.evaluate(p.x, p.y, p.t).value;
        ASSERT_EQ(va, b.evaluate(p.x, p.y, p.t).value);  // bit for bit, from a separate object
        ASSERT_EQ(va, a.evaluate(p.x, p.y, p.t).value);  // and when asked again
        float vc = c.evaluate(p.x, p.y, p.t).value;
        sum_ac += va * vc, sum_aa += va * va, sum_cc += vc * vc;
    }
    // Another seed is another field: uncorrelated (|r| well under 0.1 for 2000 samples).
    EXPECT_LT(std::abs(sum_ac / std::sqrt(sum_aa * sum_cc)), 0.1);
}

TEST(FractalNoise, StaysWithinTheSumOfItsOctaveAmplitudes) {
    // 3D gradient noise with gradients of length sqrt(2) is bounded by sqrt(3/4) sqrt(2) < 1.23
    // per octave; the billowy |n| - mean is bounded by the same.
    const double bound_per_octave = std::sqrt(0.75) * std::sqrt(2.0);
    for (int billow_from : {1 << 30, 1}) {
        FractalNoise noise(3, 6, 0.55, billow_from);
        const double bound = bound_per_octave * amplitude_sum(6, 0.55, billow_from);
        double lo = 0, hi = 0;
        for (const Point& p : random_points(20000, 2)) {
            float v = noise.evaluate(p.x, p.y, p.t).value;
            ASSERT_TRUE(std::isfinite(v));
            ASSERT_LE(std::abs(v), bound);
            lo = std::min(lo, double(v)), hi = std::max(hi, double(v));
        }
        // Not degenerate: the field spans a good part of its range on both sides of zero.
        EXPECT_LT(lo, -2.5 * noise.sigma()) << billow_from;
        EXPECT_GT(hi, 2.5 * noise.sigma()) << billow_from;
    }
}

TEST(FractalNoise, HasZeroMeanAndTheAdvertisedDeviation) {
    const FractalNoise::OctaveStats& s = FractalNoise::octave_stats();
    // Perlin noise spreads well inside [-1, 1]; its magnitude's mean and spread are positive.
    EXPECT_GT(s.sigma, 0.1f);
    EXPECT_LT(s.sigma, 0.5f);
    EXPECT_GT(s.abs_mean, 0.05f);
    EXPECT_LT(s.abs_mean, s.sigma);  // E|n| <= sqrt(E n^2)
    EXPECT_GT(s.abs_sigma, 0.0f);
    for (int billow_from : {1 << 30, 2}) {
        const int octaves = 4;
        const double gain = 0.5;
        FractalNoise noise(11, octaves, gain, billow_from);
        // sigma^2 = sum over octaves of (amplitude * per-octave sigma)^2.
        double var = 0, a = 1;
        for (int k = 0; k < octaves; ++k, a *= gain)
            var += k >= billow_from ? std::pow(2 * a * s.abs_sigma, 2) : std::pow(a * s.sigma, 2);
        EXPECT_NEAR(noise.sigma(), std::sqrt(var), 1e-5);
        // Measured on independent points: mean 0, deviation sigma() (5 %).
        const int n = 40000;
        double sum = 0, sum2 = 0;
        for (const Point& p : random_points(n, 5, 20000.0)) {
            double v = noise.evaluate(p.x, p.y, p.t).value;
            sum += v, sum2 += v * v;
        }
        double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
        EXPECT_NEAR(mean, 0.0, 5 * noise.sigma() / std::sqrt(n)) << billow_from;
        EXPECT_NEAR(sd, noise.sigma(), 0.05 * noise.sigma()) << billow_from;
    }
}

TEST(FractalNoise, IsSmoothAtSmallScalesAndDecorrelatesAtLarge) {
    FractalNoise noise(21, 1, 0.5);  // one octave: one lattice cell per unit
    const double h = 1e-3;
    double max_step = 0, sum_near = 0, sum_far = 0, sum2 = 0;
    const auto points = random_points(5000, 9);
    for (const Point& p : points) {
        double v = noise.evaluate(p.x, p.y, p.t).value;
        double dx = noise.evaluate(p.x + h, p.y, p.t).value - v;
        double dt = noise.evaluate(p.x, p.y, p.t + h).value - v;
        max_step = std::max({max_step, std::abs(dx), std::abs(dt)});
        sum_near += v * noise.evaluate(p.x + 0.1, p.y, p.t).value;
        sum_far += v * noise.evaluate(p.x + 7.5, p.y - 3.25, p.t).value;
        sum2 += v * v;
    }
    // Perlin noise's gradient is bounded (a few units per lattice cell): steps of 1e-3 move it
    // by well under 1 % of its range.
    EXPECT_LT(max_step, 0.01);
    EXPECT_GT(max_step, 1e-5);  // but it does move
    // Close points agree, points several cells apart do not.
    EXPECT_GT(sum_near / sum2, 0.7);
    EXPECT_LT(std::abs(sum_far / sum2), 0.1);
}

TEST(FractalNoise, OneOctaveRepeatsAfter256TimeUnits) {
    // The first octave runs at one lattice cell per unit of t, and stb_perlin's lattice repeats
    // every 256 cells.
    FractalNoise noise(5, 1, 0.5);
    for (const Point& p : random_points(200, 4, 100.0)) {
        float v = noise.evaluate(p.x, p.y, p.t).value;
        EXPECT_NEAR(noise.evaluate(p.x, p.y, p.t + 256.0).value, v, 1e-4f);
        EXPECT_NEAR(noise.evaluate(p.x, p.y, p.t - 512.0).value, v, 1e-4f);
    }
    // Half a period away it is another value.
    int same = 0;
    for (const Point& p : random_points(200, 4, 100.0))
        same += std::abs(noise.evaluate(p.x, p.y, p.t + 128.0).value - noise.evaluate(p.x, p.y, p.t).value) < 1e-4f;
    EXPECT_LT(same, 10);
}

TEST(FractalNoise, FarFromTheOriginKeepsFullPrecision) {
    // A million lattice units out, float positions are 1/16 apart; the double wrap keeps
    // neighbours 1/100 apart distinct and the field as smooth as near the origin.
    FractalNoise noise(2, 3, 0.5);
    std::set<float> values;
    double max_step = 0;
    float previous = noise.evaluate(1e6, -3e6, 2e6).value;
    for (int k = 1; k <= 100; ++k) {
        float v = noise.evaluate(1e6 + 0.01 * k, -3e6, 2e6).value;
        values.insert(v);
        max_step = std::max(max_step, double(std::abs(v - previous)));
        previous = v;
    }
    EXPECT_GT(values.size(), 95u);
    EXPECT_LT(max_step, 0.1);
}

TEST(FractalNoise, FootprintFadesTheFineOctaves) {
    const int octaves = 4;
    const double gain = 0.6;
    FractalNoise full(17, octaves, gain), first(17, 1, gain);
    const float s = FractalNoise::octave_stats().sigma;
    for (const Point& p : random_points(300, 6)) {
        FractalNoise::Sample all = full.evaluate(p.x, p.y, p.t);
        EXPECT_EQ(all.removed_sigma, 0.0f);
        // Footprints up to 1/4 of the finest octave's cell keep every octave at full weight.
        FractalNoise::Sample kept = full.evaluate(p.x, p.y, p.t, 0.25 / 8);
        EXPECT_EQ(kept.value, all.value);
        EXPECT_EQ(kept.removed_sigma, 0.0f);
        // A footprint of 1/4 cell keeps only the first octave (the second sees 1/2 cell: Nyquist),
        // which is exactly a one-octave noise of the same seed.
        FractalNoise::Sample coarse = full.evaluate(p.x, p.y, p.t, 0.25);
        EXPECT_FLOAT_EQ(coarse.value, first.evaluate(p.x, p.y, p.t).value);
        EXPECT_NEAR(coarse.removed_sigma, s * std::sqrt(std::pow(gain, 2) + std::pow(gain, 4) + std::pow(gain, 6)),
                    1e-5);
        // Between: at 0.3 cells the first octave has weight 2 - 4 * 0.3 = 0.8.
        FractalNoise::Sample partial = full.evaluate(p.x, p.y, p.t, 0.3);
        EXPECT_NEAR(partial.value, 0.8f * first.evaluate(p.x, p.y, p.t).value, 1e-6f);
        EXPECT_NEAR(partial.removed_sigma,
                    s * std::sqrt(0.04 + std::pow(gain, 2) + std::pow(gain, 4) + std::pow(gain, 6)), 1e-5);
        // A footprint of several cells removes everything: the whole deviation is gone.
        FractalNoise::Sample none = full.evaluate(p.x, p.y, p.t, 4.0);
        EXPECT_EQ(none.value, 0.0f);
        EXPECT_NEAR(none.removed_sigma, full.sigma(), 1e-5f);
    }
}

}  // namespace
}  // namespace dynsky
