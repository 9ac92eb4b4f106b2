#include "renderer/distribution_2d.h"

#include <gtest/gtest.h>

#include "renderer/sampling.h"
#include "tests/renderer/chi_square.h"

namespace dynsky {
namespace {

// Draws n samples and tests their cells against the weights f (chi-square); checks on the way that
// each sample lies in the cell it reports, never in a zero-weight cell, with pdf == pdf(xy).
test::ChiSquareResult sample_cells_against(const Distribution2D& d, const std::vector<float>& f, int w, int h, int n,
                                           uint64_t seed) {
    std::vector<double> observed(w * h, 0), expected(w * h, 0);
    double total = 0;
    for (float v : f) total += v;
    Rng rng(seed, 2);
    for (int k = 0; k < n; ++k) {
        Vec2 xy;
        float pdf;
        int cx, cy;
        EXPECT_TRUE(d.sample(rng.uniform2(), &xy, &pdf, &cx, &cy));
        EXPECT_GE(xy.x(), 0.f);
        EXPECT_LT(xy.x(), 1.f);
        EXPECT_EQ(int(xy.x() * w), cx);
        EXPECT_EQ(int(xy.y() * h), cy);
        EXPECT_GT(f[cy * w + cx], 0.f) << "sampled a zero-weight cell";
        EXPECT_FLOAT_EQ(pdf, d.pdf(xy));
        observed[cy * w + cx] += 1;
    }
    for (int i = 0; i < w * h; ++i) expected[i] = n * f[i] / total;
    return test::chi_square_test(observed, expected);
}

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

    auto r = sample_cells_against(d, f, w, h, 400000, 11);
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

// MIS compensation computed where the weights are read (max(w - c b, 0)) must give exactly the
// distribution built from the compensated weights written out, and sample it correctly.
TEST(Distribution2D, BaselineOffsetEqualsExplicitCompensationChiSquare) {
    const int w = 53, h = 7;  // not a multiple of the block size: partial last blocks
    std::vector<float> f(w * h), explicit_f(w * h);
    std::vector<uint16_t> base(w * h);
    Rng frng(9, 4);
    const float offset = 0.02f;
    for (int k = 0; k < w * h; ++k) {
        f[k] = std::pow(frng.uniform(), 2.0f) * 100;
        base[k] = uint16_t(1000 + 2000 * frng.uniform());
        explicit_f[k] = std::max(f[k] - offset * float(base[k]), 0.0f);
    }
    Distribution2D compensated, reference;
    std::vector<float> taken = f;
    compensated.build_in_place(&taken, w, h, base.data(), offset);
    reference.build(explicit_f.data(), w, h);
    EXPECT_NEAR(compensated.integral(), reference.integral(), 1e-5 * reference.integral());
    int zero_cells = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            EXPECT_NEAR(compensated.cell_pdf(x, y), reference.cell_pdf(x, y), 1e-5f * (1 + reference.cell_pdf(x, y)));
            zero_cells += explicit_f[y * w + x] == 0;
        }
    ASSERT_GT(zero_cells, w * h / 10) << "the offset should zero a good part of the cells";

    auto r = sample_cells_against(compensated, explicit_f, w, h, 300000, 17);
    EXPECT_GT(r.p_value, 1e-3) << r.summary();
}

TEST(Distribution2D, BuildInPlaceHandsBackAReusableBuffer) {
    std::vector<float> a(16 * 4, 1.0f), b(16 * 4, 2.0f);
    Distribution2D d;
    d.build_in_place(&a, 16, 4);
    EXPECT_TRUE(a.empty()) << "first build: nothing to give back";
    d.build_in_place(&b, 16, 4);
    EXPECT_EQ(b.size(), size_t(16 * 4)) << "second build gives back the first buffer";
    EXPECT_NEAR(d.integral(), 2.0, 1e-6);
}

}  // namespace
}  // namespace dynsky
