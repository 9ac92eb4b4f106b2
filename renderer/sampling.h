// Random numbers and the warps the integrator needs.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "util/math.h"

namespace dynsky {

// PCG32 (O'Neill 2014): small state, good statistics, and cheap to seed per pixel, which makes
// renders independent of thread count (each pixel's stream depends only on pixel and seed).
class Rng {
  public:
    Rng(uint64_t seed, uint64_t stream) {
        state_ = 0u;
        inc_ = (stream << 1u) | 1u;
        next_u32();
        state_ += seed;
        next_u32();
    }
    uint32_t next_u32() {
        uint64_t old = state_;
        state_ = old * 6364136223846793005ULL + inc_;
        uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
        uint32_t rot = uint32_t(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((-rot) & 31));
    }
    // Uniform in [0, 1).
    float uniform() { return std::min(float(next_u32()) * 0x1p-32f, 0x1.fffffep-1f); }
    Vec2 uniform2() {
        float a = uniform();
        return Vec2(a, uniform());
    }

  private:
    uint64_t state_, inc_;
};

// (cell + frac) / n in [0, 1), computed in Frac's precision, kept inside the cell (int(v * n) ==
// cell, as the pdf lookups read it back): in float the quotient can round up into the next cell
// when cell is large, and when n is not a power of two cell / n can round down into the previous.
template <typename Frac>
inline float in_cell(int cell, Frac frac, int n) {
    float v = float((cell + frac) / n);
    float lo = float(cell) / n;
    while (int(lo * n) < cell) lo = std::nextafter(lo, 1.0f);
    float hi = std::nextafter(float(cell + 1) / n, 0.0f);
    while (int(hi * n) > cell) hi = std::nextafter(hi, 0.0f);
    return std::clamp(v, lo, hi);
}

// 64-bit mix (splitmix64 finaliser), for deriving per-pixel seeds.
inline uint64_t mix_bits(uint64_t v) {
    v ^= v >> 31;
    v *= 0x7fb5d329728ea185ULL;
    v ^= v >> 27;
    v *= 0x81dadef4bc2dd44dULL;
    v ^= v >> 33;
    return v;
}

// Cosine-weighted direction about +Z (local shading frame), pdf = cos(theta) / pi.
inline Vec3 sample_cosine_hemisphere(const Vec2& u) {
    // Concentric disc mapping (Shirley & Chiu), then project up.
    float a = 2 * u.x() - 1, b = 2 * u.y() - 1;
    float r, phi;
    if (a == 0 && b == 0) return Vec3(0, 0, 1);
    if (std::abs(a) > std::abs(b)) {
        r = a, phi = (kPi / 4) * (b / a);
    } else {
        r = b, phi = (kPi / 2) - (kPi / 4) * (a / b);
    }
    float x = r * std::cos(phi), y = r * std::sin(phi);
    return Vec3(x, y, safe_sqrt(1 - x * x - y * y));
}

// Uniform direction on the hemisphere about +Z, pdf = 1 / (2 pi).
inline Vec3 sample_uniform_hemisphere(const Vec2& u) {
    float z = u.x();
    float r = safe_sqrt(1 - z * z);
    float phi = 2 * kPi * u.y();
    return Vec3(r * std::cos(phi), r * std::sin(phi), z);
}

// Veach's power heuristic (beta = 2) for two strategies, one sample each.
inline float power_heuristic(float pdf_a, float pdf_b) {
    if (std::isinf(pdf_a)) return 1.0f;
    float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
    return a + b > 0 ? a / (a + b) : 0.0f;
}

}  // namespace dynsky
