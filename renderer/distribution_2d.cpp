#include "renderer/distribution_2d.h"

#include <algorithm>
#include <cmath>

namespace dynsky {

void Distribution2D::build(const float* weights, int width, int height) {
    build_with(width, height, [&](int x, int y) { return weights[size_t(y) * width + x]; });
}

void Distribution2D::finish_marginal() {
    double total = 0;
    marginal_cdf_[0] = 0;
    for (int y = 0; y < height_; ++y) {
        total += row_sum_[size_t(y)];
        marginal_cdf_[size_t(y) + 1] = float(total);
    }
    integral_ = total / (double(width_) * height_);
    if (total > 0) {
        for (int y = 1; y <= height_; ++y) marginal_cdf_[size_t(y)] = float(marginal_cdf_[size_t(y)] / total);
        marginal_cdf_[size_t(height_)] = 1.0f;
    }
}

// Index i with cdf[i] <= u < cdf[i + 1], skipping zero-width cells.
static int find_interval(const float* cdf, int n, float u) {
    const float* it = std::upper_bound(cdf + 1, cdf + n + 1, u);
    int i = int(it - cdf) - 1;
    i = std::clamp(i, 0, n - 1);
    while (i < n - 1 && cdf[i + 1] <= cdf[i]) ++i;  // never land on an empty cell
    return i;
}

bool Distribution2D::sample(const Vec2& u, Vec2* xy, float* pdf, int* cell_x, int* cell_y) const {
    if (empty()) return false;
    int y = find_interval(marginal_cdf_.data(), height_, u.y());
    float m0 = marginal_cdf_[size_t(y)], m1 = marginal_cdf_[size_t(y) + 1];
    float dy = m1 > m0 ? (u.y() - m0) / (m1 - m0) : 0.5f;
    const float* cdf = &row_cdf_[size_t(y) * (width_ + 1)];
    int x = find_interval(cdf, width_, u.x());
    float c0 = cdf[x], c1 = cdf[x + 1];
    float dx = c1 > c0 ? (u.x() - c0) / (c1 - c0) : 0.5f;
    dx = std::clamp(dx, 0.0f, 0x1.fffffep-1f), dy = std::clamp(dy, 0.0f, 0x1.fffffep-1f);
    // (x + dx) / W can round up into the next cell in float when x is large: keep it in cell x.
    auto in_cell = [](int cell, float frac, int n) {
        float v = (cell + frac) / n;
        float hi = std::nextafter(float(cell + 1) / n, 0.0f);
        while (int(hi * n) > cell) hi = std::nextafter(hi, 0.0f);
        return std::clamp(v, float(cell) / n, hi);
    };
    *xy = Vec2(in_cell(x, dx, width_), in_cell(y, dy, height_));
    *pdf = cell_pdf(x, y);
    if (cell_x) *cell_x = x;
    if (cell_y) *cell_y = y;
    return *pdf > 0;
}

float Distribution2D::cell_pdf(int x, int y) const {
    if (empty()) return 0.0f;
    return float(weights_[size_t(y) * width_ + x] / integral_);
}

float Distribution2D::pdf(const Vec2& xy) const {
    int x = std::clamp(int(xy.x() * width_), 0, width_ - 1);
    int y = std::clamp(int(xy.y() * height_), 0, height_ - 1);
    return cell_pdf(x, y);
}

size_t Distribution2D::memory_bytes() const {
    return weights_.capacity() * sizeof(float) + row_cdf_.capacity() * sizeof(float) +
           row_sum_.capacity() * sizeof(double) + marginal_cdf_.capacity() * sizeof(float);
}

}  // namespace dynsky
