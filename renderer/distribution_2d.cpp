#include "renderer/distribution_2d.h"

#include <algorithm>
#include <cmath>

namespace dynsky {

void Distribution2D::build(const float* weights, int width, int height) {
    build_rows(width, height, [&](int y, float* out) {
        std::copy(weights + size_t(y) * width, weights + size_t(y + 1) * width, out);
    });
}

void Distribution2D::finish_marginal() {
    double total = 0;
    marginal_[0] = 0;
    for (int y = 0; y < height_; ++y) {
        total += row(y)[width_];
        marginal_[size_t(y) + 1] = total;
    }
    total_ = total;
    pdf_scale_ = total > 0 ? float(double(width_) * height_ / total) : 0.0f;
}

// Index i with cdf[i] <= t < cdf[i + 1] among n cells, never landing on an empty cell.
template <typename T>
static int find_interval(const T* cdf, int n, T t) {
    const T* it = std::upper_bound(cdf + 1, cdf + n + 1, t);
    int i = std::clamp(int(it - cdf) - 1, 0, n - 1);
    while (i < n - 1 && cdf[i + 1] <= cdf[i]) ++i;
    while (i > 0 && cdf[i + 1] <= cdf[i]) --i;  // t at the very top: step back to a non-empty cell
    return i;
}

// (cell + frac) / n can round up into the next cell in float when cell is large: keep it inside.
static float in_cell(int cell, float frac, int n) {
    float v = (cell + frac) / n;
    float hi = std::nextafter(float(cell + 1) / n, 0.0f);
    while (int(hi * n) > cell) hi = std::nextafter(hi, 0.0f);
    return std::clamp(v, float(cell) / n, hi);
}

bool Distribution2D::sample(const Vec2& u, Vec2* xy, float* pdf, int* cell_x, int* cell_y) const {
    if (empty()) return false;
    double ty = double(u.y()) * total_;
    int y = find_interval(marginal_.data(), height_, ty);
    double m0 = marginal_[size_t(y)], m1 = marginal_[size_t(y) + 1];
    float dy = m1 > m0 ? float((ty - m0) / (m1 - m0)) : 0.5f;
    const float* p = row(y);
    float tx = u.x() * p[width_];
    int x = find_interval(p, width_, tx);
    float c0 = p[x], c1 = p[x + 1];
    float dx = c1 > c0 ? (tx - c0) / (c1 - c0) : 0.5f;
    dx = std::clamp(dx, 0.0f, 0x1.fffffep-1f), dy = std::clamp(dy, 0.0f, 0x1.fffffep-1f);
    *xy = Vec2(in_cell(x, dx, width_), in_cell(y, dy, height_));
    *pdf = cell_pdf(x, y);
    if (cell_x) *cell_x = x;
    if (cell_y) *cell_y = y;
    return *pdf > 0;
}

float Distribution2D::cell_pdf(int x, int y) const {
    const float* p = row(y);
    // P(row) P(cell | row) W H = (row total / total) ((p[x+1] - p[x]) / row total) W H.
    return (p[x + 1] - p[x]) * pdf_scale_;
}

float Distribution2D::pdf(const Vec2& xy) const {
    int x = std::clamp(int(xy.x() * width_), 0, width_ - 1);
    int y = std::clamp(int(xy.y() * height_), 0, height_ - 1);
    return cell_pdf(x, y);
}

size_t Distribution2D::memory_bytes() const {
    return row_prefix_.capacity() * sizeof(float) + marginal_.capacity() * sizeof(double);
}

}  // namespace dynsky
