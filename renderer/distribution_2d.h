// Piecewise-constant 2D distribution over a W x H grid (row CDFs plus a marginal over rows, as
// pbrt-v4's PiecewiseConstant2D), built for per-frame rebuilds. Each row keeps its cell weights
// and the running sums of blocks of 16 cells: sampling is a binary search in the marginal, one
// in the row's block sums, then a scan of at most 16 weights (one cache line). The rebuild is
// one read-only pass over the weights it takes over from the caller (build_in_place: no copy),
// writing only the block sums (1/16 of the cells); no per-cell running sum, whose chain of
// dependent adds would bound the pass. Cell weights may be offset, max(w - c b, 0) for a baseline
// b (MIS compensation), computed where they are read instead of written back. A cell's pdf is its
// weight over the total, the same weights the scan walks through, so sample() and pdf() agree.
#pragma once

#include <cstddef>
#include <vector>

#include <algorithm>
#include <cstdint>

#include "util/math.h"

namespace dynsky {

class Distribution2D {
  public:
    static constexpr int kBlock = 16;  // cells per block of a row

    Distribution2D() = default;

    // weights: W * H non-negative finite values, row-major.
    void build(const float* weights, int width, int height);

    // Takes *weights (W * H, row-major, >= 0, finite) as its own storage and gives back its
    // previous buffer (reused by the caller next frame: no allocation once sizes settle). With a
    // baseline (W * H, alive until the next build) cell k weighs max(w[k] - offset baseline[k], 0).
    void build_in_place(std::vector<float>* weights, int width, int height, const uint16_t* baseline = nullptr,
                        float offset = 0);

    // Sample (x, y) in [0, 1)^2; *pdf per unit area of [0, 1]^2. Returns false when the
    // distribution is empty (all weights zero).
    bool sample(const Vec2& u, Vec2* xy, float* pdf, int* cell_x = nullptr, int* cell_y = nullptr) const;
    // Density per unit area of [0, 1]^2 of the cell containing xy.
    float pdf(const Vec2& xy) const;
    float cell_pdf(int x, int y) const { return cell_weight(size_t(y) * width_ + x) * pdf_scale_; }
    // Starts loading what cell_pdf(x, y) reads (see EnvLight::prefetch).
    void prefetch_cell(int x, int y) const {
        const size_t k = size_t(y) * width_ + x;
        if (k >= weights_.size()) return;
        __builtin_prefetch(&weights_[k]);
        if (baseline_) __builtin_prefetch(&baseline_[k]);
    }

    const std::vector<float>& weights() const { return weights_; }
    int width() const { return width_; }
    int height() const { return height_; }
    // Integral of the piecewise-constant function over [0,1]^2 (sum of weights / (W H)).
    double integral() const { return total_ / (double(width_) * height_); }
    bool empty() const { return !(total_ > 0); }
    size_t memory_bytes() const;

  private:
    float cell_weight(size_t k) const {
        return baseline_ ? std::max(weights_[k] - offset_ * float(baseline_[k]), 0.0f) : weights_[k];
    }
    void sum_blocks(int y);
    void finish_marginal();
    int width_ = 0, height_ = 0, blocks_ = 0;
    std::vector<float> weights_;     // H x W cell weights
    std::vector<float> block_sums_;  // H x blocks_: running sums of each row's block totals
    std::vector<double> marginal_;   // H + 1 running sums of the row totals (first is 0)
    // K + 1 bounds of the row search (K the power of two >= H): guide_[k] = number of running sums
    // marginal_[1..H] <= (k / K) total, so a sample's search only spans its bucket's rows.
    std::vector<int> guide_;
    const uint16_t* baseline_ = nullptr;
    float offset_ = 0;
    double total_ = 0;
    float pdf_scale_ = 0;  // W H / total: turns a weight into a pdf
};

}  // namespace dynsky
