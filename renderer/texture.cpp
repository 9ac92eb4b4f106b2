#include "renderer/texture.h"

#include <cmath>

#include "util/color.h"
#include "util/error.h"

namespace dynsky {
namespace {

// Reduces a texture coordinate to a range where the texel index fits an int, without changing
// which texels the wrap mode selects: Repeat has period 1, MirroredRepeat period 2, and clamping
// beyond [-1, 2] changes nothing. NaN and infinities (from degenerate UVs) read at 0.
float reduce_coordinate(float u, TextureWrap wrap) {
    if (!std::isfinite(u)) return 0.0f;
    switch (wrap) {
        case TextureWrap::Repeat: return u - std::floor(u);
        case TextureWrap::MirroredRepeat: return u - 2.0f * std::floor(0.5f * u);
        case TextureWrap::ClampToEdge: return clamp(u, -1.0f, 2.0f);
    }
    return u;
}

// Texel index i (any integer) to [0, n) per the glTF (OpenGL) wrap mode.
int wrap_index(int i, int n, TextureWrap wrap) {
    switch (wrap) {
        case TextureWrap::Repeat: {
            int m = i % n;
            return m < 0 ? m + n : m;
        }
        case TextureWrap::MirroredRepeat: {
            int period = 2 * n;
            int m = i % period;
            if (m < 0) m += period;
            return m < n ? m : period - 1 - m;
        }
        case TextureWrap::ClampToEdge: return clamp(i, 0, n - 1);
    }
    return 0;
}

}  // namespace

Texture::Texture(std::string name, int width, int height, std::vector<float> rgba, bool srgb, TextureWrap wrap_s,
                 TextureWrap wrap_t, TextureFilter filter)
    : name_(std::move(name)),
      width_(width),
      height_(height),
      rgba_(std::move(rgba)),
      wrap_s_(wrap_s),
      wrap_t_(wrap_t),
      filter_(filter) {
    if (width_ <= 0 || height_ <= 0 || rgba_.size() != size_t(width_) * size_t(height_) * 4)
        throw Error("texture '" + name_ + "': " + std::to_string(rgba_.size()) + " floats do not make a " +
                    std::to_string(width_) + " x " + std::to_string(height_) + " RGBA image");
    // 8-bit sources (nearly every glTF texture) are kept as bytes and decoded by table on lookup:
    // the same values as decoding up front, at a quarter of the memory.
    static const std::vector<float> srgb_table = [] {
        std::vector<float> t(256);
        for (int k = 0; k < 256; ++k) t[size_t(k)] = srgb_to_linear(float(k) * (1.0f / 255.0f));
        return t;
    }();
    static const std::vector<float> linear_table = [] {
        std::vector<float> t(256);
        for (int k = 0; k < 256; ++k) t[size_t(k)] = float(k) * (1.0f / 255.0f);
        return t;
    }();
    bool eight_bit = true;
    for (float v : rgba_) {
        int k = v >= 0.0f && v <= 1.0f ? int(v * 255.0f + 0.5f) : -1;
        if (k < 0 || float(k) * (1.0f / 255.0f) != v) {
            eight_bit = false;
            break;
        }
    }
    if (eight_bit) {
        tiles_x_ = (width_ + 3) / 4;
        const size_t tiled = size_t(tiles_x_) * size_t((height_ + 3) / 4) * 64;
        bytes_.assign(tiled + 63, 0);
        const size_t misalign = reinterpret_cast<uintptr_t>(bytes_.data()) & 63;
        tiles_at_ = misalign ? 64 - misalign : 0;
        uint8_t* tiles = bytes_.data() + tiles_at_;
        for (int y = 0; y < height_; ++y)
            for (int x = 0; x < width_; ++x) {
                const size_t i = (size_t(y) * size_t(width_) + size_t(x)) * 4;
                for (size_t c = 0; c < 4; ++c)
                    tiles[tiled_offset(x, y) + c] = uint8_t(int(rgba_[i + c] * 255.0f + 0.5f));
            }
        decode_rgb_ = srgb ? srgb_table.data() : linear_table.data();
        std::vector<float>().swap(rgba_);
    } else if (srgb) {
        // Alpha is linear in glTF and stays untouched.
        for (size_t i = 0; i < rgba_.size(); i += 4)
            for (size_t c = 0; c < 3; ++c) rgba_[i + c] = srgb_to_linear(rgba_[i + c]);
    }
}

Vec4 Texture::texel(int x, int y) const {
    if (tiles_x_) return decoded(tiles() + tiled_offset(x, y));
    size_t i = (size_t(y) * size_t(width_) + size_t(x)) * 4;
    const float* p = &rgba_[i];
    return Vec4(p[0], p[1], p[2], p[3]);
}

Vec4 Texture::evaluate(const Vec2& uv) const {
    float u = reduce_coordinate(uv.x(), wrap_s_);
    float v = reduce_coordinate(uv.y(), wrap_t_);
    if (filter_ == TextureFilter::Nearest) {
        int x = wrap_index(int(std::floor(u * float(width_))), width_, wrap_s_);
        int y = wrap_index(int(std::floor(v * float(height_))), height_, wrap_t_);
        return texel(x, y);
    }
    // Texel centres sit at (i + 0.5) / size, as in OpenGL's LINEAR filter.
    float fx = u * float(width_) - 0.5f, fy = v * float(height_) - 0.5f;
    float x0f = std::floor(fx), y0f = std::floor(fy);
    float tx = fx - x0f, ty = fy - y0f;
    int x0 = int(x0f), y0 = int(y0f);
    // Inside the image (nearly every lookup) every wrap mode leaves the indices as they are.
    int xa = x0, xb = x0 + 1, ya = y0, yb = y0 + 1;
    if (x0 < 0 || xb >= width_) xa = wrap_index(x0, width_, wrap_s_), xb = wrap_index(x0 + 1, width_, wrap_s_);
    if (y0 < 0 || yb >= height_) ya = wrap_index(y0, height_, wrap_t_), yb = wrap_index(y0 + 1, height_, wrap_t_);
    if (tiles_x_) {
        // The four texels of 8-bit storage decoded in place (texel(), without its branch).
        const uint8_t* t = tiles();
        return (1 - ty) * ((1 - tx) * decoded(t + tiled_offset(xa, ya)) + tx * decoded(t + tiled_offset(xb, ya))) +
               ty * ((1 - tx) * decoded(t + tiled_offset(xa, yb)) + tx * decoded(t + tiled_offset(xb, yb)));
    }
    return (1 - ty) * ((1 - tx) * texel(xa, ya) + tx * texel(xb, ya)) +
           ty * ((1 - tx) * texel(xa, yb) + tx * texel(xb, yb));
}

}  // namespace dynsky
