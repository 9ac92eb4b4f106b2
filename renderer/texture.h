// Image textures with glTF samplers: wrap modes, nearest or bilinear filtering, and colour space.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "util/math.h"

namespace dynsky {

enum class TextureWrap { Repeat, ClampToEdge, MirroredRepeat };
enum class TextureFilter { Nearest, Linear };

class Texture {
  public:
    // texels: width * height * 4 floats (RGBA), row 0 at the top (glTF uv (0, 0) is the top-left).
    // If srgb, RGB are decoded to linear at construction (base colour and emissive textures).
    Texture(std::string name, int width, int height, std::vector<float> rgba, bool srgb,
            TextureWrap wrap_s = TextureWrap::Repeat, TextureWrap wrap_t = TextureWrap::Repeat,
            TextureFilter filter = TextureFilter::Linear);

    // RGBA at glTF uv (u right, v down), filtered and wrapped per the sampler.
    Vec4 evaluate(const Vec2& uv) const;

    int width() const { return width_; }
    size_t memory_bytes() const { return rgba_.capacity() * sizeof(float) + bytes_.capacity(); }
    int height() const { return height_; }
    const std::string& name() const { return name_; }

  private:
    Vec4 texel(int x, int y) const;
    // Byte offset of texel (x, y) in 8-bit storage: 4 x 4 texel tiles of 64 bytes, one cache line
    // each, so a bilinear footprint mostly reads one line instead of two rows' (pbrt's BlockedArray).
    size_t tiled_offset(int x, int y) const {
        return ((size_t(y >> 2) * size_t(tiles_x_) + size_t(x >> 2)) * 16 + size_t((y & 3) * 4 + (x & 3))) * 4;
    }
    // One texel of 8-bit storage (its four bytes at b), decoded.
    Vec4 decoded(const uint8_t* b) const {
        return Vec4(decode_rgb_[b[0]], decode_rgb_[b[1]], decode_rgb_[b[2]], float(b[3]) * (1.0f / 255.0f));
    }
    std::string name_;
    int width_, height_;
    std::vector<float> rgba_;     // float storage (HDR or 16-bit sources)
    std::vector<uint8_t> bytes_;  // 8-bit storage (tiled): 4x less memory and cache traffic
    size_t tiles_at_ = 0;         // bytes_'s first 64-byte boundary: tiles on cache lines
    int tiles_x_ = 0;             // tiles per row (0: float storage)
    const uint8_t* tiles() const { return bytes_.data() + tiles_at_; }
    const float* decode_rgb_ = nullptr;  // byte -> linear value for RGB (sRGB or linear table)
    TextureWrap wrap_s_, wrap_t_;
    TextureFilter filter_;
};

}  // namespace dynsky
