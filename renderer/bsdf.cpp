#include "renderer/bsdf.h"

#include "renderer/sampling.h"

namespace dynsky {

// Below this GGX alpha the lobe is so sharp that float pdfs overflow; 1e-3 still looks mirror-like.
constexpr float kMinAlpha = 1e-3f;
// The clear coat's Fresnel at normal incidence: KHR_materials_clearcoat's fixed IOR 1.5.
constexpr float kCoatF0 = 0.04f;

static float schlick_weight(float cos_theta) {
    float m = clamp(1.0f - cos_theta, 0.0f, 1.0f);
    float m2 = m * m;
    return m2 * m2 * m;
}

namespace {

// The mu of node i of the albedo tables below: uniform in sqrt(mu), so that nodes crowd towards
// grazing, where a smooth lobe's albedo falls steeply (over mu < 2 alpha). Spaced uniformly in mu,
// the first cell (mu < 1/31, 88.2 degrees) read a smooth dielectric's albedo as 0.83 where it is
// 0.96, and the base under it, weighted by 1 - E, reflected up to 9 % more than came in.
template <int kSize>
float table_mu(int i) {
    const float t = float(i) / (kSize - 1);
    return std::max(t * t, 1e-4f);
}

// Bilinear interpolation in a table over (sqrt(mu), roughness) in [0, 1]^2 with kSize nodes each
// way; e(i, j) is the value at mu node i (table_mu) and roughness node j.
template <int kSize, class Value>
float bilinear_over_mu_and_roughness(float mu, float roughness, const Value& e) {
    float x = std::sqrt(clamp(mu, 0.0f, 1.0f)) * (kSize - 1), y = clamp(roughness, 0.0f, 1.0f) * (kSize - 1);
    int x0 = std::min(int(x), kSize - 2), y0 = std::min(int(y), kSize - 2);
    float fx = x - x0, fy = y - y0;
    return (1 - fy) * ((1 - fx) * e(x0, y0) + fx * e(x0 + 1, y0)) +
           fy * ((1 - fx) * e(x0, y0 + 1) + fx * e(x0 + 1, y0 + 1));
}

// Directional albedo E(mu, roughness, F0) of the dielectric specular lobe (Schlick), and its
// cosine-weighted average. The Lambert base is scaled by (1 - E(mu_o)) (1 - E(mu_i)) /
// (1 - E_avg) (Kelemen and Szirmay-Kalos 2001; Kulla and Conty 2017): reciprocal, and a white
// dielectric then reflects exactly what its specular lobe does not, so energy is conserved,
// where glTF's reference fresnel_mix reflects up to 1.2 at grazing angles. Schlick's Fresnel is
// linear in F0 (F0 + (1 - F0) w), so the table holds E[G1] and E[w G1] and any F0 (any IOR,
// KHR_materials_ior) is their mix: E = F0 E[G1] + (1 - F0) E[w G1].
class SpecularAlbedoTable {
  public:
    static constexpr int kSize = 64;  // fine in roughness too: near grazing E falls at mu ~ 2 alpha
    static const SpecularAlbedoTable& get() {
        static const SpecularAlbedoTable table;
        return table;
    }
    float albedo(float mu, float roughness, float f0) const {
        return bilinear_over_mu_and_roughness<kSize>(mu, roughness, [&](int i, int j) {
            const Moments& m = albedo_[j * kSize + i];
            return f0 * m.g + (1 - f0) * m.wg;
        });
    }
    float average(float roughness, float f0) const {
        float y = clamp(roughness, 0.0f, 1.0f) * (kSize - 1);
        int y0 = std::min(int(y), kSize - 2);
        float fy = y - y0;
        auto e = [&](int j) { return f0 * average_[j].g + (1 - f0) * average_[j].wg; };
        return (1 - fy) * e(y0) + fy * e(y0 + 1);
    }

  private:
    struct Moments {
        float g = 0, wg = 0;  // E[G1(wi)] and E[w G1(wi)] under the VNDF, w = (1 - wo.m)^5
    };
    SpecularAlbedoTable() {
        // Stratified visible-normal sampling: E = E[F(wo.m) G1(wi)] under the VNDF.
        const int strata = 24;
        for (int j = 0; j < kSize; ++j) {
            float roughness = float(j) / (kSize - 1);
            float alpha = std::max(roughness * roughness, kMinAlpha);
            double avg_g = 0, avg_wg = 0;
            for (int i = 0; i < kSize; ++i) {
                const float mu = table_mu<kSize>(i);
                Vec3 wo(safe_sqrt(1 - mu * mu), 0, mu);
                double sum_g = 0, sum_wg = 0;
                for (int a = 0; a < strata; ++a)
                    for (int b = 0; b < strata; ++b) {
                        Vec2 u((a + 0.5f) / strata, (b + 0.5f) / strata);
                        Vec3 wm = MetalRoughBsdf::sample_ggx_vndf(wo, alpha, u);
                        Vec3 wi = 2 * wo.dot(wm) * wm - wo;
                        if (wi.z() <= 0) continue;
                        const double g1 = MetalRoughBsdf::smith_g1(wi, alpha);
                        sum_g += g1, sum_wg += schlick_weight(wo.dot(wm)) * g1;
                    }
                albedo_[j * kSize + i] = {float(sum_g / (strata * strata)), float(sum_wg / (strata * strata))};
            }
            // E_avg = 2 * integral of E(mu) mu dmu (trapezoid over the table's mu nodes).
            for (int i = 0; i + 1 < kSize; ++i) {
                const float m0 = i == 0 ? 0.0f : table_mu<kSize>(i), m1 = table_mu<kSize>(i + 1);
                const Moments &e0 = albedo_[j * kSize + i], &e1 = albedo_[j * kSize + i + 1];
                avg_g += 0.5 * (e0.g * m0 + e1.g * m1) * (m1 - m0);
                avg_wg += 0.5 * (e0.wg * m0 + e1.wg * m1) * (m1 - m0);
            }
            average_[j] = {float(2 * avg_g), float(2 * avg_wg)};
        }
    }
    Moments albedo_[kSize * kSize];
    Moments average_[kSize];
};

// The sheen's Charlie distribution (Conty and Kulla 2017) with alpha = roughness (the extension's
// convention), and the visibility of the same paper through its fitted Lambda.
float charlie_d(float cos_h, float alpha) {
    const float inv = 1 / alpha, sin2 = std::max(0.0f, 1 - cos_h * cos_h);
    return (2 + inv) * std::pow(sin2, 0.5f * inv) / (2 * kPi);
}
float charlie_l(float x, float alpha) {
    const float t = (1 - alpha) * (1 - alpha);
    auto mix = [t](float a, float b) { return a + (b - a) * t; };
    const float a = mix(21.5473f, 25.3245f), b = mix(3.82987f, 3.32435f), c = mix(0.19823f, 0.16801f),
                d = mix(-1.97760f, -1.27393f), e = mix(-4.32054f, -4.85967f);
    return a / (1 + b * std::pow(x, c)) + d * x + e;
}
float charlie_lambda(float cos_theta, float alpha) {
    const float c = std::abs(cos_theta);
    return c < 0.5f ? std::exp(charlie_l(c, alpha)) : std::exp(2 * charlie_l(0.5f, alpha) - charlie_l(1 - c, alpha));
}
constexpr float kMinSheenRoughness = 0.07f;  // below, the lobe is a sliver at grazing

// Directional albedo of the sheen lobe (colour 1) over mu and roughness, by stratified quadrature
// of the hemisphere; bilinear lookup.
class SheenAlbedoTable {
  public:
    static constexpr int kSize = 32;
    static const SheenAlbedoTable& get() {
        static const SheenAlbedoTable table;
        return table;
    }
    float albedo(float mu, float roughness) const {
        return bilinear_over_mu_and_roughness<kSize>(mu, roughness,
                                                     [&](int i, int j) { return albedo_[j * kSize + i]; });
    }

  private:
    SheenAlbedoTable() {
        const int n = 64;  // n x 2n cells over (cos theta_i, phi)
        for (int j = 0; j < kSize; ++j) {
            const float roughness = float(j) / (kSize - 1);
            for (int i = 0; i < kSize; ++i) {
                const float mu = table_mu<kSize>(i);
                const Vec3 wo(safe_sqrt(1 - mu * mu), 0, mu);
                double sum = 0;
                for (int a = 0; a < n; ++a)
                    for (int b = 0; b < 2 * n; ++b) {
                        const float z = (a + 0.5f) / n, phi = kPi * (b + 0.5f) / n, r = safe_sqrt(1 - z * z);
                        const Vec3 wi(r * std::cos(phi), r * std::sin(phi), z);
                        sum += MetalRoughBsdf::sheen_lobe(wo, wi, roughness) * z;
                    }
                albedo_[j * kSize + i] = float(sum * 2 * kPiD / (double(n) * 2 * n));
            }
        }
    }
    float albedo_[kSize * kSize];
};

}  // namespace

float MetalRoughBsdf::sheen_lobe(const Vec3& wo, const Vec3& wi, float roughness) {
    if (wo.z() <= 0 || wi.z() <= 0) return 0;
    const float alpha = std::max(roughness, kMinSheenRoughness);
    const Vec3 wm = (wo + wi).normalized();
    const float v = 1 / ((1 + charlie_lambda(wo.z(), alpha) + charlie_lambda(wi.z(), alpha)) * 4 * wo.z() * wi.z());
    return charlie_d(wm.z(), alpha) * v;
}

float MetalRoughBsdf::sheen_distribution(float cos_h, float roughness) {
    return charlie_d(cos_h, std::max(roughness, kMinSheenRoughness));
}

float MetalRoughBsdf::sheen_albedo_table(float mu, float roughness) {
    return SheenAlbedoTable::get().albedo(mu, roughness);
}

MetalRoughBsdf::MetalRoughBsdf(const Color& base_color, float metallic, float roughness, float specular,
                               float transmission)
    : base_(base_color.max(0.0f).min(1.0f)),
      metallic_(clamp(metallic, 0.0f, 1.0f)),
      specular_(clamp(specular, 0.0f, 1.0f)),
      transmission_(clamp(transmission, 0.0f, 1.0f)) {
    roughness_ = clamp(roughness, 0.0f, 1.0f);
    alpha_ = std::max(roughness_ * roughness_, kMinAlpha);
    if (specular_ > 0) e_avg_ = specular_ * specular_average();
}

void MetalRoughBsdf::set_ior(float ior) {
    // glTF's 1.5 is the default; the extension allows 1 and above (0 for "ignore", read as 1.5).
    if (!(ior >= 1) || !std::isfinite(ior)) ior = 1.5f;
    const float r = (ior - 1) / (ior + 1);
    f0_ior_ = r * r;
    update_f0();
}

void MetalRoughBsdf::set_specular_color(const Color& colour) {
    specular_color_ = colour.max(0.0f);
    if (!specular_color_.allFinite()) specular_color_ = Color::Ones();
    coloured_ = (specular_color_ != 1.0f).any();
    update_f0();
}

void MetalRoughBsdf::update_f0() {
    // The albedo tables take one F0: the largest channel's. E grows with F0 at every angle, so that
    // channel's E is the largest at every angle, and the Lambert base weighted by it keeps every
    // channel within energy.
    f0_colour_ = (f0_ior_ * specular_color_).min(1.0f);
    f0_ = coloured_ ? f0_colour_.maxCoeff() : f0_ior_;
    if (specular_ > 0) e_avg_ = specular_ * specular_average();
    cached_wo_z_ = -1;  // set_wo again
}

Color MetalRoughBsdf::transmitted(const Vec3& wo) const {
    if (transmission_ <= 0 || metallic_ >= 1 || !(wo.z() > 0)) return Color::Zero();
    const float e_o = specular_ <= 0 ? 0.0f : cached_for(wo) ? cached_e_o_ : specular_albedo(wo);
    const float under_coat = coat_ > 0 ? 1 - (cached_for(wo) ? cached_e_coat_ : coat_albedo(wo.z())) : 1.0f;
    const float under_sheen = sheen_max_ > 0 ? sheen_scaling(wo.z()) : 1.0f;
    return base_ * tint_ * ((1 - metallic_) * transmission_ * (1 - e_o) * under_coat * under_sheen);
}

float MetalRoughBsdf::specular_albedo(const Vec3& w) const {
    return specular_ *
           SpecularAlbedoTable::get().albedo(w.z(), anisotropic_ ? projected_roughness(w) : roughness_, f0_);
}

namespace {

// An anisotropic lobe's albedo towards w is close to the isotropic one of the roughness w's azimuth
// meets (what its Smith masking takes: alpha^2 = cos^2 phi alpha_x^2 + sin^2 phi alpha_y^2, Heitz
// 2014). With the mean roughness a white dielectric seen at 88 degrees along the stretch reflected
// 1.22, across it 0.51. Straight down every azimuth is alike: `mean` (perceptual). Returns the
// tables' perceptual roughness (alpha = r^2).
float projected_perceptual_roughness(const Vec3& w, float alpha_x, float alpha_y, float mean) {
    const float xy2 = w.x() * w.x() + w.y() * w.y();
    if (!(xy2 > 1e-12f)) return mean;
    const float a2 = (w.x() * w.x() * alpha_x * alpha_x + w.y() * w.y() * alpha_y * alpha_y) / xy2;
    return std::sqrt(std::sqrt(a2));
}

// The cosine-weighted mean over the hemisphere of an anisotropic lobe's directional albedo (as
// projected_perceptual_roughness gives it), 2 int E mu dmu over the azimuths, for the perceptual
// roughnesses (sqrt alpha) along x and y on a 32 x 32 grid, bilinear between: computed per BSDF
// (512 table lookups) it made anisotropic materials render 7.5 x slower. Schlick's Fresnel is
// linear in F0, so the table holds the two moments as SpecularAlbedoTable does.
class AnisotropicAverageTable {
  public:
    static constexpr int kSize = 32;
    static const AnisotropicAverageTable& get() {
        static const AnisotropicAverageTable table;
        return table;
    }
    float average(float rx, float ry, float f0) const {
        const float x = clamp(rx, 0.0f, 1.0f) * (kSize - 1), y = clamp(ry, 0.0f, 1.0f) * (kSize - 1);
        const int x0 = std::min(int(x), kSize - 2), y0 = std::min(int(y), kSize - 2);
        const float fx = x - x0, fy = y - y0;
        auto e = [&](int i, int j) {
            const float* m = moments_[size_t(j) * kSize + i];
            return f0 * m[0] + (1 - f0) * m[1];
        };
        return (1 - fy) * ((1 - fx) * e(x0, y0) + fx * e(x0 + 1, y0)) +
               fy * ((1 - fx) * e(x0, y0 + 1) + fx * e(x0 + 1, y0 + 1));
    }

  private:
    AnisotropicAverageTable() {
        const SpecularAlbedoTable& table = SpecularAlbedoTable::get();
        const int nm = 32, np = 16;  // midpoints; a quarter turn by symmetry
        for (int j = 0; j < kSize; ++j)
            for (int i = 0; i < kSize; ++i) {
                const float rx = float(i) / (kSize - 1), ry = float(j) / (kSize - 1);
                const float ax = std::max(rx * rx, kMinAlpha), ay = std::max(ry * ry, kMinAlpha);
                const float mean = std::sqrt(std::sqrt(ax * ay));
                double g = 0, wg = 0;
                for (int a = 0; a < nm; ++a) {
                    const float mu = (a + 0.5f) / nm, r = safe_sqrt(1 - mu * mu);
                    for (int b = 0; b < np; ++b) {
                        const float phi = 0.5f * kPi * (b + 0.5f) / np;
                        const float rp = projected_perceptual_roughness(Vec3(r * std::cos(phi), r * std::sin(phi), mu),
                                                                        ax, ay, mean);
                        g += table.albedo(mu, rp, 1.0f) * mu;
                        wg += table.albedo(mu, rp, 0.0f) * mu;
                    }
                }
                float* m = moments_[size_t(j) * kSize + i];
                m[0] = float(2.0 * g / (double(nm) * np)), m[1] = float(2.0 * wg / (double(nm) * np));
            }
    }
    float moments_[kSize * kSize][2];
};

}  // namespace

float MetalRoughBsdf::projected_roughness(const Vec3& w) const {
    return projected_perceptual_roughness(w, alpha_x_, alpha_y_, roughness_);
}

float MetalRoughBsdf::specular_average() const {
    if (!anisotropic_) return SpecularAlbedoTable::get().average(roughness_, f0_);
    return AnisotropicAverageTable::get().average(std::sqrt(alpha_x_), std::sqrt(alpha_y_), f0_);
}

bool MetalRoughBsdf::cached_for(const Vec3& wo) const {
    return wo.z() == cached_wo_z_ && (!anisotropic_ || (wo.x() == cached_wo_x_ && wo.y() == cached_wo_y_));
}

void MetalRoughBsdf::set_wo(const Vec3& wo) {
    cached_wo_z_ = -1;
    if (!(wo.z() > 0)) return;
    cached_e_o_ = specular_albedo(wo);
    cached_ps_ = specular_probability_for(wo, cached_e_o_);
    if (coat_ > 0) {
        cached_e_coat_ = coat_albedo(wo.z());
        cached_pc_ = coat_probability_for(wo, cached_e_coat_);
    }
    cached_wo_z_ = wo.z(), cached_wo_x_ = wo.x(), cached_wo_y_ = wo.y();
}

float MetalRoughBsdf::ggx_d(const Vec3& wm, float alpha) {
    float c2 = wm.z() * wm.z();
    if (c2 <= 0) return 0;
    float a2 = alpha * alpha;
    float d = c2 * (a2 - 1) + 1;
    return a2 / (kPi * d * d);
}

float MetalRoughBsdf::smith_g1(const Vec3& w, float alpha) {
    float c2 = w.z() * w.z();
    if (c2 <= 0) return 0;
    float t2 = (1 - c2) / c2;  // tan^2(theta)
    return 2.0f / (1.0f + std::sqrt(1.0f + alpha * alpha * t2));
}

Vec3 MetalRoughBsdf::sample_ggx_vndf(const Vec3& wo, float alpha, const Vec2& u) {
    return sample_ggx_vndf(wo, alpha, alpha, u);  // the same arithmetic, bit for bit
}

float MetalRoughBsdf::ggx_d(const Vec3& wm, float alpha_x, float alpha_y) {
    if (wm.z() <= 0) return 0;
    const float x = wm.x() / alpha_x, y = wm.y() / alpha_y, d = x * x + y * y + wm.z() * wm.z();
    return 1 / (kPi * alpha_x * alpha_y * d * d);
}

float MetalRoughBsdf::smith_g1(const Vec3& w, float alpha_x, float alpha_y) {
    const float c2 = w.z() * w.z();
    if (c2 <= 0) return 0;
    const float a2t2 = (alpha_x * alpha_x * w.x() * w.x() + alpha_y * alpha_y * w.y() * w.y()) / c2;
    return 2.0f / (1.0f + std::sqrt(1.0f + a2t2));
}

Vec3 MetalRoughBsdf::sample_ggx_vndf(const Vec3& wo, float alpha_x, float alpha_y, const Vec2& u) {
    // Stretch the view vector to the hemisphere configuration, sample a projected disc, unstretch.
    Vec3 wh = Vec3(alpha_x * wo.x(), alpha_y * wo.y(), wo.z()).normalized();
    if (wh.z() < 0) wh = -wh;
    Vec3 t1 = wh.z() < 0.99999f ? Vec3::UnitZ().cross(wh).normalized() : Vec3::UnitX();
    Vec3 t2 = wh.cross(t1);
    float r = std::sqrt(u.x()), phi = 2 * kPi * u.y();
    float p1 = r * std::cos(phi), p2 = r * std::sin(phi);
    float s = 0.5f * (1 + wh.z());
    p2 = (1 - s) * safe_sqrt(1 - p1 * p1) + s * p2;
    Vec3 nh = p1 * t1 + p2 * t2 + safe_sqrt(1 - p1 * p1 - p2 * p2) * wh;
    return Vec3(alpha_x * nh.x(), alpha_y * nh.y(), std::max(1e-6f, nh.z())).normalized();
}

float MetalRoughBsdf::ggx_vndf_pdf_wi(const Vec3& wo, const Vec3& wi, float alpha_x, float alpha_y) {
    Vec3 wm = wo + wi;
    if (wm.squaredNorm() == 0 || wo.z() <= 0) return 0;
    wm.normalize();
    if (wm.z() < 0) wm = -wm;
    if (wo.dot(wm) <= 0) return 0;
    return smith_g1(wo, alpha_x, alpha_y) * ggx_d(wm, alpha_x, alpha_y) / (4 * wo.z());
}

void MetalRoughBsdf::set_anisotropy(float strength) {
    strength = clamp(strength, 0.0f, 1.0f);
    if (!(strength > 0)) return;
    anisotropic_ = true;
    alpha_x_ = alpha_ + (1 - alpha_) * strength * strength, alpha_y_ = alpha_;
    // The tables' perceptual roughness for the mean alpha.
    roughness_ = std::sqrt(std::sqrt(alpha_x_ * alpha_y_));
    update_f0();
}

float MetalRoughBsdf::specular_dgg(const Vec3& wm, const Vec3& wo, const Vec3& wi) const {
    if (anisotropic_)
        return ggx_d(wm, alpha_x_, alpha_y_) * smith_g1(wo, alpha_x_, alpha_y_) * smith_g1(wi, alpha_x_, alpha_y_);
    return ggx_d(wm, alpha_) * smith_g1(wo, alpha_) * smith_g1(wi, alpha_);
}

float MetalRoughBsdf::specular_vndf_pdf(const Vec3& wo, const Vec3& wi) const {
    return anisotropic_ ? ggx_vndf_pdf_wi(wo, wi, alpha_x_, alpha_y_) : ggx_vndf_pdf_wi(wo, wi, alpha_);
}

float MetalRoughBsdf::ggx_vndf_pdf_wi(const Vec3& wo, const Vec3& wi, float alpha) {
    Vec3 wm = wo + wi;
    if (wm.squaredNorm() == 0 || wo.z() <= 0) return 0;
    wm.normalize();
    if (wm.z() < 0) wm = -wm;
    float wo_dot_m = wo.dot(wm);
    if (wo_dot_m <= 0) return 0;
    // D_v(wm) = G1(wo) max(0, wo.wm) D(wm) / cos(theta_o); pdf(wi) = D_v / (4 wo.wm).
    return smith_g1(wo, alpha) * ggx_d(wm, alpha) / (4 * wo.z());
}


Color MetalRoughBsdf::metal_rough_eval(const Vec3& wo, const Vec3& wi) const {
    if (wo.z() <= 0 || wi.z() <= 0) return Color::Zero();
    Vec3 wm = (wo + wi).normalized();
    float v_dot_h = clamp(wo.dot(wm), 0.0f, 1.0f);
    float w = schlick_weight(v_dot_h);
    // Specular microfacet term without Fresnel: D G / (4 cos_o cos_i), separable Smith G.
    float spec = specular_dgg(wm, wo, wi) / (4 * wo.z() * wi.z());
    // Dielectric: fresnel_mix(ior 1.5) of Lambert base and specular; metal: conductor Fresnel.
    float f_dielectric = specular_ * (f0_ + (1 - f0_) * w);
    float diffuse_weight = 1.0f;
    if (specular_ > 0) {
        float e_o = cached_for(wo) ? cached_e_o_ : specular_albedo(wo);
        diffuse_weight = (1 - e_o) * (1 - specular_albedo(wi)) / std::max(1 - e_avg_, 1e-4f);
    }
    diffuse_weight *= 1 - transmission_;  // the rest passes through (transmitted())
    Color dielectric = diffuse_weight * base_ * kInvPi;
    if (coloured_) dielectric += specular_ * (f0_colour_ + (1 - f0_colour_) * w) * spec;
    else dielectric += Color::Constant(f_dielectric * spec);
    Color metal = (base_ + (1 - base_) * w) * spec;
    return (1 - metallic_) * dielectric + metallic_ * metal;
}

float MetalRoughBsdf::specular_probability(const Vec3& wo) const {
    if (cached_for(wo)) return cached_ps_;
    return specular_probability_for(wo, metallic_ >= 1 ? 0.0f : specular_albedo(wo));
}

float MetalRoughBsdf::specular_probability_for(const Vec3& wo, float e_spec) const {
    if (metallic_ >= 1) return 1.0f;
    float w = schlick_weight(std::max(0.0f, wo.z()));
    float spec = (1 - metallic_) * e_spec + metallic_ * luminance(base_ + (1 - base_) * w);
    float diff = (1 - metallic_) * (1 - e_spec) * (1 - transmission_) * luminance(base_);
    if (spec <= 0) return 0.0f;  // pure Lambertian
    float p = spec / std::max(spec + diff, 1e-6f);
    return clamp(p, 0.1f, 0.9f);  // both lobes stay reachable
}

float MetalRoughBsdf::metal_rough_pdf(const Vec3& wo, const Vec3& wi) const {
    if (wo.z() <= 0 || wi.z() <= 0) return 0;
    float ps = specular_probability(wo);
    return ps * specular_vndf_pdf(wo, wi) + (1 - ps) * wi.z() * kInvPi;
}

void MetalRoughBsdf::set_sheen(const Color& colour, float roughness) {
    sheen_ = colour.max(0.0f).min(1.0f);
    sheen_max_ = sheen_.maxCoeff();
    if (!(sheen_max_ > 0)) {
        sheen_ = Color::Zero(), sheen_max_ = 0;
        return;
    }
    sheen_roughness_ = clamp(roughness, kMinSheenRoughness, 1.0f);
    cached_wo_z_ = -1;  // set_wo again
}

float MetalRoughBsdf::sheen_scaling(float mu) const {
    return 1 - sheen_max_ * SheenAlbedoTable::get().albedo(mu, sheen_roughness_);
}

float MetalRoughBsdf::base_albedo_estimate(const Vec3& wo) const {
    const float e_spec = metallic_ >= 1 ? 0.0f : specular_albedo(wo);
    const float w = schlick_weight(std::max(0.0f, wo.z()));
    return (1 - metallic_) * (e_spec + (1 - e_spec) * (1 - transmission_) * luminance(base_)) +
           metallic_ * luminance(base_ + (1 - base_) * w);
}

float MetalRoughBsdf::sheen_probability(const Vec3& wo) const {
    // The sheen's albedo against what the base under it returns. Its samples are uniform over the
    // hemisphere: the fibres shine at grazing angles, where cosine sampling is thin.
    const float scaling = sheen_scaling(wo.z()), e = 1 - scaling;
    const float p = e / std::max(e + scaling * base_albedo_estimate(wo), 1e-6f);
    return clamp(p, 0.05f, 0.5f);
}

Color MetalRoughBsdf::base_eval(const Vec3& wo, const Vec3& wi) const {
    if (sheen_max_ <= 0) return metal_rough_eval(wo, wi);
    if (wo.z() <= 0 || wi.z() <= 0) return Color::Zero();
    const float scaling = std::min(sheen_scaling(wo.z()), sheen_scaling(wi.z()));
    return sheen_ * sheen_lobe(wo, wi, sheen_roughness_) + metal_rough_eval(wo, wi) * scaling;
}

float MetalRoughBsdf::base_pdf(const Vec3& wo, const Vec3& wi) const {
    if (sheen_max_ <= 0) return metal_rough_pdf(wo, wi);
    if (wo.z() <= 0 || wi.z() <= 0) return 0;
    const float p = sheen_probability(wo);
    return p * (0.5f * kInvPi) + (1 - p) * metal_rough_pdf(wo, wi);
}

bool MetalRoughBsdf::sample(const Vec3& wo, float u_lobe, const Vec2& u, BsdfSample* out) const {
    if (wo.z() <= 0) return false;
    Vec3 wi;
    const float pc = coat_ > 0 ? coat_probability(wo) : 0.0f;
    if (u_lobe < pc) {  // the clearcoat's lobe
        Vec3 wm = sample_ggx_vndf(wo, coat_alpha_, u);
        wi = 2 * wo.dot(wm) * wm - wo;
    } else {
        if (pc > 0) u_lobe = std::min((u_lobe - pc) / (1 - pc), 0.99999994f);
        const float psh = sheen_max_ > 0 ? sheen_probability(wo) : 0.0f;
        if (u_lobe < psh) {  // the sheen's
            wi = sample_uniform_hemisphere(u);
        } else {
            if (psh > 0) u_lobe = std::min((u_lobe - psh) / (1 - psh), 0.99999994f);
            float ps = specular_probability(wo);
            if (u_lobe < ps) {
                Vec3 wm = anisotropic_ ? sample_ggx_vndf(wo, alpha_x_, alpha_y_, u) : sample_ggx_vndf(wo, alpha_, u);
                wi = 2 * wo.dot(wm) * wm - wo;
            } else {
                wi = sample_cosine_hemisphere(u);
            }
        }
    }
    if (wi.z() <= 0) return false;
    out->wi = wi;
    out->pdf = pdf(wo, wi);
    out->f = eval(wo, wi);
    return out->pdf > 0;
}

void MetalRoughBsdf::set_clearcoat(float factor, float roughness) {
    coat_ = clamp(factor, 0.0f, 1.0f);
    if (!(coat_ > 0)) {
        coat_ = 0;
        return;
    }
    coat_roughness_ = clamp(roughness, 0.0f, 1.0f);
    coat_alpha_ = std::max(coat_roughness_ * coat_roughness_, kMinAlpha);
    cached_wo_z_ = -1;  // set_wo again
}

float MetalRoughBsdf::coat_albedo(float mu) const {
    return coat_ * SpecularAlbedoTable::get().albedo(mu, coat_roughness_, kCoatF0);
}

float MetalRoughBsdf::coat_probability(const Vec3& wo) const {
    if (cached_for(wo)) return cached_pc_;
    return coat_probability_for(wo, coat_albedo(wo.z()));
}

float MetalRoughBsdf::coat_probability_for(const Vec3& wo, float e_coat) const {
    // The base's albedo towards wo, roughly, under what the coat lets through.
    const float base = base_albedo_estimate(wo);
    const float p = e_coat / std::max(e_coat + (1 - e_coat) * base, 1e-6f);
    return clamp(p, 0.05f, 0.95f);
}

Color MetalRoughBsdf::eval(const Vec3& wo, const Vec3& wi) const {
    if (coat_ <= 0) return base_eval(wo, wi);
    if (wo.z() <= 0 || wi.z() <= 0) return Color::Zero();
    // The base under the coat receives and returns what the coat's lobe does not reflect (its
    // albedo E_c each way): energy never grows, and the layer stays reciprocal.
    const float e_o = cached_for(wo) ? cached_e_coat_ : coat_albedo(wo.z());
    const Color base = base_eval(wo, wi) * ((1 - e_o) * (1 - coat_albedo(wi.z())));
    const Vec3 wm = (wo + wi).normalized();
    const float f = kCoatF0 + (1 - kCoatF0) * schlick_weight(clamp(wo.dot(wm), 0.0f, 1.0f));
    const float coat = coat_ * f * ggx_d(wm, coat_alpha_) * smith_g1(wo, coat_alpha_) * smith_g1(wi, coat_alpha_) /
                       (4 * wo.z() * wi.z());
    return base + Color::Constant(coat);
}

float MetalRoughBsdf::pdf(const Vec3& wo, const Vec3& wi) const {
    if (coat_ <= 0) return base_pdf(wo, wi);
    if (wo.z() <= 0 || wi.z() <= 0) return 0;
    const float pc = coat_probability(wo);
    return pc * ggx_vndf_pdf_wi(wo, wi, coat_alpha_) + (1 - pc) * base_pdf(wo, wi);
}

}  // namespace dynsky
