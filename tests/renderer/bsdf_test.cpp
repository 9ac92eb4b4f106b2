#include "renderer/bsdf.h"

#include <gtest/gtest.h>

#include <array>
#include <string>

#include "renderer/sampling.h"

namespace dynsky {
namespace {

Vec3 dir_from_theta(float theta) { return Vec3(std::sin(theta), 0, std::cos(theta)); }

// Directional albedo by midpoint quadrature over (cos theta, phi): no sampling involved.
Color albedo_quadrature(const MetalRoughBsdf& bsdf, const Vec3& wo, int n = 400) {
    Eigen::Array3d sum = Eigen::Array3d::Zero();
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < 2 * n; ++b) {
            float z = (a + 0.5f) / n, phi = 2 * kPi * (b + 0.5f) / (2 * n), r = safe_sqrt(1 - z * z);
            Vec3 wi(r * std::cos(phi), r * std::sin(phi), z);
            sum += (bsdf.eval(wo, wi) * z).cast<double>();
        }
    return (sum * (2 * kPiD / (double(n) * 2 * n))).cast<float>();
}

double pdf_integral(const MetalRoughBsdf& bsdf, const Vec3& wo, int n = 400) {
    double sum = 0;
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < 2 * n; ++b) {
            float z = (a + 0.5f) / n, phi = 2 * kPi * (b + 0.5f) / (2 * n), r = safe_sqrt(1 - z * z);
            sum += bsdf.pdf(wo, Vec3(r * std::cos(phi), r * std::sin(phi), z));
        }
    return sum * 2 * kPiD / (double(n) * 2 * n);
}

// E[f cos / pdf] over sampled directions equals the quadrature albedo iff the sampler draws from
// the pdf it reports.
void expect_sampled_estimate_matches_quadrature(const MetalRoughBsdf& bsdf, const Vec3& wo, Rng* rng,
                                                const std::string& what) {
    const Color exact = albedo_quadrature(bsdf, wo, 1000);
    const int n = 400000;
    Eigen::Array3d sum = Eigen::Array3d::Zero(), sum2 = Eigen::Array3d::Zero();
    for (int k = 0; k < n; ++k) {
        BsdfSample s;
        float ul = rng->uniform();
        Vec2 u = rng->uniform2();
        if (!bsdf.sample(wo, ul, u, &s)) continue;
        EXPECT_NEAR(s.pdf, bsdf.pdf(wo, s.wi), 1e-3f * s.pdf) << what;
        Eigen::Array3d v = (s.f * (s.wi.z() / s.pdf)).cast<double>();
        sum += v, sum2 += v * v;
    }
    Eigen::Array3d mean = sum / n, se = ((sum2 / n - mean * mean) / n).sqrt();
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean[c], exact[c], 4 * se[c] + 2e-3) << what;
}

TEST(MetalRoughBsdf, WhiteLambertianHasAlbedoOne) {
    MetalRoughBsdf bsdf(Color::Ones(), 0.0f, 1.0f, 0.0f);
    for (float theta : {0.0f, 0.7f, 1.3f}) {
        Color a = albedo_quadrature(bsdf, dir_from_theta(theta));
        EXPECT_NEAR(a[0], 1.0f, 2e-3f);
    }
}

TEST(MetalRoughBsdf, NeverReflectsMoreThanItReceives) {
    for (float metallic : {0.0f, 0.5f, 1.0f})
        for (float roughness : {0.3f, 0.5f, 0.7f, 1.0f})
            for (float theta : {0.0f, 0.8f, 1.2f, 1.4f}) {
                MetalRoughBsdf bsdf(Color::Ones(), metallic, roughness);
                Color a = albedo_quadrature(bsdf, dir_from_theta(theta), 500);
                EXPECT_LE(a.maxCoeff(), 1.0f + 5e-3f)
                    << "metallic " << metallic << " roughness " << roughness << " theta " << theta;
                EXPECT_GT(a.minCoeff(), 0.3f);
                // A white dielectric reflects everything: what the specular lobe does not, the base does.
                if (metallic == 0) {
                    EXPECT_NEAR(a[0], 1.0f, 1e-2f) << "roughness " << roughness << " theta " << theta;
                }
            }
}

// At near-grazing views a smooth lobe's albedo falls steeply (within mu < 2 alpha); the albedo
// tables the base is weighted by must follow it. Their first cell spanned mu < 1/31 and a white
// smooth dielectric, or a sheen over white, reflected up to 9 % more than it received past 88
// degrees (a white furnace: 1.089 at 89.6 degrees; material audit). Sampled estimate, as the
// quadrature cannot resolve a mirror lobe.
// The red channel's albedo towards wo by importance sampling (n samples), and its standard error.
double sampled_albedo(const MetalRoughBsdf& bsdf, const Vec3& wo, Rng* rng, int n, double* standard_error) {
    double sum = 0, sum2 = 0;
    for (int k = 0; k < n; ++k) {
        BsdfSample s;
        const float ul = rng->uniform();
        const Vec2 u = rng->uniform2();
        if (!bsdf.sample(wo, ul, u, &s)) continue;
        const double v = s.f[0] * s.wi.z() / s.pdf;
        sum += v, sum2 += v * v;
    }
    const double mean = sum / n;
    *standard_error = std::sqrt((sum2 / n - mean * mean) / n);
    return mean;
}

TEST(MetalRoughBsdf, NothingWhiteGainsEnergyAtGrazingViews) {
    Rng rng(7, 2);
    for (const float deg : {88.5f, 89.0f, 89.3f, 89.6f, 89.8f})
        for (int kind = 0; kind < 3; ++kind) {
            MetalRoughBsdf bsdf(Color::Ones(), kind == 2 ? 1.0f : 0.0f, kind == 1 ? 0.05f : 0.0f);
            if (kind == 2) bsdf.set_sheen(Color::Ones(), 0.5f);
            double se = 0;
            const double mean = sampled_albedo(bsdf, dir_from_theta(deg * kPi / 180), &rng, 200000, &se);
            const char* what[] = {"smooth dielectric", "dielectric roughness 0.05", "smooth metal + sheen"};
            EXPECT_LE(mean, 1.0 + 4 * se + 2e-3) << what[kind] << " at " << deg << " degrees";
        }
}

// Thin-walled transmission takes its share from the diffuse base alone: a white glass reflects what
// its specular lobe does and passes the rest (reflected + transmitted = 1), a tinted one passes the
// base colour's share of it, and a glass of transmission t keeps (1 - t) of the base's diffuse light.
TEST(MetalRoughBsdf, TransmissionPassesWhatTheSpecularLobeDoesNotReflect) {
    for (float roughness : {0.3f, 0.6f, 1.0f})
        for (float theta : {0.0f, 0.8f, 1.3f}) {
            const Vec3 wo = dir_from_theta(theta);
            MetalRoughBsdf glass(Color::Ones(), 0.0f, roughness, 1.0f, 1.0f);
            const Color reflected = albedo_quadrature(glass, wo, 500), through = glass.transmitted(wo);
            EXPECT_NEAR(reflected[0] + through[0], 1.0f, 1e-2f) << "roughness " << roughness << " theta " << theta;
            EXPECT_GT(through[0], 0.3f);
            // Tinted: the base colour tints what passes, not what the specular lobe reflects.
            MetalRoughBsdf tinted(Color(1.0f, 0.5f, 0.25f), 0.0f, roughness, 1.0f, 1.0f);
            const Color t = tinted.transmitted(wo);
            EXPECT_NEAR(t[1], 0.5f * through[0], 1e-5f);
            EXPECT_NEAR(t[2], 0.25f * through[0], 1e-5f);
            EXPECT_NEAR(albedo_quadrature(tinted, wo, 500)[2], reflected[0], 1e-3f);
            // Half transmission: half of the base's diffuse light stays, half passes.
            MetalRoughBsdf half(Color::Ones(), 0.0f, roughness, 1.0f, 0.5f), none(Color::Ones(), 0.0f, roughness);
            const float diffuse = albedo_quadrature(none, wo, 500)[0] - reflected[0];
            EXPECT_NEAR(albedo_quadrature(half, wo, 500)[0], reflected[0] + 0.5f * diffuse, 2e-3f);
            EXPECT_NEAR(half.transmitted(wo)[0], 0.5f * through[0], 1e-5f);
        }
    // KHR_materials_volume's absorption tints what passes, and only that.
    {
        const Vec3 wo = dir_from_theta(0.3f);
        MetalRoughBsdf clear(Color::Ones(), 0.0f, 0.4f, 1.0f, 1.0f), bottle(Color::Ones(), 0.0f, 0.4f, 1.0f, 1.0f);
        bottle.set_transmission_tint(Color(0.25f, 1.0f, 0.0625f));
        EXPECT_TRUE(bottle.transmitted(wo).isApprox(clear.transmitted(wo) * Color(0.25f, 1.0f, 0.0625f), 1e-6f));
        EXPECT_TRUE(bottle.eval(wo, dir_from_theta(-0.5f)).isApprox(clear.eval(wo, dir_from_theta(-0.5f)), 1e-6f));
    }
    // Metals and opaque dielectrics pass nothing; a half-metal passes its dielectric half's share.
    const Vec3 wo = dir_from_theta(0.5f);
    EXPECT_EQ(MetalRoughBsdf(Color::Ones(), 1.0f, 0.2f, 1.0f, 1.0f).transmitted(wo).maxCoeff(), 0.0f);
    EXPECT_EQ(MetalRoughBsdf(Color::Ones(), 0.0f, 0.2f).transmitted(wo).maxCoeff(), 0.0f);
    EXPECT_NEAR(MetalRoughBsdf(Color::Ones(), 0.5f, 0.2f, 1.0f, 1.0f).transmitted(wo)[0],
                0.5f * MetalRoughBsdf(Color::Ones(), 0.0f, 0.2f, 1.0f, 1.0f).transmitted(wo)[0], 1e-6f);
}

// KHR_materials_ior: a smooth dielectric reflects F0 = ((n - 1) / (n + 1))^2 at normal incidence
// (water 1.33: 0.020, diamond 2.42: 0.172, glTF's 1.5: 0.04), a white one still reflects everything
// (what the specular lobe does not, the base does), glass passes the rest, and sampling draws the
// pdf it reports. IOR 1.5 is the default, bit for bit.
TEST(MetalRoughBsdf, IorSetsTheDielectricsReflectanceAndKeepsEnergy) {
    const Vec3 normal(0, 0, 1);
    for (float ior : {1.0f, 1.33f, 1.5f, 2.42f}) {
        const double f0 = std::pow((ior - 1.0) / (ior + 1.0), 2);
        MetalRoughBsdf smooth_glass(Color::Ones(), 0.0f, 0.0f, 1.0f, 1.0f);
        smooth_glass.set_ior(ior);
        EXPECT_NEAR(1 - smooth_glass.transmitted(normal)[0], f0, 2e-3) << "ior " << ior;
        for (float roughness : {0.3f, 0.7f})
            for (float theta : {0.0f, 0.8f, 1.3f}) {
                const Vec3 wo = dir_from_theta(theta);
                MetalRoughBsdf white(Color::Ones(), 0.0f, roughness);
                white.set_ior(ior);
                EXPECT_NEAR(albedo_quadrature(white, wo, 500)[0], 1.0f, 1e-2f)
                    << "ior " << ior << " roughness " << roughness << " theta " << theta;
                MetalRoughBsdf glass(Color::Ones(), 0.0f, roughness, 1.0f, 1.0f);
                glass.set_ior(ior);
                EXPECT_NEAR(albedo_quadrature(glass, wo, 500)[0] + glass.transmitted(wo)[0], 1.0f, 1e-2f)
                    << "ior " << ior << " roughness " << roughness << " theta " << theta;
            }
    }
    // More IOR, more specular: a black dielectric reflects only its specular lobe.
    const Vec3 wo = dir_from_theta(0.6f);
    MetalRoughBsdf water(Color::Zero(), 0.0f, 0.4f), diamond(Color::Zero(), 0.0f, 0.4f);
    water.set_ior(1.33f), diamond.set_ior(2.42f);
    EXPECT_LT(albedo_quadrature(water, wo)[0], albedo_quadrature(MetalRoughBsdf(Color::Zero(), 0.0f, 0.4f), wo)[0]);
    EXPECT_GT(albedo_quadrature(diamond, wo)[0], 3 * albedo_quadrature(water, wo)[0]);
    Rng rng(7, 1);
    expect_sampled_estimate_matches_quadrature(diamond, wo, &rng, "diamond");
    // 1.5, set or not, is the same BSDF.
    MetalRoughBsdf plain(Color(0.8f, 0.5f, 0.2f), 0.0f, 0.5f), set(Color(0.8f, 0.5f, 0.2f), 0.0f, 0.5f);
    set.set_ior(1.5f);
    const Vec3 wi = dir_from_theta(-0.4f);
    EXPECT_NEAR(plain.eval(wo, wi)[0], set.eval(wo, wi)[0], 1e-6f * plain.eval(wo, wi)[0]);
}

// KHR_materials_clearcoat: over a black Lambertian the coat alone reflects what a bare dielectric of
// its roughness reflects with its specular lobe (the same F0 0.04 GGX); over any base the layer never
// reflects more than it receives, a full coat over white at least its own albedo; sampling draws the
// pdf it reports and the layered BSDF stays reciprocal. A coat of 0 changes nothing, bit for bit.
TEST(MetalRoughBsdf, ClearcoatLayersEnergySafelyOverTheBase) {
    for (float coat_roughness : {0.1f, 0.4f})
        for (float theta : {0.0f, 0.8f, 1.3f}) {
            const Vec3 wo = dir_from_theta(theta);
            MetalRoughBsdf coated_black(Color::Zero(), 0.0f, 1.0f, 0.0f);
            coated_black.set_clearcoat(1.0f, coat_roughness);
            const MetalRoughBsdf bare(Color::Zero(), 0.0f, coat_roughness);
            const float coat = albedo_quadrature(coated_black, wo, 800)[0];
            EXPECT_NEAR(coat, albedo_quadrature(bare, wo, 800)[0], 2e-3f) << coat_roughness << " " << theta;
            for (float metallic : {0.0f, 1.0f}) {
                MetalRoughBsdf white(Color::Ones(), metallic, 0.6f);
                white.set_clearcoat(1.0f, coat_roughness);
                const Color a = albedo_quadrature(white, wo, 800);
                EXPECT_LE(a.maxCoeff(), 1.0f + 5e-3f);
                EXPECT_GE(a.minCoeff(), coat);
            }
        }
    MetalRoughBsdf layered(Color(0.8f, 0.3f, 0.1f), 0.2f, 0.7f);
    layered.set_clearcoat(0.8f, 0.15f);
    Rng rng(5, 9);
    for (int k = 0; k < 1000; ++k) {
        Vec3 a = sample_cosine_hemisphere(rng.uniform2()), b = sample_cosine_hemisphere(rng.uniform2());
        Color f1 = layered.eval(a, b), f2 = layered.eval(b, a);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(f1[c], f2[c], 1e-4f * std::max(1.0f, f1[c]));
    }
    const Vec3 wo = dir_from_theta(0.7f);
    EXPECT_LE(pdf_integral(layered, wo), 1.0 + 5e-3);
    expect_sampled_estimate_matches_quadrature(layered, wo, &rng, "clearcoat");
    MetalRoughBsdf none(Color(0.8f, 0.3f, 0.1f), 0.2f, 0.7f), zero(Color(0.8f, 0.3f, 0.1f), 0.2f, 0.7f);
    zero.set_clearcoat(0.0f, 0.5f);
    EXPECT_TRUE(none.eval(wo, dir_from_theta(-0.3f)).isApprox(zero.eval(wo, dir_from_theta(-0.3f)), 0.0f));
}

// KHR_materials_sheen: the Charlie distribution is normalised (integral of D cos over the
// hemisphere is 1); the sheen alone reflects its tabulated albedo, never more than it receives;
// over a white base the layered sum stays within energy; reciprocal; sampled as its pdf says (also
// over a metal, as SheenChair's fabric is); a black sheen changes nothing.
TEST(MetalRoughBsdf, SheenLayersEnergySafelyOverTheBase) {
    for (float r : {0.1f, 0.5f, 1.0f}) {
        double d = 0;
        const int n = 4000;
        for (int a = 0; a < n; ++a) {
            const double z = (a + 0.5) / n;  // cos theta_h, d omega = 2 pi dz
            d += MetalRoughBsdf::sheen_distribution(float(z), r) * z * 2 * kPiD / n;
        }
        EXPECT_NEAR(d, 1.0, 2e-3) << r;
    }
    for (float r : {0.2f, 0.6f})
        for (float theta : {0.0f, 0.9f, 1.4f}) {
            const Vec3 wo = dir_from_theta(theta);
            MetalRoughBsdf sheen_only(Color::Zero(), 0.0f, 1.0f, 0.0f);
            sheen_only.set_sheen(Color(1.0f, 0.5f, 0.25f), r);
            const Color a = albedo_quadrature(sheen_only, wo, 800);
            const float table = MetalRoughBsdf::sheen_albedo_table(wo.z(), r);
            EXPECT_GT(table, 0.01f) << r << " " << theta;
            EXPECT_LE(table, 1.0f);
            EXPECT_NEAR(a[0], table, 0.02f * table + 2e-3f) << r << " " << theta;
            EXPECT_NEAR(a[1], 0.5f * a[0], 1e-4f);
            MetalRoughBsdf white(Color::Ones(), 0.0f, 0.8f, 0.0f);  // a white Lambertian under it
            white.set_sheen(Color::Ones(), r);
            const Color w = albedo_quadrature(white, wo, 800);
            EXPECT_LE(w.maxCoeff(), 1.0f + 5e-3f) << r << " " << theta;
            EXPECT_GE(w.minCoeff(), table) << r << " " << theta;
        }
    Rng rng(7, 3);
    for (float metallic : {0.0f, 1.0f}) {
        MetalRoughBsdf fabric(Color(0.6f, 0.2f, 0.3f), metallic, 0.7f);
        fabric.set_sheen(Color(0.9f, 0.8f, 1.0f), 0.3f);
        for (int k = 0; k < 1000; ++k) {
            Vec3 a = sample_cosine_hemisphere(rng.uniform2()), b = sample_cosine_hemisphere(rng.uniform2());
            Color f1 = fabric.eval(a, b), f2 = fabric.eval(b, a);
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(f1[c], f2[c], 1e-4f * std::max(1.0f, f1[c]));
        }
        for (float theta : {0.3f, 1.3f}) {
            const Vec3 wo = dir_from_theta(theta);
            fabric.set_wo(wo);
            EXPECT_LE(pdf_integral(fabric, wo), 1.0 + 5e-3);
            expect_sampled_estimate_matches_quadrature(fabric, wo, &rng, "sheen");
        }
    }
    MetalRoughBsdf none(Color(0.8f, 0.3f, 0.1f), 0.2f, 0.7f), black(Color(0.8f, 0.3f, 0.1f), 0.2f, 0.7f);
    black.set_sheen(Color::Zero(), 0.5f);
    const Vec3 wo = dir_from_theta(0.7f), wi = dir_from_theta(-0.3f);
    EXPECT_TRUE(none.eval(wo, wi).isApprox(black.eval(wo, wi), 0.0f));
    EXPECT_EQ(none.pdf(wo, wi), black.pdf(wo, wi));
}

// KHR_materials_specular's colour: each channel's specular lobe is the uncoloured one of F0 x
// colour (black base: only the lobe reflects); over a white base the largest channel reflects
// exactly what it receives and none more; F0 above 1 is capped; white changes nothing.
TEST(MetalRoughBsdf, SpecularColourTintsTheDielectricsFresnelAndKeepsEnergy) {
    auto ior_for = [](float f0) { return (1 + std::sqrt(f0)) / (1 - std::sqrt(f0)); };
    for (float roughness : {0.3f, 0.7f})
        for (float theta : {0.2f, 1.2f}) {
            const Vec3 wo = dir_from_theta(theta);
            MetalRoughBsdf tinted(Color::Zero(), 0.0f, roughness);
            tinted.set_specular_color(Color(1.0f, 0.5f, 4.0f));  // F0 0.04, 0.02, 0.16
            const Color a = albedo_quadrature(tinted, wo, 600);
            for (int c = 0; c < 3; ++c) {
                MetalRoughBsdf plain(Color::Zero(), 0.0f, roughness);
                plain.set_ior(ior_for(0.04f * std::array<float, 3>{1.0f, 0.5f, 4.0f}[size_t(c)]));
                EXPECT_NEAR(a[c], albedo_quadrature(plain, wo, 600)[c], 1e-3f) << c << " " << theta;
            }
            MetalRoughBsdf white(Color::Ones(), 0.0f, roughness);
            white.set_specular_color(Color(0.2f, 1.0f, 3.0f));
            const Color w = albedo_quadrature(white, wo, 600);
            EXPECT_NEAR(w[2], 1.0f, 5e-3f) << theta;  // the largest F0's channel: exactly 1
            EXPECT_LE(w.maxCoeff(), 1.0f + 5e-3f);
            EXPECT_GT(w.minCoeff(), 0.8f);
            MetalRoughBsdf capped(Color::Ones(), 0.0f, roughness);
            capped.set_specular_color(Color::Constant(1e6f));  // F0 1: a perfect (rough) mirror lobe
            const Color m = albedo_quadrature(capped, wo, 600);
            EXPECT_TRUE(m.allFinite());
            EXPECT_LE(m.maxCoeff(), 1.0f + 5e-3f);
        }
    Rng rng(11, 2);
    MetalRoughBsdf tinted(Color(0.5f, 0.4f, 0.3f), 0.0f, 0.4f);
    tinted.set_specular_color(Color(1.5f, 0.2f, 1.0f));
    const Vec3 wo = dir_from_theta(0.9f);
    tinted.set_wo(wo);
    expect_sampled_estimate_matches_quadrature(tinted, wo, &rng, "specular colour");
    MetalRoughBsdf none(Color(0.8f, 0.3f, 0.1f), 0.2f, 0.7f), white(Color(0.8f, 0.3f, 0.1f), 0.2f, 0.7f);
    white.set_specular_color(Color::Ones());
    const Vec3 wi = dir_from_theta(-0.3f);
    EXPECT_TRUE(none.eval(wo, wi).isApprox(white.eval(wo, wi), 0.0f));
    EXPECT_EQ(none.pdf(wo, wi), white.pdf(wo, wi));
}

// KHR_materials_anisotropy: the anisotropic GGX distribution is normalised (the integral of D cos
// over the hemisphere is 1), the lobe spreads further along local x (the anisotropy direction) than
// along y, energy stays within 1 for a white metal and a white dielectric, the BSDF is reciprocal,
// sampled as its pdf says (also for a wo off the anisotropy's axes), and strength 0 changes nothing.
TEST(MetalRoughBsdf, AnisotropyStretchesTheLobeAndKeepsEnergy) {
    for (auto [ax, ay] : {std::pair<float, float>{0.5f, 0.1f}, {0.15f, 0.6f}, {0.3f, 0.3f}}) {
        const int n = 1200;
        double sum = 0;
        for (int a = 0; a < n; ++a)
            for (int b = 0; b < 2 * n; ++b) {
                const float z = (a + 0.5f) / n, phi = 2 * kPi * (b + 0.5f) / (2 * n), r = safe_sqrt(1 - z * z);
                sum += MetalRoughBsdf::ggx_d(Vec3(r * std::cos(phi), r * std::sin(phi), z), ax, ay) * z;
            }
        EXPECT_NEAR(sum * 2 * kPiD / (double(n) * 2 * n), 1.0, 5e-3) << ax << " " << ay;
    }
    // Isotropic alphas give the isotropic functions.
    const Vec3 w = Vec3(0.3f, -0.4f, 0.866f).normalized();
    EXPECT_NEAR(MetalRoughBsdf::ggx_d(w, 0.4f, 0.4f), MetalRoughBsdf::ggx_d(w, 0.4f), 1e-5f);
    EXPECT_NEAR(MetalRoughBsdf::smith_g1(w, 0.4f, 0.4f), MetalRoughBsdf::smith_g1(w, 0.4f), 1e-6f);

    MetalRoughBsdf brushed(Color(0.9f, 0.8f, 0.6f), 1.0f, 0.3f);
    brushed.set_anisotropy(0.8f);
    const Vec3 up(0, 0, 1);
    const Vec3 along_x = Vec3(std::sin(0.35f), 0, std::cos(0.35f)), along_y = Vec3(0, std::sin(0.35f), std::cos(0.35f));
    EXPECT_GT(brushed.eval(up, along_x)[0], 3 * brushed.eval(up, along_y)[0]);
    for (float metallic : {0.0f, 1.0f})
        for (float theta : {0.0f, 0.8f, 1.3f}) {
            MetalRoughBsdf white(Color::Ones(), metallic, 0.4f);
            white.set_anisotropy(1.0f);
            EXPECT_LE(albedo_quadrature(white, dir_from_theta(theta), 800).maxCoeff(), 1.0f + 1e-2f)
                << metallic << " " << theta;
        }
    Rng rng(23, 4);
    for (int k = 0; k < 1000; ++k) {
        Vec3 a = sample_cosine_hemisphere(rng.uniform2()), b = sample_cosine_hemisphere(rng.uniform2());
        Color f1 = brushed.eval(a, b), f2 = brushed.eval(b, a);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(f1[c], f2[c], 1e-4f * std::max(1.0f, f1[c]));
    }
    const Vec3 wo = Vec3(0.5f, 0.45f, 0.74f).normalized();
    EXPECT_LE(pdf_integral(brushed, wo), 1.0 + 5e-3);
    EXPECT_GT(pdf_integral(brushed, wo), 0.6);
    expect_sampled_estimate_matches_quadrature(brushed, wo, &rng, "anisotropic metal");
    MetalRoughBsdf satin(Color(0.6f, 0.2f, 0.2f), 0.0f, 0.5f);
    satin.set_anisotropy(0.6f);
    expect_sampled_estimate_matches_quadrature(satin, wo, &rng, "anisotropic dielectric");
    MetalRoughBsdf none(Color(0.6f, 0.2f, 0.2f), 0.3f, 0.5f), zero(Color(0.6f, 0.2f, 0.2f), 0.3f, 0.5f);
    zero.set_anisotropy(0.0f);
    EXPECT_TRUE(none.eval(wo, dir_from_theta(-0.3f)).isApprox(zero.eval(wo, dir_from_theta(-0.3f)), 0.0f));
    EXPECT_EQ(none.pdf(wo, dir_from_theta(-0.3f)), zero.pdf(wo, dir_from_theta(-0.3f)));
}

// A white anisotropic dielectric reflects all it receives from any view: its Lambert base takes
// what the stretched specular lobe leaves towards that view, and that lobe's albedo depends on the
// view's azimuth (the roughness it meets is the one projected on it). With the albedo of the mean
// roughness a grazing view along the stretch reflected up to 1.22 and one across it 0.51; with the
// roughness projected on the view's azimuth at most 1.005, and at least 0.68 (strength 0.9,
// roughness 0.05, 86 degrees across the stretch: the remaining loss).
TEST(MetalRoughBsdf, AWhiteAnisotropicDielectricReflectsAllItReceivesFromAnyView) {
    Rng rng(11, 3);
    double worst_high = 0, worst_low = 2, all = 0;
    int views = 0;
    for (const float strength : {0.3f, 0.6f, 0.9f})
        for (const float roughness : {0.05f, 0.2f, 0.5f})
            for (const float deg : {60.0f, 80.0f, 86.0f, 88.5f})
                for (const float azimuth : {0.0f, 0.8f, 1.5708f}) {
                    MetalRoughBsdf bsdf(Color::Ones(), 0.0f, roughness);
                    bsdf.set_anisotropy(strength);
                    const float t = deg * kPi / 180;
                    const Vec3 wo(std::sin(t) * std::cos(azimuth), std::sin(t) * std::sin(azimuth), std::cos(t));
                    bsdf.set_wo(wo);
                    double se = 0;
                    const double mean = sampled_albedo(bsdf, wo, &rng, 40000, &se);
                    worst_high = std::max(worst_high, mean - 4 * se), worst_low = std::min(worst_low, mean + 4 * se);
                    EXPECT_LE(mean, 1.0 + 4 * se + 1e-2) << "strength " << strength << " roughness " << roughness
                                                         << " at " << deg << " deg, azimuth " << azimuth;
                    // Across a strong stretch near grazing the lobe loses what its wide x spread
                    // masks; the isotropic albedo of the projected roughness misses some of that.
                    EXPECT_GE(mean, 0.65 - 4 * se) << "strength " << strength << " roughness " << roughness << " at "
                                                   << deg << " deg, azimuth " << azimuth;
                    all += mean, ++views;
                }
    std::printf("white anisotropic dielectric: albedo within %.3f .. %.3f (4 standard errors), mean %.3f\n", worst_low,
                worst_high, all / views);
    EXPECT_GT(all / views, 0.97);
}

TEST(MetalRoughBsdf, PdfIntegratesToAtMostOne) {
    for (float metallic : {0.0f, 1.0f})
        for (float roughness : {0.3f, 0.8f})
            for (float theta : {0.2f, 1.0f}) {
                MetalRoughBsdf bsdf(Color(0.8f, 0.5f, 0.2f), metallic, roughness);
                double integral = pdf_integral(bsdf, dir_from_theta(theta));
                EXPECT_LE(integral, 1.0 + 5e-3);
                // The visible-normal lobe loses only what reflects below the horizon.
                EXPECT_GT(integral, 0.6);
            }
}

TEST(MetalRoughBsdf, SampledEstimateMatchesQuadrature) {
    for (float metallic : {0.0f, 1.0f})
        for (float roughness : {0.2f, 0.6f}) {
            MetalRoughBsdf bsdf(Color(0.9f, 0.6f, 0.3f), metallic, roughness);
            Rng rng(17, 3);
            expect_sampled_estimate_matches_quadrature(bsdf, dir_from_theta(0.9f), &rng,
                                                       "metallic " + std::to_string(metallic) + " roughness " +
                                                           std::to_string(roughness));
        }
}

TEST(MetalRoughBsdf, IsReciprocal) {
    MetalRoughBsdf bsdf(Color(0.7f, 0.4f, 0.9f), 0.3f, 0.45f);
    Rng rng(1, 1);
    for (int k = 0; k < 1000; ++k) {
        Vec3 a = sample_cosine_hemisphere(rng.uniform2()), b = sample_cosine_hemisphere(rng.uniform2());
        Color f1 = bsdf.eval(a, b), f2 = bsdf.eval(b, a);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(f1[c], f2[c], 1e-4f * std::max(1.0f, f1[c]));
    }
}

}  // namespace
}  // namespace dynsky
