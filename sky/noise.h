// Band-limited fractal gradient noise over a plane and time, for procedural clouds.
//
// The gradient noise itself is stb_perlin's 3D Perlin noise (libstb-dev); this adds what clouds
// need on top: a seed-dependent domain per octave (offset and rotation, so 2^64 seeds give distinct
// fields and octaves do not share lattice lines), a time axis that evolves small octaves faster
// than large ones (Kolmogorov: an eddy's turnover time grows as its size^(2/3)), double-precision wrapping (Perlin's period is 256 lattice cells) so positions
// hundreds of kilometres away keep full float precision, and octave fading by pixel footprint so
// that clouds near the horizon, where a pixel covers kilometres of the layer, do not alias.
#pragma once

#include <cstdint>
#include <vector>

namespace dynsky {

class FractalNoise {
  public:
    // octaves: number of frequency doublings; gain: amplitude ratio between successive octaves.
    // billow_from: octaves from this index on are "billowy" (|noise| minus its mean), whose
    // creases at the zero crossings give thresholded clouds rounded, cauliflower lobes.
    FractalNoise(uint64_t seed, int octaves, double gain, int billow_from = 1 << 30);

    struct Sample {
        float value = 0.0f;          // the fBm value (zero mean)
        float removed_sigma = 0.0f;  // standard deviation of the octaves faded out by the footprint
    };

    // Noise at plane point (x, y) and time coordinate t, all in lattice units of the first octave.
    // footprint: the size of the pixel's footprint in the same units (0 keeps every octave);
    // octaves finer than about two per footprint are faded out. Thread-safe, deterministic.
    Sample evaluate(double x, double y, double t, double footprint = 0.0) const;

    // Standard deviation of the full fBm (all octaves), from the single-octave deviation.
    float sigma() const { return total_sigma_; }
    int octaves() const { return int(octaves_.size()); }

    // Statistics of one octave of stb_perlin's noise (measured once, deterministically): the
    // standard deviation of the noise, and the mean and standard deviation of its magnitude.
    struct OctaveStats {
        float sigma, abs_mean, abs_sigma;
    };
    static const OctaveStats& octave_stats();

  private:
    struct Octave {
        double frequency;  // lattice cells per unit
        double time_rate;  // lattice cells per unit of t
        double offset_x, offset_y, offset_t;
        double cos_r, sin_r;  // domain rotation
        float amplitude;
        bool billow;
        unsigned char seed;  // stb_perlin's permutation offset
    };
    std::vector<Octave> octaves_;
    float total_sigma_ = 0.0f;
};

// A 64-bit mixing function (SplitMix64 finaliser): seeds to well-spread pseudo-random bits.
uint64_t noise_hash(uint64_t x);
// Uniform double in [0, 1) from hashed bits.
inline double noise_unit(uint64_t bits) { return double(bits >> 11) * (1.0 / 9007199254740992.0); }

}  // namespace dynsky
