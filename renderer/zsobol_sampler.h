// Low-discrepancy samples for the path tracer: Owen-scrambled Sobol points with the pixels
// visited in a randomised Morton (Z) order, after Ahmed and Wonka 2020 ("Screen-space blue-noise
// diffusion of Monte Carlo sampling error via hierarchical ordering of pixels") as pbrt-v4's
// ZSobolSampler does. One global Sobol sequence is shared by all pixels: pixel p's sample i is
// point (morton(p) << log2 spp | i), its base-4 digits shuffled per dimension so neighbouring
// pixels take well-spread parts of it (error as blue noise). Each dimension (pair) uses the first
// two Sobol dimensions with its own hash-based Owen scramble (Burley 2020, "Practical hash-based
// Owen scrambling"), so any number of dimensions stays well stratified in 1D and 2D projections.
// Everything is a pure function of (seed, pixel, sample index, dimension): renders stay the same
// on any number of threads.
#pragma once

#include <cstdint>

#include "renderer/sampling.h"

namespace dynsky {

enum class SamplePattern { Random, ZSobol };

class ZSobolSampler {
  public:
    // width x height: the image (the Morton grid is the next power of two above the larger side);
    // spp: samples per pixel (rounded up to a power of two for the index layout).
    ZSobolSampler(int width, int height, int spp, uint64_t seed) : seed_(mix_bits(seed ^ 0x5DEECE66DULL)) {
        int res = 1, log2_res = 0;
        while (res < std::max(width, height)) res <<= 1, ++log2_res;
        while ((1 << log2_spp_) < spp) ++log2_spp_;
        base4_digits_ = log2_res + (log2_spp_ + 1) / 2;
    }

    // Starts sample `index` of pixel (x, y), at dimension 0.
    void start(int x, int y, int index) {
        morton_ = (interleave(uint32_t(x)) | (interleave(uint32_t(y)) << 1)) << log2_spp_ | uint64_t(index);
        dimension_ = 0;
    }

    // The integrator's interface (as Rng's): the next dimension, or the next two.
    float uniform() {
        uint64_t i = sample_index();
        uint64_t h = mix_bits(uint64_t(dimension_++) ^ seed_);
        return to_unit(scramble(sobol(i, 0), uint32_t(h)));
    }
    Vec2 uniform2() {
        uint64_t i = sample_index();
        uint64_t h = mix_bits(uint64_t(dimension_) ^ seed_);
        dimension_ += 2;
        return Vec2(to_unit(scramble(sobol(i, 0), uint32_t(h))), to_unit(scramble(sobol(i, 1), uint32_t(h >> 32))));
    }

    // Building blocks, public for tests. Sobol dimension 0 (van der Corput) or 1 of index a, as 32 bits.
    static uint32_t sobol(uint64_t a, int dim) {
        uint32_t v = 0, c = 0x80000000u;  // generator column j of the dimension
        for (; a != 0; a >>= 1) {
            if (a & 1) v ^= c;
            // Dimension 0: c_j = 2^(31 - j); dimension 1 (primitive polynomial x + 1): c_j = c_{j-1} ^ (c_{j-1} >> 1).
            c = dim == 0 ? c >> 1 : c ^ (c >> 1);
        }
        return v;
    }
    // Nested uniform (Owen) scramble of the bits of v, most significant first: Laine-Karras style
    // hash on the reversed bits (Burley 2020, listing 2, with his improved constants).
    static uint32_t scramble(uint32_t v, uint32_t seed) {
        uint32_t x = reverse_bits(v);
        x += seed;
        x ^= x * 0x6c50b47cu;
        x ^= x * 0xb82f1e52u;
        x ^= x * 0xc7afe638u;
        x ^= x * 0x8d22f6e6u;
        return reverse_bits(x);
    }

  private:
    static float to_unit(uint32_t v) { return std::min(float(v) * 0x1p-32f, 0x1.fffffep-1f); }
    static uint32_t reverse_bits(uint32_t v) {
        v = ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
        v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
        v = ((v >> 4) & 0x0F0F0F0Fu) | ((v & 0x0F0F0F0Fu) << 4);
        v = ((v >> 8) & 0x00FF00FFu) | ((v & 0x00FF00FFu) << 8);
        return (v >> 16) | (v << 16);
    }
    // Spreads the 16 low bits of v to the even bit positions.
    static uint64_t interleave(uint32_t v) {
        uint64_t x = v & 0xFFFFu;
        x = (x | (x << 8)) & 0x00FF00FFu;
        x = (x | (x << 4)) & 0x0F0F0F0Fu;
        x = (x | (x << 2)) & 0x33333333u;
        x = (x | (x << 1)) & 0x55555555u;
        return x;
    }
    // The Morton index with each base-4 digit permuted by one of the 24 permutations of {0..3},
    // chosen by a hash of the digits above it and the dimension (a random but consistent shuffle of
    // the quadtree, which keeps every pixel's samples a stratified part of the sequence). An odd
    // log2 spp leaves a last base-2 digit, flipped by a hash bit.
    uint64_t sample_index() const {
        static constexpr uint8_t kPermutations[24][4] = {{0, 1, 2, 3}, {0, 1, 3, 2}, {0, 2, 1, 3}, {0, 2, 3, 1},
                                                         {0, 3, 2, 1}, {0, 3, 1, 2}, {1, 0, 2, 3}, {1, 0, 3, 2},
                                                         {1, 2, 0, 3}, {1, 2, 3, 0}, {1, 3, 2, 0}, {1, 3, 0, 2},
                                                         {2, 1, 0, 3}, {2, 1, 3, 0}, {2, 0, 1, 3}, {2, 0, 3, 1},
                                                         {2, 3, 0, 1}, {2, 3, 1, 0}, {3, 1, 2, 0}, {3, 1, 0, 2},
                                                         {3, 2, 1, 0}, {3, 2, 0, 1}, {3, 0, 2, 1}, {3, 0, 1, 2}};
        const bool odd = log2_spp_ & 1;
        const uint64_t salt = 0x55555555ull * uint64_t(dimension_) ^ seed_;
        uint64_t index = 0;
        for (int i = base4_digits_ - 1; i >= (odd ? 1 : 0); --i) {
            int shift = 2 * i - (odd ? 1 : 0);
            int digit = int((morton_ >> shift) & 3);
            uint64_t higher = morton_ >> (shift + 2);
            int p = int((mix_bits(higher ^ salt) >> 24) % 24);
            index |= uint64_t(kPermutations[p][digit]) << shift;
        }
        if (odd) index |= (morton_ & 1) ^ (mix_bits((morton_ >> 1) ^ salt) & 1);
        return index;
    }

    uint64_t seed_;
    int log2_spp_ = 0, base4_digits_ = 0;
    uint64_t morton_ = 0;
    int dimension_ = 0;
};

}  // namespace dynsky
