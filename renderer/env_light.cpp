#include "renderer/env_light.h"

#include <chrono>

#include "renderer/sampling.h"
#include "sky/fisheye.h"
#include "util/error.h"

namespace dynsky {

EnvLight::EnvLight(std::shared_ptr<const SkyImage> sky, float ground_albedo) : ground_albedo_(ground_albedo) {
    set_sky(std::move(sky));
}

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
    distribution_.build_rows(n, n, [&](int j, float* w) {
        const float* row = rgb + size_t(j) * n * 3;
        const uint16_t* t = &solid_angle_table_[size_t(j) * n * 2];
        float er = 0, eg = 0, eb = 0;
        for (int i = 0; i < n; ++i) {
            float r = row[3 * i], g = row[3 * i + 1], b = row[3 * i + 2];
            float jac = float(t[2 * i]), cjac = float(t[2 * i + 1]);
            w[i] = (0.2126f * r + 0.7152f * g + 0.0722f * b) * jac;
            er += r * cjac, eg += g * cjac, eb += b * cjac;
        }
        row_irradiance_[size_t(j)] = Eigen::Array3d(er, eg, eb) * double(kFromFixed);
    });
    Eigen::Array3d e = Eigen::Array3d::Zero();
    for (const auto& part : row_irradiance_) e += part;
    sky_irradiance_ = (e * double(du * du)).cast<float>();
    ground_radiance_ = ground_albedo_ * sky_irradiance_ * kInvPi;

    // Power (luminance x solid angle) decides how often each part is sampled.
    // Weights carry the fixed-point scale of the table; integral over [0,1]^2 -> over [-1,1]^2.
    double sky_power = distribution_.integral() * 4.0 * (kPiD * kPiD / 4) / 65535.0;
    double ground_power = double(luminance(ground_radiance_)) * 2 * kPiD;
    sky_probability_ = sky_power + ground_power > 0 ? float(sky_power / (sky_power + ground_power)) : 1.0f;
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
    return Color(p[0], p[1], p[2]);
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
    if (distribution_.empty()) return 0;
    Vec2 uv;
    fisheye::uv_from_direction(w, &uv);
    Vec2 xy = 0.5f * (uv + Vec2::Ones());
    float pdf_uv = distribution_.pdf(xy) * 0.25f;
    return sky_probability_ * pdf_uv / jacobian_from_r2(uv.squaredNorm());
}

bool EnvLight::sample(float u_choice, const Vec2& u, EnvLightSample* out) const {
    if (u_choice < sky_probability_) {
        Vec2 xy;
        float pdf_xy;
        if (!distribution_.sample(u, &xy, &pdf_xy)) return false;
        Vec2 uv = 2.0f * xy - Vec2::Ones();
        float r2 = uv.squaredNorm();
        if (r2 > 1.0f) return false;  // the part of a rim pixel below the horizon
        out->wi = fisheye::direction_from_uv(uv);
        // Radiance and pdf through the same lookup that radiance() and pdf() use, so a direction
        // that rounds across a pixel edge still reports matching values (no fireflies).
        Vec2 uv_back;
        fisheye::uv_from_direction(out->wi, &uv_back);
        const float* p = &sky_->rgb[size_t(lookup_pixel(uv_back)) * 3];
        out->radiance = Color(p[0], p[1], p[2]);
        out->pdf = sky_probability_ * distribution_.pdf(0.5f * (uv_back + Vec2::Ones())) * 0.25f /
                   jacobian_from_r2(uv_back.squaredNorm());
        return out->pdf > 0;
    }
    Vec3 h = sample_uniform_hemisphere(u);  // about +Z; map +Z to -Y (down)
    out->wi = Vec3(h.x(), -h.z(), h.y());
    out->radiance = ground_radiance_;
    out->pdf = (1 - sky_probability_) / (2 * kPi);
    return out->pdf > 0;
}

}  // namespace dynsky
