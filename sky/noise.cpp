#include "sky/noise.h"

#include <cmath>

// stb_perlin's implementation lives in this one translation unit of the whole program.
#define STB_PERLIN_IMPLEMENTATION
#include <stb/stb_perlin.h>

namespace dynsky {

namespace {

constexpr double kPeriod = 256.0;  // stb_perlin repeats every 256 lattice cells on each axis

// Wraps into [0, 256) in double precision before the float noise sees it.
inline float wrap(double x) { return float(x - kPeriod * std::floor(x / kPeriod)); }

}  // namespace

uint64_t noise_hash(uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

const FractalNoise::OctaveStats& FractalNoise::octave_stats() {
    // Perlin noise's spread is not a round number; measure it once on a fixed pseudo-random set.
    static const OctaveStats stats = [] {
        double sum = 0, sum2 = 0, abs_sum = 0;
        const int n = 20000;
        uint64_t state = 12345;
        for (int k = 0; k < n; ++k) {
            double x = noise_unit(state = noise_hash(state)) * kPeriod;
            double y = noise_unit(state = noise_hash(state)) * kPeriod;
            double t = noise_unit(state = noise_hash(state)) * kPeriod;
            double v = stb_perlin_noise3_seed(float(x), float(y), float(t), 0, 0, 0, k & 255);
            sum += v, sum2 += v * v, abs_sum += std::abs(v);
        }
        double mean = sum / n, abs_mean = abs_sum / n;
        OctaveStats s;
        s.sigma = float(std::sqrt(std::max(0.0, sum2 / n - mean * mean)));
        s.abs_mean = float(abs_mean);
        s.abs_sigma = float(std::sqrt(std::max(0.0, sum2 / n - abs_mean * abs_mean)));
        return s;
    }();
    return stats;
}

FractalNoise::FractalNoise(uint64_t seed, int octaves, double gain, int billow_from) {
    const OctaveStats& stats = octave_stats();
    uint64_t state = noise_hash(seed ^ 0x5eedc10dull);
    double frequency = 1.0, amplitude = 1.0, variance = 0.0;
    for (int k = 0; k < octaves; ++k) {
        Octave o;
        o.frequency = frequency;
        o.amplitude = float(amplitude);
        // Small eddies live shorter: Kolmogorov's turnover time scales as size^(2/3).
        o.time_rate = std::pow(frequency, 2.0 / 3.0);
        o.offset_x = noise_unit(state = noise_hash(state)) * kPeriod;
        o.offset_y = noise_unit(state = noise_hash(state)) * kPeriod;
        o.offset_t = noise_unit(state = noise_hash(state)) * kPeriod;
        double angle = noise_unit(state = noise_hash(state)) * 2.0 * 3.14159265358979323846;
        o.cos_r = std::cos(angle), o.sin_r = std::sin(angle);
        o.seed = (unsigned char)(noise_hash(state = noise_hash(state)) & 255);
        o.billow = k >= billow_from;
        // Billowy octaves get twice the amplitude: |noise| spreads about half as much as noise.
        if (o.billow) o.amplitude *= 2.0f;
        octaves_.push_back(o);
        double sigma = o.amplitude * (o.billow ? stats.abs_sigma : stats.sigma);
        variance += sigma * sigma;
        frequency *= 2.0;
        amplitude *= gain;
    }
    total_sigma_ = float(std::sqrt(variance));
}

FractalNoise::Sample FractalNoise::evaluate(double x, double y, double t, double footprint) const {
    Sample s;
    float removed_variance = 0.0f;
    const OctaveStats& stats = octave_stats();
    for (const Octave& o : octaves_) {
        // Cells per footprint: full weight below 1/4, none above 1/2 (Nyquist), linear between.
        double cells = footprint * o.frequency;
        float weight = cells <= 0.25 ? 1.0f : cells >= 0.5 ? 0.0f : float(2.0 - 4.0 * cells);
        if (weight < 1.0f) {
            float removed = (1.0f - weight) * o.amplitude * (o.billow ? stats.abs_sigma : stats.sigma);
            removed_variance += removed * removed;
        }
        if (weight == 0.0f) continue;
        double fx = x * o.frequency, fy = y * o.frequency;
        double rx = o.cos_r * fx - o.sin_r * fy + o.offset_x;
        double ry = o.sin_r * fx + o.cos_r * fy + o.offset_y;
        double rt = t * o.time_rate + o.offset_t;
        float n = stb_perlin_noise3_seed(wrap(rx), wrap(ry), wrap(rt), 0, 0, 0, o.seed);
        if (o.billow) n = std::abs(n) - stats.abs_mean;
        s.value += weight * o.amplitude * n;
    }
    s.removed_sigma = std::sqrt(removed_variance);
    return s;
}

}  // namespace dynsky
