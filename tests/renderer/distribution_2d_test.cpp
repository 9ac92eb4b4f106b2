#include "renderer/distribution_2d.h"

#include <gtest/gtest.h>

#include "renderer/sampling.h"
#include "tests/renderer/chi_square.h"

namespace dynsky {
namespace {

TEST(Distribution2D, SamplesFollowThePdfChiSquare) {
    const int w = 24, h = 16;
    std::vector<float> f(w * h);
    Rng frng(3, 1);
    for (auto& v : f) v = frng.uniform() < 0.2f ? 0.0f : std::pow(frng.uniform(), 3.0f) * 10;
    f[5 * w + 7] = 200;  // a bright "sun" cell
    Distribution2D d;
    d.build(f.data(), w, h);
    double total = 0;
    for (float v : f) total += v;
    EXPECT_NEAR(d.integral(), total / (w * h), 1e-6 * total);

    const int n = 400000;
    std::vector<double> observed(w * h, 0), expected(w * h, 0);
    Rng rng(11, 2);
    for (int k = 0; k < n; ++k) {
        Vec2 xy;
        float pdf;
        int cx, cy;
        ASSERT_TRUE(d.sample(rng.uniform2(), &xy, &pdf, &cx, &cy));
        ASSERT_GE(xy.x(), 0.f);
        ASSERT_LT(xy.x(), 1.f);
        ASSERT_EQ(int(xy.x() * w), cx);
        ASSERT_EQ(int(xy.y() * h), cy);
        ASSERT_GT(f[cy * w + cx], 0.f) << "sampled a zero-weight cell";
        EXPECT_FLOAT_EQ(pdf, d.pdf(xy));
        observed[cy * w + cx] += 1;
    }
    for (int i = 0; i < w * h; ++i) expected[i] = n * f[i] / total;
    auto r = test::chi_square_test(observed, expected);
    EXPECT_GT(r.p_value, 1e-3) << r.summary();
}

TEST(Distribution2D, PdfIntegratesToOne) {
    const int w = 37, h = 11;
    std::vector<float> f(w * h);
    for (int i = 0; i < w * h; ++i) f[i] = float((i * 7919) % 13);
    Distribution2D d;
    d.build(f.data(), w, h);
    double sum = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) sum += d.cell_pdf(x, y) / (w * h);
    EXPECT_NEAR(sum, 1.0, 1e-5);
}

TEST(Distribution2D, AllZeroIsEmptyAndRefusesToSample) {
    std::vector<float> f(16, 0.0f);
    Distribution2D d;
    d.build(f.data(), 4, 4);
    EXPECT_TRUE(d.empty());
    Vec2 xy;
    float pdf;
    EXPECT_FALSE(d.sample(Vec2(0.3f, 0.7f), &xy, &pdf));
    EXPECT_EQ(d.pdf(Vec2(0.5f, 0.5f)), 0.0f);
}

TEST(Distribution2D, SingleLitCellIsAlwaysChosen) {
    std::vector<float> f(64 * 64, 0.0f);
    f[40 * 64 + 3] = 1e-3f;
    Distribution2D d;
    d.build(f.data(), 64, 64);
    Rng rng(1, 1);
    for (int k = 0; k < 1000; ++k) {
        Vec2 xy;
        float pdf;
        int cx, cy;
        ASSERT_TRUE(d.sample(rng.uniform2(), &xy, &pdf, &cx, &cy));
        EXPECT_EQ(cx, 3);
        EXPECT_EQ(cy, 40);
        EXPECT_NEAR(pdf, 64.0f * 64.0f, 1e-2f);
    }
}

TEST(Distribution2D, RebuildReplacesTheOldFunction) {
    std::vector<float> a(8 * 8, 0.0f), b(8 * 8, 0.0f);
    a[0] = 1, b[63] = 1;
    Distribution2D d;
    d.build(a.data(), 8, 8);
    d.build(b.data(), 8, 8);
    Vec2 xy;
    float pdf;
    int cx, cy;
    ASSERT_TRUE(d.sample(Vec2(0.5f, 0.5f), &xy, &pdf, &cx, &cy));
    EXPECT_EQ(cx, 7);
    EXPECT_EQ(cy, 7);
    EXPECT_EQ(d.cell_pdf(0, 0), 0.0f);
}

}  // namespace
}  // namespace dynsky
