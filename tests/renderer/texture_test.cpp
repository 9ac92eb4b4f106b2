#include "renderer/texture.h"

#include <gtest/gtest.h>

#include "util/color.h"
#include "util/error.h"

namespace dynsky {
namespace {

// A w x h texture whose texel (x, y) has R = x, G = y, B = 10 x + y, A = 1 (linear), so every
// expected value below follows from the texel positions by hand.
Texture ramp(int w, int h, TextureWrap ws, TextureWrap wt, TextureFilter f) {
    std::vector<float> rgba;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) rgba.insert(rgba.end(), {float(x), float(y), float(10 * x + y), 1.0f});
    return Texture("ramp", w, h, rgba, false, ws, wt, f);
}

void expect_vec4(const Vec4& got, const Vec4& want, float tol = 1e-5f) {
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(got[c], want[c], tol) << "channel " << c;
}

TEST(Texture, NearestPicksTheTexelContainingUvWithRowZeroAtTheTop) {
    Texture t = ramp(4, 2, TextureWrap::Repeat, TextureWrap::Repeat, TextureFilter::Nearest);
    // u in [0.5, 0.75) is column 2; v in [0.5, 1) is row 1 (the bottom row).
    expect_vec4(t.evaluate(Vec2(0.6f, 0.7f)), Vec4(2, 1, 21, 1));
    expect_vec4(t.evaluate(Vec2(0.01f, 0.01f)), Vec4(0, 0, 0, 1));
    expect_vec4(t.evaluate(Vec2(0.99f, 0.49f)), Vec4(3, 0, 30, 1));
}

TEST(Texture, BilinearInterpolatesBetweenTexelCentres) {
    Texture t = ramp(4, 4, TextureWrap::ClampToEdge, TextureWrap::ClampToEdge, TextureFilter::Linear);
    // Texel centres at (i + 0.5) / 4. uv (0.5, 0.75) is halfway between columns 1 and 2 and rows 2
    // and 3 => R = 1.5, G = 2.5, B = 10 * 1.5 + 2.5.
    expect_vec4(t.evaluate(Vec2(0.5f, 0.75f)), Vec4(1.5f, 2.5f, 17.5f, 1));
    // A quarter of the way from column 0's centre (u = 0.125) to column 1's: R = 0.25.
    expect_vec4(t.evaluate(Vec2(0.125f + 0.0625f, 0.125f)), Vec4(0.25f, 0, 2.5f, 1));
    // Exactly on a texel centre gives that texel.
    expect_vec4(t.evaluate(Vec2(0.625f, 0.875f)), Vec4(2, 3, 23, 1));
}

TEST(Texture, RepeatWrapsWithPeriodOneAndBlendsAcrossTheSeam) {
    Texture n = ramp(4, 4, TextureWrap::Repeat, TextureWrap::Repeat, TextureFilter::Nearest);
    expect_vec4(n.evaluate(Vec2(1.3f, -0.9f)), n.evaluate(Vec2(0.3f, 0.1f)));
    expect_vec4(n.evaluate(Vec2(-0.1f, 0.1f)), Vec4(3, 0, 30, 1));  // column 3 from the left edge
    Texture l = ramp(4, 4, TextureWrap::Repeat, TextureWrap::Repeat, TextureFilter::Linear);
    // u = 0: halfway between column 3 (wrapped) and column 0 => R = 1.5; v on row 1's centre.
    expect_vec4(l.evaluate(Vec2(0.0f, 0.375f)), Vec4(1.5f, 1, 16, 1));
    expect_vec4(l.evaluate(Vec2(7.0f, 0.375f)), Vec4(1.5f, 1, 16, 1));
}

TEST(Texture, ClampToEdgeRepeatsTheBorderTexel) {
    Texture l = ramp(4, 4, TextureWrap::ClampToEdge, TextureWrap::ClampToEdge, TextureFilter::Linear);
    expect_vec4(l.evaluate(Vec2(0.0f, 0.375f)), Vec4(0, 1, 1, 1));  // no blend with column 3
    expect_vec4(l.evaluate(Vec2(-5.0f, 9.0f)), Vec4(0, 3, 3, 1));
    expect_vec4(l.evaluate(Vec2(1.2f, -0.3f)), Vec4(3, 0, 30, 1));
}

TEST(Texture, MirroredRepeatReflectsEveryOtherPeriod) {
    Texture n = ramp(4, 4, TextureWrap::MirroredRepeat, TextureWrap::MirroredRepeat, TextureFilter::Nearest);
    // u in (1, 2) reads the image mirrored: u = 1.1 -> 0.9 -> column 3; u = -0.1 -> 0.1 -> column 0.
    expect_vec4(n.evaluate(Vec2(1.1f, 0.1f)), Vec4(3, 0, 30, 1));
    expect_vec4(n.evaluate(Vec2(-0.1f, 0.1f)), Vec4(0, 0, 0, 1));
    expect_vec4(n.evaluate(Vec2(2.1f, 1.9f)), Vec4(0, 0, 0, 1));  // period 2: 2.1 -> 0.1, 1.9 -> 0.1
    Texture l = ramp(4, 4, TextureWrap::MirroredRepeat, TextureWrap::ClampToEdge, TextureFilter::Linear);
    // u = 1: the mirror line, both neighbours are column 3.
    expect_vec4(l.evaluate(Vec2(1.0f, 0.125f)), Vec4(3, 0, 30, 1));
}

TEST(Texture, DifferentWrapModesPerAxis) {
    Texture n = ramp(4, 4, TextureWrap::Repeat, TextureWrap::ClampToEdge, TextureFilter::Nearest);
    expect_vec4(n.evaluate(Vec2(1.6f, 1.6f)), Vec4(2, 3, 23, 1));
}

TEST(Texture, SrgbTexturesAreDecodedToLinearExceptAlpha) {
    std::vector<float> rgba = {0.5f, 0.04f, 1.0f, 0.5f};
    Texture s("s", 1, 1, rgba, true);
    Vec4 v = s.evaluate(Vec2(0.5f, 0.5f));
    // IEC 61966-2-1: ((0.5 + 0.055) / 1.055)^2.4 = 0.21404; 0.04 / 12.92 = 0.0030960.
    EXPECT_NEAR(v[0], 0.214041f, 1e-5f);
    EXPECT_NEAR(v[1], 0.0030960f, 1e-6f);
    EXPECT_NEAR(v[2], 1.0f, 1e-6f);
    EXPECT_NEAR(v[3], 0.5f, 1e-7f);
    Texture l("l", 1, 1, rgba, false);
    EXPECT_NEAR(l.evaluate(Vec2(0.5f, 0.5f))[0], 0.5f, 1e-7f);
}

TEST(Texture, EightBitSrgbValuesDecodeLikeTheTransferFunction) {
    // Every 8-bit code k / 255 (as an image loader produces them), one texel per code.
    std::vector<float> rgba;
    for (int k = 0; k < 256; ++k) {
        float v = float(k) * (1.0f / 255.0f);
        rgba.insert(rgba.end(), {v, v, v, v});
    }
    Texture t("codes", 256, 1, rgba, true, TextureWrap::ClampToEdge, TextureWrap::ClampToEdge, TextureFilter::Nearest);
    for (int k = 0; k < 256; ++k) {
        double v = k / 255.0;
        double want = v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
        Vec4 got = t.evaluate(Vec2((k + 0.5f) / 256.0f, 0.5f));
        EXPECT_NEAR(got[0], want, 1e-6) << k;
        EXPECT_NEAR(got[3], v, 1e-7) << k;
    }
}

TEST(Texture, NonFiniteCoordinatesDoNotCrash) {
    Texture l = ramp(4, 4, TextureWrap::Repeat, TextureWrap::MirroredRepeat, TextureFilter::Linear);
    Vec4 v = l.evaluate(Vec2(std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()));
    EXPECT_TRUE(v.allFinite());
    EXPECT_TRUE(l.evaluate(Vec2(3e9f, -3e9f)).allFinite());
}

TEST(Texture, RejectsPixelArraysOfTheWrongSize) {
    EXPECT_THROW(Texture("bad", 2, 2, std::vector<float>(15, 0.0f), false), Error);
    EXPECT_THROW(Texture("bad", 0, 2, std::vector<float>(), false), Error);
}

}  // namespace
}  // namespace dynsky
