#include "renderer/env_light.h"

#include <tbb/parallel_for.h>

#include <chrono>
#include <limits>

#include "renderer/sampling.h"
#include "sky/fisheye.h"
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
    return weights_.capacity() * sizeof(float) + solid_angle_table_.capacity() * sizeof(uint16_t) + sampler_->memory_bytes();
}

// Radiance as sampled: NaN, infinite and negative channels count as 0.
static inline float sane(float x) { return x >= 0 && x <= std::numeric_limits<float>::max() ? x : 0.0f; }

float EnvLight::jacobian_from_r2(float r2) {
    // sin(x)/x = sum (-1)^k x^(2k) / (2k+1)!, x^2 = (pi^2/4) r^2 <= 2.47: error < 1e-9 with 7 terms.
    float x2 = (kPi * kPi / 4) * r2;
    float s = 1.0f + x2 * (-1.0f / 6 + x2 * (1.0f / 120 + x2 * (-1.0f / 5040 + x2 * (1.0f / 362880 +
              x2 * (-1.0f / 39916800 + x2 * (1.0f / 6227020800.0f))))));
    return (kPi * kPi / 4) * s;
}

float EnvLight::cos_theta_from_r2(float r2) {
    float x2 = (kPi * kPi / 4) * r2;
    return 1.0f + x2 * (-1.0f / 2 + x2 * (1.0f / 24 + x2 * (-1.0f / 720 + x2 * (1.0f / 40320 +
           x2 * (-1.0f / 3628800 + x2 * (1.0f / 479001600.0f))))));
}

void EnvLight::set_sky(std::shared_ptr<const SkyImage> sky) {
    if (!sky || sky->resolution <= 0) throw Error("environment light: empty sky image");
    auto start = std::chrono::steady_clock::now();
    sky_ = std::move(sky);
    const int n = sky_->resolution;
    const float* rgb = sky_->rgb.data();
    const float du = 2.0f / n;

    // Per-pixel solid angle (0 outside the disc) and cos x solid angle depend only on N: tabulated
    // once, as 16-bit fixed point pairs (relative precision 2e-5, plenty for importance weights
    // and the ground's irradiance), so the per-frame pass is a branch-free stream that reads
    // 4 bytes of table per pixel beside the 12 of the image, and vectorises.
    constexpr float kTableMax = kPi * kPi / 4;  // the largest jacobian (at the zenith)
    constexpr float kToFixed = 65535.0f / kTableMax, kFromFixed = kTableMax / 65535.0f;
    if (table_resolution_ != n) {
        solid_angle_table_.assign(size_t(n) * n * 2, 0);
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                float u = (i + 0.5f) * du - 1.0f, v = (j + 0.5f) * du - 1.0f, r2 = u * u + v * v;
                if (r2 > 1.0f) continue;  // centre below the horizon: the rim is looked up inward
                float jac = jacobian_from_r2(r2);
                solid_angle_table_[2 * (size_t(j) * n + i)] = uint16_t(std::lround(jac * kToFixed));
                solid_angle_table_[2 * (size_t(j) * n + i) + 1] = uint16_t(std::lround(jac * cos_theta_from_r2(r2) * kToFixed));
            }
        table_resolution_ = n;
    }
    row_irradiance_.assign(size_t(n), Eigen::Array3d::Zero());
    row_bad_.assign(size_t(n), 0);
    row_weight_.assign(size_t(n), 0.0);
    weights_.resize(size_t(n) * n);
    tbb::parallel_for(tbb::blocked_range<int>(0, n, 16), [&](const tbb::blocked_range<int>& rows) {
        for (int j = rows.begin(); j != rows.end(); ++j) {
            const float* row = rgb + size_t(j) * n * 3;
            const uint16_t* t = &solid_angle_table_[size_t(j) * n * 2];
            float* w = &weights_[size_t(j) * n];
            float er = 0, eg = 0, eb = 0, wsum = 0;
            size_t bad = 0;
            for (int i = 0; i < n; ++i) {
                float r0 = row[3 * i], g0 = row[3 * i + 1], b0 = row[3 * i + 2];
                float r = sane(r0), g = sane(g0), b = sane(b0);
                bad += (r != r0) | (g != g0) | (b != b0);  // NaN != NaN too
                float jac = float(t[2 * i]), cjac = float(t[2 * i + 1]);
                w[i] = (0.2126f * r + 0.7152f * g + 0.0722f * b) * jac;
                wsum += w[i];
                er += r * cjac, eg += g * cjac, eb += b * cjac;
            }
            row_irradiance_[size_t(j)] = Eigen::Array3d(er, eg, eb) * double(kFromFixed);
            row_weight_[size_t(j)] = wsum;
            row_bad_[size_t(j)] = bad;
        }
    });
    bad_pixels_ = 0;
    for (size_t b : row_bad_) bad_pixels_ += b;
    double total_weight = 0;  // row sums come from the parallel pass above: no serial re-read
    for (double row : row_weight_) total_weight += row;
    if (sampler_options_.mis_compensation) compensate_for_mis(total_weight);
    Eigen::Array3d e = Eigen::Array3d::Zero();
    for (const auto& part : row_irradiance_) e += part;
    sky_irradiance_ = (e * double(du * du)).cast<float>();
    ground_radiance_ = ground_albedo_ * sky_irradiance_ * kInvPi;

    // Power (luminance x solid angle) decides how often each part is sampled.
    // Weights carry the fixed-point scale of the table; integral over [0,1]^2 -> over [-1,1]^2.
    double sky_power = total_weight * double(du) * du * double(kFromFixed);
    double ground_power = double(luminance(ground_radiance_)) * 2 * kPiD;
    sky_probability_ = sky_power + ground_power > 0 ? float(sky_power / (sky_power + ground_power)) : 1.0f;
    sampler_->build(*sky_, weights_, n);
    build_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

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

Color EnvLight::radiance(const Vec3& w) const {
    if (w.y() < 0) return ground_radiance_;
    Vec2 uv;
    fisheye::uv_from_direction(w, &uv);
    const float* p = &sky_->rgb[size_t(lookup_pixel(uv)) * 3];
    return Color(sane(p[0]), sane(p[1]), sane(p[2]));
}

Color EnvLight::radiance_filtered(const Vec3& w) const {
    if (w.y() < 0) return ground_radiance_;
    Vec2 uv;
    fisheye::uv_from_direction(w, &uv);
    const int n = sky_->resolution;
    // Continuous pixel coordinates (pixel centres at integers), clamped to the disc's pixels.
    float fx = (uv.x() + 1) * 0.5f * n - 0.5f, fy = (uv.y() + 1) * 0.5f * n - 0.5f;
    int x0 = int(std::floor(fx)), y0 = int(std::floor(fy));
    float tx = fx - x0, ty = fy - y0;
    Color sum = Color::Zero();
    float weight = 0;
    for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
            int x = x0 + dx, y = y0 + dy;
            if (x < 0 || y < 0 || x >= n || y >= n || !sky_->in_disc(x, y)) continue;  // no black from outside
            float wgt = (dx ? tx : 1 - tx) * (dy ? ty : 1 - ty);
            sum += wgt * sky_->pixel(x, y);
            weight += wgt;
        }
    return weight > 0 ? Color(sum / weight) : radiance(w);
}

float EnvLight::pdf(const Vec3& w) const {
    if (w.y() < 0) return (1 - sky_probability_) / (2 * kPi);
    return sky_probability_ * sampler_->pdf(w);
}

bool EnvLight::sample(float u_choice, const Vec2& u, EnvLightSample* out) const {
    if (u_choice < sky_probability_) {
        float pdf;
        if (!sampler_->sample(u, &out->wi, &pdf)) return false;
        out->radiance = radiance(out->wi);
        out->pdf = sky_probability_ * pdf;
        return out->pdf > 0;
    }
    Vec3 h = sample_uniform_hemisphere(u);  // about +Z; map +Z to -Y (down)
    out->wi = Vec3(h.x(), -h.z(), h.y());
    out->radiance = ground_radiance_;
    out->pdf = (1 - sky_probability_) / (2 * kPi);
    return out->pdf > 0;
}

void EnvLight::compensate_for_mis(double total_weight) {
    // Karlik et al. 2019 as in pbrt-v4: sample max(L - mean L, 0), where BSDF sampling already
    // does well on the rest; uniform in solid angle if that leaves nothing. Same fixed-point
    // scale as the weights: mean = sum(L jac) / sum(jac).
    const int n = table_resolution_;
    double jac_sum = 0;
    for (size_t k = 0; k < solid_angle_table_.size(); k += 2) jac_sum += solid_angle_table_[k];
    const float mean = jac_sum > 0 ? float(total_weight / jac_sum) : 0.0f;
    std::vector<double> row_sum(size_t(n), 0.0);
    tbb::parallel_for(tbb::blocked_range<int>(0, n, 16), [&](const tbb::blocked_range<int>& rows) {
        for (int j = rows.begin(); j != rows.end(); ++j) {
            float* w = &weights_[size_t(j) * n];
            const uint16_t* t = &solid_angle_table_[size_t(j) * n * 2];
            float s = 0;
            for (int i = 0; i < n; ++i) {
                w[i] = std::max(w[i] - mean * float(t[2 * i]), 0.0f);
                s += w[i];
            }
            row_sum[size_t(j)] = s;
        }
    });
    double left = 0;
    for (double r : row_sum) left += r;
    if (!(left > 0))
        for (size_t k = 0; k < weights_.size(); ++k) weights_[k] = float(solid_angle_table_[2 * k]);
}

}  // namespace dynsky
