#include "renderer/sky_sampler.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>

#include "renderer/distribution_2d.h"
#include "renderer/env_light.h"
#include "renderer/sampling.h"
#include "sky/fisheye.h"
#include "util/error.h"

namespace dynsky {

void SkyWeights::finish_row(int j, float* row) const {
    if (!(mis_floor > 0)) return;
    const uint16_t* jac = jacobian + size_t(j) * n;
    int i = 0;
#if defined(__SSE2__)
    // Explicit: GCC 12 leaves this loop scalar, and it is a whole pass per frame.
    const __m128 f = _mm_set1_ps(mis_floor), zero = _mm_setzero_ps();
    const __m128i zi = _mm_setzero_si128();
    for (; i + 4 <= n; i += 4) {
        __m128 jf = _mm_cvtepi32_ps(_mm_unpacklo_epi16(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(jac + i)), zi));
        _mm_storeu_ps(row + i, _mm_max_ps(_mm_sub_ps(_mm_loadu_ps(row + i), _mm_mul_ps(f, jf)), zero));
    }
#endif
    for (; i < n; ++i) row[i] = std::max(row[i] - mis_floor * float(jac[i]), 0.0f);
}

void SkyWeights::apply_compensation() {
    if (!(mis_floor > 0)) return;
    tbb::parallel_for(tbb::blocked_range<int>(0, n, 16), [&](const tbb::blocked_range<int>& rows) {
        for (int j = rows.begin(); j != rows.end(); ++j) finish_row(j, &(*values)[size_t(j) * n]);
    });
    mis_floor = 0;
}

namespace {

// ---- Samplers that ignore the sky ----

class UniformSampler : public SkySampler {
  public:
    void build(const SkyImage&, SkyWeights&) override {}
    bool sample(const Vec2& u, Vec3* wi, float* pdf, Vec2* uv) const override {
        Vec3 h = sample_uniform_hemisphere(u);
        *wi = Vec3(h.x(), h.z(), h.y());
        fisheye::uv_from_direction(*wi, uv);
        *pdf = this->pdf(*wi);
        return *pdf > 0;
    }
    float pdf(const Vec3& w) const override { return w.y() >= 0 ? 1 / (2 * kPi) : 0.0f; }
    size_t memory_bytes() const override { return 0; }
};

class CosineSampler : public SkySampler {
  public:
    void build(const SkyImage&, SkyWeights&) override {}
    bool sample(const Vec2& u, Vec3* wi, float* pdf, Vec2* uv) const override {
        Vec3 h = sample_cosine_hemisphere(u);
        *wi = Vec3(h.x(), h.z(), h.y());
        fisheye::uv_from_direction(*wi, uv);
        *pdf = this->pdf(*wi);
        return *pdf > 0;
    }
    float pdf(const Vec3& w) const override { return w.y() > 0 ? w.y() * kInvPi : 0.0f; }
    size_t memory_bytes() const override { return 0; }
};

// ---- Pixel-based samplers: a pixel by weight, a uniform point inside it ----

class PixelSampler : public SkySampler {
  public:
    bool sample(const Vec2& u, Vec3* wi, float* pdf, Vec2* uv_wi) const override {
        Vec2 xy;
        if (n_ == 0 || !(total_ > 0) || !sample_xy(u, &xy)) return false;
        // The caller reads this pixel's radiance next (nearly always this pixel, the rim aside): its
        // load, a cache miss in a large sky, overlaps the mapping to a direction and back.
        if (rgb_)
            __builtin_prefetch(rgb_ + 3 * (size_t(std::min(int(xy.y() * n_), n_ - 1)) * n_ +
                                           size_t(std::min(int(xy.x() * n_), n_ - 1))));
        Vec2 uv = 2.0f * xy - Vec2::Ones();
        if (uv.squaredNorm() > 1.0f) return false;  // the part of a rim pixel below the horizon
        *wi = fisheye::direction_from_uv(uv);
        fisheye::uv_from_direction(*wi, uv_wi);
        *pdf = pdf_uv(*wi, *uv_wi);  // from the direction, exactly as pdf() sees it
        return *pdf > 0;
    }
    float pdf(const Vec3& w) const override {
        if (n_ == 0 || w.y() < 0 || !(total_ > 0)) return 0;
        Vec2 uv;
        fisheye::uv_from_direction(w, &uv);
        return pdf_uv(w, uv);
    }
    float pdf_uv(const Vec3& w, const Vec2& uv) const override {
        if (n_ == 0 || w.y() < 0 || !(total_ > 0)) return 0;
        int i = std::clamp(int((uv.x() + 1) * 0.5f * n_), 0, n_ - 1);
        int j = std::clamp(int((uv.y() + 1) * 0.5f * n_), 0, n_ - 1);
        return cell_pdf(i, j) * 0.25f / EnvLight::jacobian_from_r2(uv.squaredNorm());
    }
    // Sum of the weights the sampler was built on (after any sun cut-out).
    double total() const { return total_; }
    bool has_weight() const override { return total_ > 0; }

  protected:
    // A point in [0, 1)^2 (x right, y down, pixel grid n x n).
    virtual bool sample_xy(const Vec2& u, Vec2* xy) const = 0;
    // Density per unit area of [0, 1]^2 of cell (i, j).
    virtual float cell_pdf(int i, int j) const = 0;
    int n_ = 0;
    double total_ = 0;
    const float* rgb_ = nullptr;  // the image built on, only prefetched (the caller keeps it alive)
};

class CdfSampler : public PixelSampler {
  public:
    // One read-only pass over the weights (compensated where they are read, not written back).
    void build(const SkyImage& sky, SkyWeights& w) override {
        n_ = w.n;
        rgb_ = sky.rgb.data();
        dist_.build_in_place(w.values, n_, n_, w.jacobian, w.mis_floor);
        w.mis_floor = 0;  // values now hold the distribution's old buffer: nothing to read there
        total_ = dist_.integral() * double(n_) * n_;
    }
    size_t memory_bytes() const override { return dist_.memory_bytes(); }
    const Distribution2D* distribution() const override { return &dist_; }

  protected:
    bool sample_xy(const Vec2& u, Vec2* xy) const override {
        float pdf;
        return dist_.sample(u, xy, &pdf);
    }
    float cell_pdf(int i, int j) const override { return dist_.cell_pdf(i, j); }

  private:
    Distribution2D dist_;
};

// Vose's alias method on one table of n entries. prob/alias out; returns the sum of the weights.
// Entries are scaled to mean 1; the "small" entries take an alias among the "large" ones.
double build_alias(const float* w, int n, float* prob, uint16_t* alias, std::vector<int>* small,
                   std::vector<int>* large, std::vector<double>* scaled) {
    double sum = 0;
    for (int i = 0; i < n; ++i) sum += w[i];
    if (!(sum > 0)) {
        for (int i = 0; i < n; ++i) prob[i] = 1, alias[i] = uint16_t(i);
        return 0;
    }
    small->clear(), large->clear();
    scaled->resize(size_t(n));
    for (int i = 0; i < n; ++i) {
        (*scaled)[size_t(i)] = w[i] * n / sum;
        ((*scaled)[size_t(i)] < 1 ? small : large)->push_back(i);
    }
    while (!small->empty() && !large->empty()) {
        int s = small->back(), l = large->back();
        small->pop_back();
        prob[s] = float((*scaled)[size_t(s)]), alias[s] = uint16_t(l);
        (*scaled)[size_t(l)] -= 1 - (*scaled)[size_t(s)];
        if ((*scaled)[size_t(l)] < 1) {
            large->pop_back();
            small->push_back(l);
        }
    }
    for (int i : *large) prob[i] = 1, alias[i] = uint16_t(i);
    for (int i : *small) prob[i] = 1, alias[i] = uint16_t(i);  // rounding leftovers
    return sum;
}

// One alias lookup from one uniform: the slot from its integer part, the coin from the fraction,
// and the coin's own remainder returned as a fresh uniform (the position inside the cell).
inline int alias_pick(const float* prob, const uint16_t* alias, int n, double u, double* remainder) {
    double t = u * n;
    int slot = std::min(int(t), n - 1);
    double c = t - slot, p = prob[slot];
    if (c < p) {
        *remainder = p > 0 ? c / p : 0.5;
        return slot;
    }
    *remainder = p < 1 ? (c - p) / (1 - p) : 0.5;
    return alias[slot];
}

// Two levels of alias tables: u.y picks the row (its marginal table), u.x the pixel in it; each
// table's remainder places the point inside the pixel, so both uniforms stay stratified.
class AliasSampler : public PixelSampler {
  public:
    void build(const SkyImage& sky, SkyWeights& weights) override {
        const int n = weights.n;
        if (n > 65536) throw Error("alias sky sampler: resolution above 65536");
        n_ = n;
        rgb_ = sky.rgb.data();
        std::vector<float>& w = *weights.values;
        weights_ = &w;
        prob_.resize(size_t(n) * n), alias_.resize(size_t(n) * n);
        row_total_.resize(size_t(n));
        tbb::parallel_for(tbb::blocked_range<int>(0, n, 16), [&](const tbb::blocked_range<int>& r) {
            std::vector<int> small, large;
            std::vector<double> scaled;
            for (int j = r.begin(); j != r.end(); ++j) {
                weights.finish_row(j, &w[size_t(j) * n]);  // in place: cell_pdf reads the final weights
                row_total_[size_t(j)] = float(build_alias(&w[size_t(j) * n], n, &prob_[size_t(j) * n],
                                                          &alias_[size_t(j) * n], &small, &large, &scaled));
            }
        });
        weights.mis_floor = 0;
        std::vector<int> small, large;
        std::vector<double> scaled;
        row_prob_.resize(size_t(n)), row_alias_.resize(size_t(n));
        total_ = build_alias(row_total_.data(), n, row_prob_.data(), row_alias_.data(), &small, &large, &scaled);
        pdf_scale_ = total_ > 0 ? float(double(n) * n / total_) : 0.0f;
    }
    size_t memory_bytes() const override {
        return prob_.capacity() * 4 + alias_.capacity() * 2 + row_total_.capacity() * 4 + row_prob_.capacity() * 4 +
               row_alias_.capacity() * 2;
    }

  protected:
    bool sample_xy(const Vec2& u, Vec2* xy) const override {
        double fy, fx;
        int j = alias_pick(row_prob_.data(), row_alias_.data(), n_, u.y(), &fy);
        int i = alias_pick(&prob_[size_t(j) * n_], &alias_[size_t(j) * n_], n_, u.x(), &fx);
        *xy = Vec2(in_cell(i, fx, n_), in_cell(j, fy, n_));
        return true;
    }
    // The pixel's share of the total, from the weights themselves (alias tables hold no pdf).
    float cell_pdf(int i, int j) const override { return (*weights_)[size_t(j) * n_ + i] * pdf_scale_; }

  private:
    const std::vector<float>* weights_ = nullptr;
    std::vector<float> prob_, row_total_, row_prob_;
    std::vector<uint16_t> alias_, row_alias_;
    float pdf_scale_ = 0;
};

// Hierarchical warp: a sum pyramid over the weights padded to a power of two; the sample walks
// down choosing a column half by u.x and a row half by u.y at each level, rescaling each uniform.
class MipSampler : public PixelSampler {
  public:
    void build(const SkyImage& sky, SkyWeights& weights) override {
        weights.apply_compensation();
        const int n = weights.n;
        std::vector<float>& w = *weights.values;
        n_ = n;
        rgb_ = sky.rgb.data();
        weights_ = &w;
        int size = 1;
        while (size < n) size *= 2;
        // levels_[0] is size/2 square, ..., the last one 1x1. Level 0 reads the weights directly.
        // Every entry is written below, so the pyramid is only reallocated when the size changes.
        if (size != size_ || levels_.empty() != (size == 1)) {
            size_ = size;
            levels_.clear();
            for (int s = size_ / 2; s >= 1; s /= 2) levels_.emplace_back(size_t(s) * s, 0.0f);
        }
        if (levels_.empty()) {  // n == 1
            total_ = w[0];
        } else {
            const int s0 = size_ / 2;
            std::vector<float>& l0 = levels_[0];
            tbb::parallel_for(tbb::blocked_range<int>(0, s0, 8), [&](const tbb::blocked_range<int>& r) {
                for (int y = r.begin(); y != r.end(); ++y)
                    for (int x = 0; x < s0; ++x)
                        l0[size_t(y) * s0 + x] = leaf(2 * x, 2 * y) + leaf(2 * x + 1, 2 * y) + leaf(2 * x, 2 * y + 1) +
                                                 leaf(2 * x + 1, 2 * y + 1);
            });
            for (size_t k = 1; k < levels_.size(); ++k) {
                const int s = s0 >> k, sp = 2 * s;
                const std::vector<float>& below = levels_[k - 1];
                std::vector<float>& out = levels_[k];
                tbb::parallel_for(tbb::blocked_range<int>(0, s, 8), [&](const tbb::blocked_range<int>& r) {
                    for (int y = r.begin(); y != r.end(); ++y)
                        for (int x = 0; x < s; ++x)
                            out[size_t(y) * s + x] = below[size_t(2 * y) * sp + 2 * x] +
                                                     below[size_t(2 * y) * sp + 2 * x + 1] +
                                                     below[size_t(2 * y + 1) * sp + 2 * x] +
                                                     below[size_t(2 * y + 1) * sp + 2 * x + 1];
                });
            }
            total_ = levels_.back()[0];
        }
        pdf_scale_ = total_ > 0 ? float(double(n) * n / total_) : 0.0f;
    }
    size_t memory_bytes() const override {
        size_t b = 0;
        for (const auto& l : levels_) b += l.capacity() * 4;
        return b;
    }

  protected:
    float leaf(int x, int y) const { return x < n_ && y < n_ ? (*weights_)[size_t(y) * n_ + x] : 0.0f; }
    // Value of node (x, y) at depth level d (d = -1: leaves).
    float node(int d, int x, int y) const {
        if (d < 0) return leaf(x, y);
        int s = (size_ / 2) >> d;
        return levels_[size_t(d)][size_t(y) * s + x];
    }
    bool sample_xy(const Vec2& u, Vec2* xy) const override {
        double ux = u.x(), uy = u.y();
        int x = 0, y = 0;
        for (int d = int(levels_.size()) - 2; d >= -1; --d) {
            x *= 2, y *= 2;
            double left = double(node(d, x, y)) + node(d, x, y + 1),
                   right = double(node(d, x + 1, y)) + node(d, x + 1, y + 1);
            if (!(left + right > 0)) return false;
            double pl = left / (left + right);
            if (ux < pl) {
                ux /= pl;
            } else {
                ux = (ux - pl) / (1 - pl), x += 1;
            }
            double top = node(d, x, y), bottom = node(d, x, y + 1);
            double pt = top / (top + bottom);
            if (uy < pt) {
                uy /= pt;
            } else {
                uy = (uy - pt) / (1 - pt), y += 1;
            }
            ux = std::min(ux, 0x1.fffffffffffffp-1), uy = std::min(uy, 0x1.fffffffffffffp-1);
        }
        if (x >= n_ || y >= n_) return false;
        *xy = Vec2(in_cell(x, ux, n_), in_cell(y, uy, n_));
        return true;
    }
    float cell_pdf(int i, int j) const override { return (*weights_)[size_t(j) * n_ + i] * pdf_scale_; }

  private:
    const std::vector<float>* weights_ = nullptr;
    std::vector<std::vector<float>> levels_;
    int size_ = 1;
    float pdf_scale_ = 0;
};

// ---- Sun / sky split ----

class SunSplitSampler : public SkySampler {
  public:
    explicit SunSplitSampler(std::unique_ptr<PixelSampler> base) : base_(std::move(base)) {}

    void build(const SkyImage& sky, SkyWeights& weights) override {
        sun_probability_ = 0;
        weights.apply_compensation();  // the sun is found in the final weights
        double removed = find_and_remove_sun(sky, *weights.values, weights.n);
        base_->build(sky, weights);
        double rest = base_->total();
        if (removed > 0) sun_probability_ = float(removed / (removed + rest));
        cone_pdf_ = sun_probability_ > 0 ? float(1 / (2 * kPiD * one_minus_cos_)) : 0.0f;
    }
    bool sample(const Vec2& u, Vec3* wi, float* pdf, Vec2* uv) const override {
        if (u.x() < sun_probability_) {
            // Uniform in the cone; 1 - cos computed directly keeps a tiny cone precise in float.
            double a = std::min(double(u.x()) / sun_probability_, 1.0) * one_minus_cos_;
            double cos_t = 1 - a, sin_t = std::sqrt(std::max(0.0, a * (2 - a)));
            double phi = 2 * kPiD * u.y();
            Vec3 d = (float(sin_t * std::cos(phi)) * t_ + float(sin_t * std::sin(phi)) * b_ + float(cos_t) * sun_)
                         .normalized();
            if (d.y() < 0) return false;  // the cone's part below the horizon: no sky sample
            *wi = d;
            fisheye::uv_from_direction(d, uv);
        } else {
            Vec2 v((u.x() - sun_probability_) / (1 - sun_probability_), u.y());
            v.x() = std::min(v.x(), 0x1.fffffep-1f);
            float unused;
            if (!base_->sample(v, wi, &unused, uv)) return false;
        }
        *pdf = pdf_uv(*wi, *uv);
        return *pdf > 0;
    }
    float pdf(const Vec3& w) const override {
        if (w.y() < 0) return 0;
        Vec2 uv;
        fisheye::uv_from_direction(w, &uv);
        return pdf_uv(w, uv);
    }
    float pdf_uv(const Vec3& w, const Vec2& uv) const override {
        if (w.y() < 0) return 0;
        float p = (1 - sun_probability_) * base_->pdf_uv(w, uv);
        if (sun_probability_ > 0 && 1 - double(w.dot(sun_)) <= one_minus_cos_) p += sun_probability_ * cone_pdf_;
        return p;
    }
    size_t memory_bytes() const override { return base_->memory_bytes(); }
    float sun_probability() const override { return sun_probability_; }
    bool has_weight() const override { return sun_probability_ > 0 || base_->has_weight(); }

  private:
    // Finds the sun (given direction, else the brightest pixel if it stands far above the mean),
    // fits a cone around its bright pixels with a margin of 0.75 pixel, zeroes the weights of the
    // pixels entirely inside the cone, and returns their sum (0: no sun).
    double find_and_remove_sun(const SkyImage& sky, std::vector<float>& w, int n) {
        auto lum = [&](int i, int j) {
            Vec2 c = fisheye::pixel_center_uv(i, j, n);
            float r2 = c.squaredNorm();
            return r2 > 1 ? 0.0f : w[size_t(j) * n + i] / EnvLight::jacobian_from_r2(r2);
        };
        // Mean luminance over the hemisphere: sum(w) du dv / 2 pi.
        double sum = tbb::parallel_reduce(
            tbb::blocked_range<size_t>(0, w.size(), 1 << 16), 0.0,
            [&](const tbb::blocked_range<size_t>& r, double s) {
                for (size_t k = r.begin(); k != r.end(); ++k) s += w[k];
                return s;
            },
            std::plus<double>());
        double mean = sum * (4.0 / (double(n) * n)) / (2 * kPiD);
        if (!(mean > 0)) return 0;
        int ci, cj;
        if (sky.sun_direction && sky.sun_direction->y() > 0) {
            Vec2 uv;
            fisheye::uv_from_direction(sky.sun_direction->normalized(), &uv);
            ci = std::clamp(int((uv.x() + 1) * 0.5f * n), 0, n - 1),
            cj = std::clamp(int((uv.y() + 1) * 0.5f * n), 0, n - 1);
        } else {
            // Brightest pixel by luminance (weights are luminance x jacobian: divide it out).
            struct Best {
                float l = -1;
                int i = 0, j = 0;
            };
            Best best = tbb::parallel_reduce(
                tbb::blocked_range<int>(0, n, 16), Best{},
                [&](const tbb::blocked_range<int>& r, Best b) {
                    for (int j = r.begin(); j != r.end(); ++j)
                        for (int i = 0; i < n; ++i) {
                            float l = lum(i, j);
                            if (l > b.l) b = {l, i, j};
                        }
                    return b;
                },
                [](const Best& a, const Best& b) { return a.l >= b.l ? a : b; });
            ci = best.i, cj = best.j;
        }
        // Look in a window around the centre for the peak and the disc's bright pixels.
        const int win = std::max(4, n / 32);
        const int i0 = std::max(0, ci - win), i1 = std::min(n - 1, ci + win), j0 = std::max(0, cj - win),
                  j1 = std::min(n - 1, cj + win);
        float peak = 0;
        int pi = ci, pj = cj;
        for (int j = j0; j <= j1; ++j)
            for (int i = i0; i <= i1; ++i)
                if (lum(i, j) > peak) peak = lum(i, j), pi = i, pj = j;
        if (!(peak > kSunContrast * mean)) return 0;  // no sun standing out of the sky
        Vec3 centre = sky.sun_direction && sky.sun_direction->y() > 0
                          ? Vec3(sky.sun_direction->normalized())
                          : fisheye::direction_from_uv(fisheye::pixel_center_uv(pi, pj, n));
        const float threshold = std::max(float(0.05 * peak), float(kSunContrast * mean));
        double max_angle = 0;
        for (int j = j0; j <= j1; ++j)
            for (int i = i0; i <= i1; ++i)
                if (lum(i, j) >= threshold) {
                    Vec3 d = fisheye::direction_from_uv(fisheye::pixel_center_uv(i, j, n));
                    max_angle = std::max(max_angle, std::acos(std::clamp(double(d.dot(centre)), -1.0, 1.0)));
                }
        // A pixel spans at most pi/n radians radially (less across): its corners lie within 0.71
        // pixel of its centre, so this margin takes the whole of every bright pixel into the cone.
        double alpha = max_angle + 0.75 * kPiD / n;
        if (alpha > 0.3) return 0;  // not a compact sun (a bright cloud edge): leave it to the base
        sun_ = centre;
        orthonormal_basis(sun_, &t_, &b_);
        one_minus_cos_ = 2 * std::pow(std::sin(alpha / 2), 2);
        const double cos_alpha = std::cos(alpha);
        auto inside = [&](float u, float v) {
            if (u * u + v * v > 1) return false;
            return double(fisheye::direction_from_uv(Vec2(u, v)).dot(sun_)) >= cos_alpha;
        };
        const int reach = int(std::ceil(alpha / (kPiD / n) * 1.5)) + 2;  // pixels fully inside lie within this
        double removed = 0;
        for (int j = std::max(0, pj - reach); j <= std::min(n - 1, pj + reach); ++j)
            for (int i = std::max(0, pi - reach); i <= std::min(n - 1, pi + reach); ++i) {
                float u0 = 2.0f * i / n - 1, u1 = 2.0f * (i + 1) / n - 1, v0 = 2.0f * j / n - 1,
                      v1 = 2.0f * (j + 1) / n - 1;
                if (inside(u0, v0) && inside(u1, v0) && inside(u0, v1) && inside(u1, v1) &&
                    inside(0.5f * (u0 + u1), v0) && inside(0.5f * (u0 + u1), v1) && inside(u0, 0.5f * (v0 + v1)) &&
                    inside(u1, 0.5f * (v0 + v1))) {
                    removed += w[size_t(j) * n + i];
                    w[size_t(j) * n + i] = 0;
                }
            }
        return removed;
    }

    static constexpr double kSunContrast = 50;  // a sun is at least this many times the mean sky
    std::unique_ptr<PixelSampler> base_;
    Vec3 sun_ = Vec3::UnitY(), t_ = Vec3::UnitX(), b_ = Vec3::UnitZ();
    double one_minus_cos_ = 0;
    float sun_probability_ = 0, cone_pdf_ = 0;
};

const char* method_name(SkySamplerMethod m) {
    switch (m) {
        case SkySamplerMethod::Uniform: return "uniform";
        case SkySamplerMethod::Cosine: return "cosine";
        case SkySamplerMethod::Cdf: return "cdf";
        case SkySamplerMethod::Alias: return "alias";
        case SkySamplerMethod::Mip: return "mip";
    }
    return "?";
}

bool pixel_based(SkySamplerMethod m) {
    return m == SkySamplerMethod::Cdf || m == SkySamplerMethod::Alias || m == SkySamplerMethod::Mip;
}

std::unique_ptr<PixelSampler> make_pixel_sampler(SkySamplerMethod m) {
    switch (m) {
        case SkySamplerMethod::Cdf: return std::make_unique<CdfSampler>();
        case SkySamplerMethod::Alias: return std::make_unique<AliasSampler>();
        case SkySamplerMethod::Mip: return std::make_unique<MipSampler>();
        default: return nullptr;
    }
}

}  // namespace

std::string sky_sampler_name(const SkySamplerOptions& o) {
    std::string s = o.sun_split && pixel_based(o.method) ? "sun+" : "";
    s += method_name(o.method);
    if (o.mis_compensation && pixel_based(o.method)) s += "+mis";
    return s;
}

std::vector<std::string> sky_sampler_base_names() {
    return {"uniform", "cosine", "cdf", "alias", "mip", "sun+cdf", "sun+alias", "sun+mip"};
}

SkySamplerOptions parse_sky_sampler(const std::string& name) {
    SkySamplerOptions o;
    std::string s = name;
    o.sun_split = s.rfind("sun+", 0) == 0;
    if (o.sun_split) s = s.substr(4);
    o.mis_compensation = s.size() > 4 && s.compare(s.size() - 4, 4, "+mis") == 0;
    if (o.mis_compensation) s = s.substr(0, s.size() - 4);
    const SkySamplerMethod all[] = {SkySamplerMethod::Uniform, SkySamplerMethod::Cosine, SkySamplerMethod::Cdf,
                                    SkySamplerMethod::Alias, SkySamplerMethod::Mip};
    for (SkySamplerMethod m : all)
        if (s == method_name(m) && (pixel_based(m) || (!o.sun_split && !o.mis_compensation))) {
            o.method = m;
            return o;
        }
    std::string valid;
    for (const std::string& n : sky_sampler_base_names()) valid += (valid.empty() ? "" : ", ") + n;
    throw Error("unknown sky sampler '" + name + "': valid names are " + valid +
                ", and each pixel-based one (cdf, alias, mip, sun+...) with '+mis' (MIS compensation)");
}

SkySamplerOptions recommended_sky_sampler() {
    // docs/sampling/README.md: with MIS compensation the CDF reaches plain cdf's error soonest
    // under a sunny sky and rebuilds closest to the streaming floor (alias tables sample no faster
    // here and cost several times more to build); the sun split lost everywhere (see there why).
    return SkySamplerOptions{};
}

SkySamplerOptions path_tracer_sky_sampler() {
    SkySamplerOptions o = recommended_sky_sampler();
    o.mis_compensation = true;  // the integrator always combines light and BSDF samples by MIS
    return o;
}

std::unique_ptr<SkySampler> make_sky_sampler(const SkySamplerOptions& o) {
    if (o.method == SkySamplerMethod::Uniform) return std::make_unique<UniformSampler>();
    if (o.method == SkySamplerMethod::Cosine) return std::make_unique<CosineSampler>();
    if (o.sun_split) return std::make_unique<SunSplitSampler>(make_pixel_sampler(o.method));
    return make_pixel_sampler(o.method);
}

}  // namespace dynsky
