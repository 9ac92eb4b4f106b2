#include "renderer/distribution_2d.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "renderer/sampling.h"

namespace dynsky {

void Distribution2D::build(const float* weights, int width, int height) {
    std::vector<float> copy(weights, weights + size_t(width) * height);
    build_in_place(&copy, width, height);
}

void Distribution2D::build_in_place(std::vector<float>* weights, int width, int height, const uint16_t* baseline,
                                    float offset) {
    width_ = width, height_ = height, blocks_ = (width + kBlock - 1) / kBlock;
    baseline_ = offset > 0 ? baseline : nullptr;
    offset_ = offset;
    weights_.swap(*weights);
    weights_.resize(size_t(width) * height);
    block_sums_.resize(size_t(blocks_) * height);
    marginal_.resize(size_t(height) + 1);
    tbb::parallel_for(tbb::blocked_range<int>(0, height, 16), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y != rows.end(); ++y) sum_blocks(y);
    });
    finish_marginal();
}

void Distribution2D::sum_blocks(int y) {
    const size_t row = size_t(y) * width_;
    const float* w = &weights_[row];
    float* out = &block_sums_[size_t(y) * blocks_];
    float acc = 0;  // a running sum of non-negative terms: never decreases
    int b = 0;
#if defined(__SSE2__)
    if (baseline_) {  // the MIS-compensated weights, computed on the fly: the pass only reads
        const uint16_t* base = baseline_ + row;
        const __m128 f = _mm_set1_ps(offset_), zero = _mm_setzero_ps();
        const __m128i zi = _mm_setzero_si128();
        alignas(16) float lanes[4];
        for (; (b + 1) * kBlock <= width_; ++b) {
            __m128 s = zero;
            for (int x = b * kBlock; x < (b + 1) * kBlock; x += 8) {
                __m128i j8 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(base + x));
                __m128 j0 = _mm_cvtepi32_ps(_mm_unpacklo_epi16(j8, zi)),
                       j1 = _mm_cvtepi32_ps(_mm_unpackhi_epi16(j8, zi));
                s = _mm_add_ps(s, _mm_max_ps(_mm_sub_ps(_mm_loadu_ps(w + x), _mm_mul_ps(f, j0)), zero));
                s = _mm_add_ps(s, _mm_max_ps(_mm_sub_ps(_mm_loadu_ps(w + x + 4), _mm_mul_ps(f, j1)), zero));
            }
            _mm_store_ps(lanes, s);
            out[b] = acc += (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
        }
    }
#endif
    for (; b < blocks_; ++b) {
        const int lo = b * kBlock, hi = std::min(lo + kBlock, width_);
        float s = 0;
        for (int x = lo; x < hi; ++x) s += cell_weight(row + x);  // vectorised (reassociation allowed here)
        out[b] = acc += s;
    }
}

void Distribution2D::finish_marginal() {
    double total = 0;
    marginal_[0] = 0;
    for (int y = 0; y < height_; ++y) {
        total += block_sums_[size_t(y) * blocks_ + blocks_ - 1];
        marginal_[size_t(y) + 1] = total;
    }
    total_ = total;
    pdf_scale_ = total > 0 ? float(double(width_) * height_ / total) : 0.0f;
    // The guide: for t_k = (k / K) total, the number of running sums marginal_[1..H] <= t_k (what
    // upper_bound gives), by one merge-like walk.
    int k_size = 1;
    while (k_size < height_) k_size *= 2;
    guide_.resize(size_t(k_size) + 1);
    int r = 0;
    for (int k = 0; k <= k_size; ++k) {
        const double t = double(k) / k_size * total;
        while (r < height_ && marginal_[size_t(r) + 1] <= t) ++r;
        guide_[size_t(k)] = r;
    }
}

// std::upper_bound(s, s + n, t) - s without branches: the comparisons of a binary search over a
// CDF go either way at random, and mispredicting them cost more than the loads (the result is the
// same index).
template <typename T>
static int upper_bound_index(const T* s, int n, T t) {
    if (n <= 0) return 0;
    const T* base = s;
    for (int len = n; len > 1;) {
        const int half = len / 2;
        base += half * int(base[half - 1] <= t);  // arithmetic, not a branch
        len -= half;
    }
    return int(base - s) + (*base <= t);
}

// Cell i of the search moved off empty cells (find_interval's last step).
template <typename T>
static int settle_interval(const T* cdf, int n, int i) {
    while (i < n - 1 && cdf[i + 1] <= cdf[i]) ++i;
    while (i > 0 && cdf[i + 1] <= cdf[i]) --i;  // t at the very top: step back to a non-empty cell
    return i;
}

// Index i with cdf[i] <= t < cdf[i + 1] among n cells, never landing on an empty cell.
template <typename T>
static int find_interval(const T* cdf, int n, T t) {
    return settle_interval(cdf, n, std::clamp(upper_bound_index(cdf + 1, n, t), 0, n - 1));
}

// The same over inclusive running sums s[0..n) (block b spans [s[b-1], s[b]), s[-1] = 0).
static int find_block(const float* s, int n, float t) {
    int b = std::min(upper_bound_index(s, n, t), n - 1);
    auto lower = [&](int i) { return i > 0 ? s[i - 1] : 0.0f; };
    while (b < n - 1 && s[b] <= lower(b)) ++b;
    while (b > 0 && s[b] <= lower(b)) --b;
    return b;
}

bool Distribution2D::sample(const Vec2& u, Vec2* xy, float* pdf, int* cell_x, int* cell_y) const {
    if (empty()) return false;
    double ty = double(u.y()) * total_;
    int y;
    if (u.y() >= 0 && u.y() < 1) {
        // The guide bounds the search: K is a power of two, so u K is exact, t_k <= ty <= t_k+1
        // (rounding is monotone) and the count of sums <= ty lies in [guide k, guide k+1]. The
        // same row as the full search, in a step or two where the sun's rows hold most weight.
        const int k = int(u.y() * float(guide_.size() - 1)), lo = guide_[size_t(k)], hi = guide_[size_t(k) + 1];
        const int count = lo + upper_bound_index(marginal_.data() + 1 + lo, hi - lo, ty);
        y = settle_interval(marginal_.data(), height_, std::clamp(count, 0, height_ - 1));
    } else {
        y = find_interval(marginal_.data(), height_, ty);
    }
    double m0 = marginal_[size_t(y)], m1 = marginal_[size_t(y) + 1];
    float dy = m1 > m0 ? float((ty - m0) / (m1 - m0)) : 0.5f;
    const float* bs = &block_sums_[size_t(y) * blocks_];
    float tx = u.x() * bs[blocks_ - 1];
    int b = find_block(bs, blocks_, tx);
    float t = tx - (b > 0 ? bs[b - 1] : 0.0f);
    // Walk the block's cells; rounding can leave t past the last one: then take the last lit cell.
    const int lo = b * kBlock, hi = std::min(lo + kBlock, width_);
    const size_t row = size_t(y) * width_;
    int x = -1, last_lit = lo;
    float wx = 0;
    for (int k = lo; k < hi; ++k) {
        const float wk = cell_weight(row + k);
        if (!(wk > 0)) continue;
        last_lit = k, wx = wk;
        if (t < wk) {
            x = k;
            break;
        }
        t -= wk;
    }
    if (x < 0) x = last_lit, t = wx;
    float dx = wx > 0 ? t / wx : 0.5f;
    dx = std::clamp(dx, 0.0f, 0x1.fffffep-1f), dy = std::clamp(dy, 0.0f, 0x1.fffffep-1f);
    *xy = Vec2(in_cell(x, dx, width_), in_cell(y, dy, height_));
    *pdf = cell_pdf(x, y);
    if (cell_x) *cell_x = x;
    if (cell_y) *cell_y = y;
    return *pdf > 0;
}

float Distribution2D::pdf(const Vec2& xy) const {
    int x = std::clamp(int(xy.x() * width_), 0, width_ - 1);
    int y = std::clamp(int(xy.y() * height_), 0, height_ - 1);
    return cell_pdf(x, y);
}

size_t Distribution2D::memory_bytes() const {
    return weights_.capacity() * sizeof(float) + block_sums_.capacity() * sizeof(float) +
           marginal_.capacity() * sizeof(double) + guide_.capacity() * sizeof(int);
}

}  // namespace dynsky
