// Piecewise-constant 2D distribution over a W x H grid (row CDFs plus a marginal over rows),
// sampled by two binary searches (pbrt-v4's PiecewiseConstant2D). Built for per-frame rebuilds:
// rows are built in parallel and in one pass over the weights, with no allocation once sized.
#pragma once

#include <cstddef>
#include <vector>

#include "util/math.h"

namespace dynsky {

class Distribution2D {
  public:
    Distribution2D() = default;

    // weights: W * H non-negative values, row-major. Reuses storage when the size is unchanged.
    void build(const float* weights, int width, int height);

    // Builds from a functor weight(x, y) evaluated once per cell, fused with the row pass (saves
    // writing and re-reading a weight image).
    template <typename WeightFn>
    void build_with(int width, int height, WeightFn&& weight);

    // Sample (x, y) in [0, 1)^2; *pdf per unit area of [0, 1]^2. Returns false when the
    // distribution is empty (all weights zero).
    bool sample(const Vec2& u, Vec2* xy, float* pdf, int* cell_x = nullptr, int* cell_y = nullptr) const;
    // Density per unit area of [0, 1]^2 of the cell containing xy.
    float pdf(const Vec2& xy) const;
    float cell_pdf(int x, int y) const;

    int width() const { return width_; }
    int height() const { return height_; }
    // Sum of weights times cell area (the integral of the piecewise-constant function over [0,1]^2).
    double integral() const { return integral_; }
    bool empty() const { return !(integral_ > 0); }
    size_t memory_bytes() const;

  private:
    void finish_marginal();
    int width_ = 0, height_ = 0;
    std::vector<float> weights_;      // W * H copy of the function (for pdf lookups)
    std::vector<float> row_cdf_;      // H rows of W + 1 entries, normalised per row
    std::vector<double> row_sum_;     // H row sums (double: keeps 4096^2 sums exact enough)
    std::vector<float> marginal_cdf_; // H + 1 entries
    double integral_ = 0;
};

}  // namespace dynsky

#include "renderer/distribution_2d_impl.h"
