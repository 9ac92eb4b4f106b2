// Piecewise-constant 2D distribution over a W x H grid (row CDFs plus a marginal over rows),
// sampled by two binary searches (pbrt-v4's PiecewiseConstant2D). Built for per-frame rebuilds:
// only unnormalised row prefix sums are stored (no weight copy, no normalisation pass), rows are
// built in parallel, and storage is reused while the size is unchanged. A cell's pdf is read from
// the same prefix sums the binary search uses, so sample() and pdf() agree to the last bit.
#pragma once

#include <cstddef>
#include <vector>

#include "util/math.h"

namespace dynsky {

class Distribution2D {
  public:
    Distribution2D() = default;

    // weights: W * H non-negative finite values, row-major.
    void build(const float* weights, int width, int height);

    // Builds from a functor row_weights(y, float* out) that writes row y's W weights into the
    // distribution's own storage (then prefix-summed in place, while in cache).
    template <typename RowFn>
    void build_rows(int width, int height, RowFn&& row_weights);

    // Sample (x, y) in [0, 1)^2; *pdf per unit area of [0, 1]^2. Returns false when the
    // distribution is empty (all weights zero).
    bool sample(const Vec2& u, Vec2* xy, float* pdf, int* cell_x = nullptr, int* cell_y = nullptr) const;
    // Density per unit area of [0, 1]^2 of the cell containing xy.
    float pdf(const Vec2& xy) const;
    float cell_pdf(int x, int y) const;

    int width() const { return width_; }
    int height() const { return height_; }
    // Integral of the piecewise-constant function over [0,1]^2 (sum of weights / (W H)).
    double integral() const { return total_ / (double(width_) * height_); }
    bool empty() const { return !(total_ > 0); }
    size_t memory_bytes() const;

  private:
    const float* row(int y) const { return &row_prefix_[size_t(y) * (width_ + 1)]; }
    void finish_marginal();
    int width_ = 0, height_ = 0;
    std::vector<float> row_prefix_;    // H rows of W + 1 unnormalised prefix sums (first is 0)
    std::vector<double> marginal_;     // H + 1 prefix sums of the row totals
    double total_ = 0;
    float pdf_scale_ = 0;  // W H / total: turns a prefix-sum difference into a pdf
};

}  // namespace dynsky

#include "renderer/distribution_2d_impl.h"
