#include "renderer/env_light.h"

#include <tbb/parallel_for.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#if defined(__linux__)
#include <sys/mman.h>
#ifndef MADV_COLLAPSE
#define MADV_COLLAPSE 25  // Linux 6.1; older kernels refuse it (EINVAL), which is fine
#endif
#endif

#include <algorithm>
#include <chrono>
#include <limits>

#include "renderer/sampling.h"
#include "sky/fisheye.h"
#include "sky/latlong.h"
#include "util/error.h"

namespace dynsky {

EnvLight::EnvLight(float ground_albedo, const SkySamplerOptions& sampler)
    : sampler_options_(sampler), sampler_(make_sky_sampler(sampler)), ground_albedo_(ground_albedo) {}

EnvLight::EnvLight(std::shared_ptr<const SkyImage> sky, float ground_albedo, const SkySamplerOptions& sampler)
    : EnvLight(ground_albedo, sampler) {
    set_sky(std::move(sky));
}

const Distribution2D& EnvLight::distribution() const {
    static const Distribution2D empty;
    const Distribution2D* d = sampler_->distribution();
    return d ? *d : empty;
}

size_t EnvLight::memory_bytes() const {
    return weights_.capacity() * sizeof(float) +
           (jacobian_table_.capacity() + jacobian_pair_table_.capacity()) * sizeof(uint16_t) + sampler_->memory_bytes();
}

// Radiance as sampled: NaN, infinite and negative channels count as 0.
static inline float sane(float x) { return x >= 0 && x <= std::numeric_limits<float>::max() ? x : 0.0f; }

namespace {

// Row stride of the pair table: groups of four pixels, (jac x 4, cos x jac x 4), the last one padded.
inline size_t pair_row_stride(int n) { return 2 * size_t((n + 3) & ~3); }

using RowSums = EnvLight::RowSums;

// One row of the per-frame pass: weights w = luminance x jacobian, and the sums. Checks every
// channel (sane) and counts bad pixels; the slow path, taken only for rows that hold bad values.
// jt: the row's (jacobian, cos x jacobian) pairs, grouped by four: pixel i's at 2 (i & ~3) + (i & 3), +4.
RowSums weigh_row_checked(const float* rgb, const uint16_t* jt, int n, float* w) {
    RowSums s;
    for (int i = 0; i < n; ++i) {
        float r0 = rgb[3 * i], g0 = rgb[3 * i + 1], b0 = rgb[3 * i + 2];
        float r = sane(r0), g = sane(g0), b = sane(b0);
        s.bad += (r != r0) | (g != g0) | (b != b0);  // NaN != NaN too
        const int at = 2 * (i & ~3) + (i & 3);
        float jac = float(jt[at]), cjac = float(jt[at + 4]);
        w[i] = luminance(r, g, b) * jac;
        s.w += w[i];
        s.er += r * cjac, s.eg += g * cjac, s.eb += b * cjac;
    }
    return s;
}

// The same assuming a sane row, without per-channel checks: false (the row must be redone by
// weigh_row_checked) if it held a NaN, an infinity or a negative value. A NaN or an infinity in any
// channel makes its weight non-finite (NaN x 0 = NaN, Inf x 0 = NaN off the disc), and so the sum
// of weights; a negative value sets a sign bit in the OR of all channels (-0 too, which only costs
// the slow path). This keeps the common case at a few instructions per pixel.
bool weigh_row_fast(const float* rgb, const uint16_t* jt, int n, float* w, RowSums* out) {
    RowSums s;
    float lowest = 0;
    int i = 0;
#if defined(__SSE2__)
    {
        // Four pixels a step: three loads deinterleaved by shuffles into R, G and B lanes.
        const __m128 kr = _mm_set1_ps(kLuminanceR), kg = _mm_set1_ps(kLuminanceG), kb = _mm_set1_ps(kLuminanceB);
        const __m128i zero = _mm_setzero_si128();
        __m128 vw = _mm_setzero_ps(), vr = vw, vg = vw, vb = vw, vsign = vw;
        for (; i + 4 <= n; i += 4) {
            __m128 a = _mm_loadu_ps(rgb + 3 * i), b = _mm_loadu_ps(rgb + 3 * i + 4), c = _mm_loadu_ps(rgb + 3 * i + 8);
            __m128 t0 = _mm_shuffle_ps(a, b, _MM_SHUFFLE(1, 0, 3, 0));  // r0 r1 g1 b1
            __m128 t1 = _mm_shuffle_ps(b, c, _MM_SHUFFLE(2, 1, 3, 2));  // r2 g2 r3 g3
            __m128 r = _mm_shuffle_ps(t0, t1, _MM_SHUFFLE(2, 0, 1, 0));
            __m128 g = _mm_shuffle_ps(_mm_shuffle_ps(a, t0, _MM_SHUFFLE(2, 2, 1, 1)), t1, _MM_SHUFFLE(3, 1, 2, 0));
            __m128 bl = _mm_shuffle_ps(_mm_shuffle_ps(a, t0, _MM_SHUFFLE(3, 3, 2, 2)),
                                       _mm_shuffle_ps(c, c, _MM_SHUFFLE(3, 3, 0, 0)), _MM_SHUFFLE(2, 0, 2, 0));
            __m128i pairs = _mm_loadu_si128(reinterpret_cast<const __m128i*>(jt + 2 * i));  // jac x 4, cos x jac x 4
            __m128 jac = _mm_cvtepi32_ps(_mm_unpacklo_epi16(pairs, zero)),
                   cjac = _mm_cvtepi32_ps(_mm_unpackhi_epi16(pairs, zero));
            __m128 wi = _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(kr, r), _mm_mul_ps(kg, g)), _mm_mul_ps(kb, bl)),
                                   jac);
            _mm_storeu_ps(w + i, wi);
            vw = _mm_add_ps(vw, wi);
            vr = _mm_add_ps(vr, _mm_mul_ps(r, cjac)), vg = _mm_add_ps(vg, _mm_mul_ps(g, cjac)),
            vb = _mm_add_ps(vb, _mm_mul_ps(bl, cjac));
            vsign = _mm_or_ps(vsign, _mm_or_ps(a, _mm_or_ps(b, c)));
        }
        alignas(16) float lanes[4][4];
        _mm_store_ps(lanes[0], vw), _mm_store_ps(lanes[1], vr), _mm_store_ps(lanes[2], vg), _mm_store_ps(lanes[3], vb);
        for (int k = 0; k < 4; ++k) s.w += lanes[0][k], s.er += lanes[1][k], s.eg += lanes[2][k], s.eb += lanes[3][k];
        if (_mm_movemask_ps(vsign) != 0) return false;
    }
#endif
    for (; i < n; ++i) {
        float r = rgb[3 * i], g = rgb[3 * i + 1], b = rgb[3 * i + 2];
        const int at = 2 * (i & ~3) + (i & 3);
        float jac = float(jt[at]), cjac = float(jt[at + 4]);
        w[i] = luminance(r, g, b) * jac;
        s.w += w[i];
        s.er += r * cjac, s.eg += g * cjac, s.eb += b * cjac;
        lowest = std::min({lowest, r, g, b});
    }
    *out = s;
    const float kMax = std::numeric_limits<float>::max();
    // Finite, non-negative sums of finite, non-negative values; anything else: redo the row.
    return lowest >= 0 && s.w >= 0 && s.w <= kMax && s.er <= kMax && s.eg <= kMax && s.eb <= kMax;
}

}  // namespace

float EnvLight::jacobian_from_r2(float r2) {
    // sin(x)/x = sum (-1)^k x^(2k) / (2k+1)!, x^2 = (pi^2/4) r^2 <= 2.47: error < 1e-9 with 7 terms.
    float x2 = (kPi * kPi / 4) * r2;
    float s = 1.0f + x2 * (-1.0f / 6 +
                           x2 * (1.0f / 120 +
                                 x2 * (-1.0f / 5040 +
                                       x2 * (1.0f / 362880 + x2 * (-1.0f / 39916800 + x2 * (1.0f / 6227020800.0f))))));
    return (kPi * kPi / 4) * s;
}

float EnvLight::cos_theta_from_r2(float r2) {
    float x2 = (kPi * kPi / 4) * r2;
    return 1.0f +
           x2 * (-1.0f / 2 +
                 x2 * (1.0f / 24 +
                       x2 * (-1.0f / 720 + x2 * (1.0f / 40320 + x2 * (-1.0f / 3628800 + x2 * (1.0f / 479001600.0f))))));
}

void EnvLight::set_sky(std::shared_ptr<const SkyImage> sky) {
    if (!sky || sky->resolution <= 0) throw Error("environment light: empty sky image");
    auto start = std::chrono::steady_clock::now();
    sky_ = std::move(sky);
    const int n = sky_->resolution;
    const float* rgb = sky_->rgb.data();
    const float du = 2.0f / n;

    // Per-pixel solid angle (0 outside the disc) and cos x solid angle depend only on N: tabulated
    // once, as 16-bit fixed point (relative precision 2e-5, plenty for importance weights and the
    // ground's irradiance), so the per-frame pass is a branch-free stream that reads 4 bytes of
    // table per pixel beside the 12 of the image, and vectorises.
    constexpr float kTableMax = kPi * kPi / 4;  // the largest jacobian (at the zenith)
    constexpr float kToFixed = 65535.0f / kTableMax, kFromFixed = kTableMax / 65535.0f;
    if (table_resolution_ != n) {
        jacobian_table_.assign(size_t(n) * n, 0);
        jacobian_pair_table_.assign(size_t(n) * pair_row_stride(n), 0);
        jacobian_table_sum_ = 0;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                float u = (i + 0.5f) * du - 1.0f, v = (j + 0.5f) * du - 1.0f, r2 = u * u + v * v;
                if (r2 > 1.0f) continue;  // centre below the horizon: the rim is looked up inward
                float jac = jacobian_from_r2(r2);
                const size_t k = size_t(j) * n + i;
                // Pairs in groups of four pixels, (jac x 4, cos x jac x 4): one load and two unpacks.
                const size_t g = size_t(j) * pair_row_stride(n) + 2 * (i & ~3) + (i & 3);
                jacobian_table_[k] = jacobian_pair_table_[g] = uint16_t(std::lround(jac * kToFixed));
                jacobian_pair_table_[g + 4] = uint16_t(std::lround(jac * cos_theta_from_r2(r2) * kToFixed));
                jacobian_table_sum_ += jacobian_table_[k];
            }
        table_resolution_ = n;
    }
    row_sums_.resize(size_t(n));
    weights_.resize(size_t(n) * n);
    tbb::parallel_for(tbb::blocked_range<int>(0, n, 16), [&](const tbb::blocked_range<int>& rows) {
        for (int j = rows.begin(); j != rows.end(); ++j) {
            const uint16_t* jt = &jacobian_pair_table_[size_t(j) * pair_row_stride(n)];
            const float* row = rgb + size_t(j) * n * 3;
            float* w = &weights_[size_t(j) * n];
            RowSums& sums = row_sums_[size_t(j)];
            if (!weigh_row_fast(row, jt, n, w, &sums)) sums = weigh_row_checked(row, jt, n, w);
        }
    });
    bad_pixels_ = 0;
    double total_weight = 0;  // row sums come from the parallel pass above: no serial re-read
    Eigen::Array3d e = Eigen::Array3d::Zero();
    for (const RowSums& row : row_sums_) {
        bad_pixels_ += size_t(row.bad);
        total_weight += row.w;
        e += Eigen::Array3d(row.er, row.eg, row.eb) * double(kFromFixed);
    }
    sky_irradiance_ = (e * double(du * du)).cast<float>();
    ground_radiance_ = ground_image_ ? ground_image_mean_ : Color(ground_albedo_ * sky_irradiance_ * kInvPi);

    // Power (luminance x solid angle) decides how often each part is sampled.
    // Weights carry the fixed-point scale of the table; integral over [0,1]^2 -> over [-1,1]^2.
    double sky_power = total_weight * double(du) * du * double(kFromFixed);
    double ground_power = double(luminance(ground_radiance_)) * 2 * kPiD;
    sky_probability_ = sky_power + ground_power > 0 ? float(sky_power / (sky_power + ground_power)) : 1.0f;

    SkyWeights weights;
    weights.values = &weights_;
    weights.jacobian = jacobian_table_.data();
    weights.n = n;
    // MIS compensation (Karlik et al. 2019 as in pbrt-v4): sample max(L - mean L, 0), where BSDF
    // sampling already does well on the rest. The sampler applies it in its own pass over the
    // weights; in weight units, L jac - mean jac with mean = sum(L jac) / sum(jac).
    if (sampler_options_.mis_compensation && jacobian_table_sum_ > 0)
        weights.mis_floor = float(total_weight / jacobian_table_sum_);
    sampler_->build(*sky_, weights);
    if (sampler_options_.mis_compensation && !sampler_->has_weight() && total_weight > 0) {
        // A uniform sky leaves nothing above its mean: sample uniformly in solid angle instead.
        weights_.resize(size_t(n) * n);  // a sampler may have taken the buffer
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) weights_[size_t(j) * n + i] = float(jacobian_table_[size_t(j) * n + i]);
        weights.mis_floor = 0;
        sampler_->build(*sky_, weights);
    }
    // Escaping rays read the image, the weights and the MIS baseline at random: with 4 KB pages each
    // read is also a page walk (the prefetch waits on it). Once per buffer, not per frame.
    back_by_huge_pages(sky_->rgb.data(), sky_->rgb.size() * sizeof(float));
    back_by_huge_pages(jacobian_table_.data(), jacobian_table_.size() * sizeof(uint16_t));
    if (const Distribution2D* d = sampler_->distribution())
        back_by_huge_pages(d->weights().data(), d->weights().size() * sizeof(float));
    build_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void EnvLight::back_by_huge_pages(const void* data, size_t bytes) {
#if defined(__linux__)
    constexpr uintptr_t kHuge = uintptr_t(1) << 21;
    const uintptr_t lo = (reinterpret_cast<uintptr_t>(data) + kHuge - 1) & ~(kHuge - 1);
    const uintptr_t hi = (reinterpret_cast<uintptr_t>(data) + bytes) & ~(kHuge - 1);
    if (hi <= lo || std::find(huge_buffers_.begin(), huge_buffers_.end(), data) != huge_buffers_.end()) return;
    madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_COLLAPSE);  // advice: refused is fine
    if (huge_buffers_.size() >= 8) huge_buffers_.erase(huge_buffers_.begin());
    huge_buffers_.push_back(data);
#else
    (void)data, (void)bytes;
#endif
}

void EnvLight::set_ground_image(std::shared_ptr<const SkyImage> ground) {
    if (ground && ground->resolution <= 0) throw Error("environment light: empty ground image");
    ground_image_ = std::move(ground);
    if (ground_image_) {
        const int n = ground_image_->resolution;
        Eigen::Array3d sum = Eigen::Array3d::Zero();
        double area = 0;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                if (!ground_image_->in_disc(i, j)) continue;
                double a = fisheye::pixel_solid_angle(i, j, n);
                Color c = ground_image_->pixel(i, j);
                for (int k = 0; k < 3; ++k) sum[k] += a * sane(c[k]);
                area += a;
            }
        ground_image_mean_ = area > 0 ? Color((sum / area).cast<float>()) : Color::Zero();
        // Weights as the sky's: luminance x dw/(du dv) in the same fixed point (0 off the disc).
        constexpr float kToFixed = 65535.0f / (kPi * kPi / 4);
        const float du = 2.0f / n;
        ground_jacobian_.assign(size_t(n) * n, 0);
        ground_weights_.assign(size_t(n) * n, 0.0f);
        double total = 0, jacobian_sum = 0;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                float u = (i + 0.5f) * du - 1.0f, v = (j + 0.5f) * du - 1.0f, r2 = u * u + v * v;
                if (r2 > 1.0f) continue;
                const size_t k = size_t(j) * n + i;
                ground_jacobian_[k] = uint16_t(std::lround(jacobian_from_r2(r2) * kToFixed));
                Color c = ground_image_->pixel(i, j);
                ground_weights_[k] = luminance(Color(sane(c[0]), sane(c[1]), sane(c[2]))) * float(ground_jacobian_[k]);
                total += ground_weights_[k], jacobian_sum += ground_jacobian_[k];
            }
        ground_sampler_ = make_sky_sampler(sampler_options_);
        SkyWeights weights;
        weights.values = &ground_weights_;
        weights.jacobian = ground_jacobian_.data();
        weights.n = n;
        if (sampler_options_.mis_compensation && jacobian_sum > 0) weights.mis_floor = float(total / jacobian_sum);
        ground_sampler_->build(*ground_image_, weights);
        if (!ground_sampler_->has_weight() && total > 0) {
            // Nothing above the mean (a uniform ground): uniform in solid angle over the disc.
            ground_weights_.resize(size_t(n) * n);
            for (size_t k = 0; k < ground_weights_.size(); ++k) ground_weights_[k] = float(ground_jacobian_[k]);
            weights.mis_floor = 0;
            ground_sampler_->build(*ground_image_, weights);
        }
        if (!ground_sampler_->has_weight()) ground_sampler_.reset();  // a black ground: sampled uniformly
    } else {
        ground_sampler_.reset();
    }
    if (sky_) set_sky(sky_);  // the sky / ground split of light samples follows the ground's power
}

Color EnvLight::ground(const Vec3& w) const {
    if (!ground_image_) return ground_radiance_;
    // The nearest pixel of the mirrored fisheye (rim pixels inward, as the sky's), the cell the
    // sampler's pdf reads.
    const SkyImage& g = *ground_image_;
    const int n = g.resolution;
    Vec2 p;
    fisheye::uv_from_direction(Vec3(w.x(), -w.y(), w.z()), &p);
    int k = (n / 2) * n + n / 2;
    for (int step = 0; step < 4; ++step) {
        int i = std::clamp(int((p.x() + 1) * 0.5f * n), 0, n - 1);
        int j = std::clamp(int((p.y() + 1) * 0.5f * n), 0, n - 1);
        if (fisheye::pixel_center_uv(i, j, n).squaredNorm() <= 1.0f) {
            k = j * n + i;
            break;
        }
        float r = p.norm();
        p *= std::max(0.0f, (r - 1.0f / n)) / std::max(r, 1e-12f);
    }
    const float* c = &g.rgb[size_t(k) * 3];
    return Color(sane(c[0]), sane(c[1]), sane(c[2]));
}

float EnvLight::ground_pdf(const Vec3& w) const {
    if (!ground_sampler_) return 1 / (2 * kPi);
    return ground_sampler_->pdf(Vec3(w.x(), -w.y(), w.z()));
}

namespace {

// atan2(s, c) for s, c >= 0 without libm: Cephes' atanf (reduction to |x| <= tan(pi/8), degree-9
// odd polynomial), within 2e-7 rad; libm's atan2f was a fifth of a sky-only frame.
inline float atan2_nonnegative(float s, float c) {
    const float lo = std::min(s, c), hi = std::max(s, c);
    // atan(t) for t = lo / hi in [0, 1]; above tan(pi/8) as pi/4 + atan((t - 1) / (t + 1)).
    const bool upper = lo > 0.41421356f * hi;
    const float x = upper ? (lo - hi) / (lo + hi) : (hi > 0 ? lo / hi : 0.0f), z = x * x;
    float a = (((8.05374449538e-2f * z - 1.38776856032e-1f) * z + 1.99777106478e-1f) * z - 3.33329491539e-1f) * z * x +
              x;
    if (upper) a += kPi / 4;
    return s > c ? kPi / 2 - a : a;
}

// fisheye::uv_from_direction(w) with atan2_nonnegative; w.y() >= 0.
inline Vec2 fast_uv(const Vec3& w) {
    const float s = std::sqrt(w.x() * w.x() + w.z() * w.z());
    const float theta = atan2_nonnegative(s, w.y());
    const float k = s > 1e-4f ? (2 / kPi) * theta / s : (2 / kPi) * (1 + theta * theta / 6);
    return Vec2(-w.x() * k, w.z() * k);
}

}  // namespace

int EnvLight::lookup_pixel(const Vec2& uv) const {
    const int n = sky_->resolution;
    Vec2 p = uv;
    for (int step = 0; step < 4; ++step) {
        int i = std::clamp(int((p.x() + 1) * 0.5f * n), 0, n - 1);
        int j = std::clamp(int((p.y() + 1) * 0.5f * n), 0, n - 1);
        if (fisheye::pixel_center_uv(i, j, n).squaredNorm() <= 1.0f) return j * n + i;
        // Rim pixel: step half a pixel inward along the radius.
        float r = p.norm();
        p *= std::max(0.0f, (r - 1.0f / n)) / std::max(r, 1e-12f);
    }
    return (n / 2) * n + n / 2;
}

Color EnvLight::pixel_radiance(int k) const {
    const float* p = &sky_->rgb[size_t(k) * 3];
    return Color(sane(p[0]), sane(p[1]), sane(p[2]));
}

Color EnvLight::radiance(const Vec3& w) const {
    if (w.y() < 0) return ground(w);
    Vec2 uv;
    fisheye::uv_from_direction(w, &uv);
    return sky_radiance(uv);
}

Color EnvLight::radiance(const Vec3& w, float* pdf) const {
    if (w.y() < 0) {
        *pdf = (1 - sky_probability_) * ground_pdf(w);
        return ground(w);
    }
    Vec2 uv;
    fisheye::uv_from_direction(w, &uv);
    *pdf = sky_probability_ * sampler_->pdf_uv(w, uv);
    return sky_radiance(uv);
}

Color EnvLight::radiance_filtered(const Vec3& w) const { return w.y() < 0 ? ground(w) : filtered_at(w, fast_uv(w)); }

Color EnvLight::filtered_at(const Vec3& w, const Vec2& uv) const {
    const int n = sky_->resolution;
    // Continuous pixel coordinates (pixel centres at integers); no black from outside the disc.
    const float fx = (uv.x() + 1) * 0.5f * n - 0.5f, fy = (uv.y() + 1) * 0.5f * n - 0.5f;
    Color c;
    // Away from the rim (all four neighbours' centres lie within 2 sqrt(2) / n of uv, well inside
    // the disc) the disc tests of bilinear_in_disc all pass: the same sums without them (the tests
    // cost 8 divisions, and nearly every camera ray that sees the sky lands here).
    const float inner = 1.0f - 4.0f / n;
    if (inner > 0 && uv.squaredNorm() <= inner * inner &&
        fisheye::bilinear_in_disc<false>(sky_->rgb.data(), n, fx, fy, &c))
        return c;
    return fisheye::bilinear_in_disc(sky_->rgb.data(), n, fx, fy, &c) ? c : radiance(w);
}

void EnvLight::radiance_filtered(const Vec3* w, int count, Color* out) const {
    const int n = sky_->resolution;
    // First pass: the mappings (kept in out) and the two rows of texels each lookup reads.
    for (int k = 0; k < count; ++k) {
        if (w[k].y() < 0) continue;
        const Vec2 uv = fast_uv(w[k]);
        out[k] = Color(uv.x(), uv.y(), 0);
        const int i = std::clamp(int((uv.x() + 1) * 0.5f * n - 0.5f), 0, n - 2);
        const int j = std::clamp(int((uv.y() + 1) * 0.5f * n - 0.5f), 0, n - 2);
        const float* p = &sky_->rgb[(size_t(j) * n + i) * 3];
        __builtin_prefetch(p), __builtin_prefetch(p + 5);  // 24 bytes: may straddle two lines
        __builtin_prefetch(p + 3 * n), __builtin_prefetch(p + 3 * n + 5);
    }
    for (int k = 0; k < count; ++k)
        out[k] = w[k].y() < 0 ? ground(w[k]) : filtered_at(w[k], Vec2(out[k].x(), out[k].y()));
}

namespace {

// fisheye::uv_from_direction within a small fraction of a pixel, without the libm atan2: enough to
// name the cache lines a lookup will read. w unit, w.y() >= 0.
Vec2 approximate_uv(const Vec3& w) {
    const float s = std::sqrt(w.x() * w.x() + w.z() * w.z()), c = w.y();
    // theta = atan2(s, c) in [0, pi/2] from atan on [0, 1] (odd minimax polynomial, error ~1e-5 rad).
    const float lo = std::min(s, c), hi = std::max(s, c);
    const float t = hi > 0 ? lo / hi : 0.0f, t2 = t * t;
    float a = t *
              (0.99997726f +
               t2 * (-0.33262347f + t2 * (0.19354346f + t2 * (-0.11643287f + t2 * (0.05265332f - t2 * 0.01172120f)))));
    const float theta = s > c ? kPi / 2 - a : a;
    const float k = s > 1e-4f ? (2 / kPi) * theta / s : 2 / kPi;
    return Vec2(-w.x() * k, w.z() * k);
}

}  // namespace

void EnvLight::prefetch(const Vec3& w) const {
    if (!sky_ || w.y() < 0) return;
    const Vec2 uv = approximate_uv(w);
    const int n = sky_->resolution;
    const int i = std::clamp(int((uv.x() + 1) * 0.5f * n), 0, n - 1);
    const int j = std::clamp(int((uv.y() + 1) * 0.5f * n), 0, n - 1);
    __builtin_prefetch(&sky_->rgb[(size_t(j) * n + i) * 3]);
    if (const Distribution2D* d = sampler_->distribution(); d && d->width() == n && d->height() == n)
        d->prefetch_cell(i, j);
}

float EnvLight::pdf(const Vec3& w) const {
    if (w.y() < 0) return (1 - sky_probability_) * ground_pdf(w);
    return sky_probability_ * sampler_->pdf(w);
}

bool EnvLight::sample(float u_choice, const Vec2& u, EnvLightSample* out) const {
    if (u_choice < sky_probability_) {
        float pdf;
        Vec2 uv;
        if (!sampler_->sample(u, &out->wi, &pdf, &uv)) return false;
        out->radiance = sky_radiance(uv);
        out->pdf = sky_probability_ * pdf;
        return out->pdf > 0;
    }
    if (ground_sampler_) {
        Vec3 up;  // in the mirrored fisheye: its up is down
        float pdf;
        Vec2 uv;
        if (!ground_sampler_->sample(u, &up, &pdf, &uv)) return false;
        out->wi = Vec3(up.x(), -up.y(), up.z());
        out->radiance = ground(out->wi);
        out->pdf = (1 - sky_probability_) * pdf;
        return out->pdf > 0;
    }
    Vec3 h = sample_uniform_hemisphere(u);  // about +Z; map +Z to -Y (down)
    out->wi = Vec3(h.x(), -h.z(), h.y());
    out->radiance = ground(out->wi);
    out->pdf = (1 - sky_probability_) / (2 * kPi);
    return out->pdf > 0;
}

}  // namespace dynsky
