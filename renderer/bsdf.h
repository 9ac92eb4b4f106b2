// The glTF 2.0 metallic-roughness BRDF (glTF spec, Appendix B): Trowbridge-Reitz (GGX)
// microfacet specular with Smith masking, Schlick Fresnel, and a Lambert diffuse base. The base
// is weighted by what the specular lobe leaves (an albedo-scaled Lambert, see bsdf.cpp) rather
// than by glTF's per-half-vector fresnel_mix, so the model never reflects more than it receives.
// Directions are in the local shading frame: +Z is the shading normal.
#pragma once

#include "util/math.h"

namespace dynsky {

struct BsdfSample {
    Vec3 wi;             // local frame
    Color f;             // BSDF value (not multiplied by the cosine)
    float pdf = 0;       // solid angle
    bool delta = false;  // unused by this model (roughness is clamped), kept for the integrator
};

class MetalRoughBsdf {
  public:
    // roughness is the glTF perceptual roughness (alpha = roughness^2).
    // specular scales the dielectric Fresnel (KHR_materials_specular); 0 leaves a pure Lambertian.
    // transmission (KHR_materials_transmission) is the share of the dielectric's base that passes
    // through instead of scattering diffusely: the diffuse lobe keeps 1 - transmission of it.
    MetalRoughBsdf(const Color& base_color, float metallic, float roughness, float specular = 1.0f,
                   float transmission = 0.0f);

    // KHR_materials_clearcoat: a dielectric layer (F0 0.04, GGX of its own roughness) over the whole
    // BSDF above, of strength `factor`; the layer below receives and returns 1 - the coat's albedo
    // each way. 0 (the default): no coat, and every result bitwise as without it. Before set_wo.
    void set_clearcoat(float factor, float roughness);

    // KHR_materials_sheen: a layer of micro-fibres over the metal-rough BSDF, under any clearcoat:
    // f = sheen + base x min(1 - max(colour) E_s(mu_o), 1 - max(colour) E_s(mu_i)) (the
    // extension's albedo scaling; Conty and Kulla 2017's "Charlie" distribution and visibility, E_s
    // its directional albedo, tabulated). roughness is the extension's (alpha, not squared), at
    // least 0.07. A black colour (the default): no sheen, every result bitwise as without it.
    // Before set_wo.
    void set_sheen(const Color& colour, float roughness);

    // KHR_materials_ior: the dielectric's index of refraction (default glTF's 1.5, F0 = 0.04);
    // F0 = ((ior - 1) / (ior + 1))^2 for its specular lobe, its energy compensation and what glass
    // passes. Values below 1 (the extension's 0) read as 1.5. Before set_wo.
    void set_ior(float ior);

    // KHR_materials_specular's colour: the dielectric's F0 per channel, min(F0 x colour, 1) (F90
    // stays the specular factor). Default white: every result bitwise as without it. Before set_wo.
    void set_specular_color(const Color& colour);

    // KHR_materials_anisotropy: the specular lobe's roughness stretched along the local x axis (the
    // caller turns the shading frame's tangent to the anisotropy direction): alpha_x = mix(alpha, 1,
    // strength^2), alpha_y = alpha, as the extension defines. The albedo tables (energy compensation,
    // lobe probabilities) take the roughness each direction's azimuth meets (projected_roughness),
    // their cosine-weighted mean integrated over the hemisphere. 0 (the
    // default): isotropic, every result bitwise as without it. Before set_wo.
    void set_anisotropy(float strength);

    // KHR_materials_volume, thin: what transmitted() passes is also multiplied by this (per channel).
    void set_transmission_tint(const Color& tint) { tint_ = tint.max(0.0f).min(1.0f); }

    // Thin-walled transmission: the light arriving along -wo that passes straight through the
    // surface (a null-scattering event for the integrator, not part of eval): the dielectric's
    // share, what its specular lobe does not reflect towards wo (1 - E(wo)), times transmission,
    // tinted by the base colour. A white glass reflects E(wo) and passes 1 - E(wo): nothing lost.
    Color transmitted(const Vec3& wo) const;

    Color eval(const Vec3& wo, const Vec3& wi) const;
    float pdf(const Vec3& wo, const Vec3& wi) const;
    // u_lobe picks the lobe; u picks the direction within it.
    bool sample(const Vec3& wo, float u_lobe, const Vec2& u, BsdfSample* out) const;

    // Precomputes what depends on wo alone (the specular lobe's albedo towards wo, the lobe
    // probability): a path vertex evaluates, samples and takes pdfs for the same wo several times.
    // Results are bitwise those without it; calls with another wo still work.
    void set_wo(const Vec3& wo);

    float alpha() const { return alpha_; }
    // Probability of sampling the specular lobe for this wo.
    float specular_probability(const Vec3& wo) const;

    // GGX pieces, public for tests.
    static float ggx_d(const Vec3& wm, float alpha);
    static float smith_g1(const Vec3& w, float alpha);
    // Visible-normal sampling (Heitz 2018, "Sampling the GGX Distribution of Visible Normals").
    static Vec3 sample_ggx_vndf(const Vec3& wo, float alpha, const Vec2& u);
    static float ggx_vndf_pdf_wi(const Vec3& wo, const Vec3& wi, float alpha);
    // The same, anisotropic: roughness alpha_x along local x, alpha_y along y (Heitz 2018 covers both).
    static float ggx_d(const Vec3& wm, float alpha_x, float alpha_y);
    static float smith_g1(const Vec3& w, float alpha_x, float alpha_y);
    static Vec3 sample_ggx_vndf(const Vec3& wo, float alpha_x, float alpha_y, const Vec2& u);
    static float ggx_vndf_pdf_wi(const Vec3& wo, const Vec3& wi, float alpha_x, float alpha_y);

    // The sheen lobe alone (Charlie D and V, colour 1) and its directional albedo, for tests.
    static float sheen_lobe(const Vec3& wo, const Vec3& wi, float roughness);
    static float sheen_distribution(float cos_h, float roughness);
    static float sheen_albedo_table(float mu, float roughness);

  private:
    // The BSDF without the clearcoat: the sheen over the metal-rough BSDF.
    Color base_eval(const Vec3& wo, const Vec3& wi) const;
    float base_pdf(const Vec3& wo, const Vec3& wi) const;
    // The metal-rough BSDF alone (glTF's core model).
    Color metal_rough_eval(const Vec3& wo, const Vec3& wi) const;
    float metal_rough_pdf(const Vec3& wo, const Vec3& wi) const;
    // What the base under the sheen keeps of light arriving along mu (1 - max(colour) E_s(mu)).
    float sheen_scaling(float mu) const;
    float sheen_probability(const Vec3& wo) const;
    // The base's albedo towards wo, roughly (its lobes' weights): for lobe probabilities.
    float base_albedo_estimate(const Vec3& wo) const;
    float coat_albedo(float mu) const;  // coat_ x E_c(mu): what the clearcoat's lobe reflects
    float coat_probability(const Vec3& wo) const;
    float coat_probability_for(const Vec3& wo, float e_coat) const;
    float specular_albedo(const Vec3& w) const;      // specular_ x E(w): what the specular lobe reflects
    float projected_roughness(const Vec3& w) const;  // an anisotropic lobe's roughness towards w
    float specular_average() const;                  // E's cosine-weighted mean (no specular_)
    bool cached_for(const Vec3& wo) const;           // set_wo's cache holds wo
    float specular_probability_for(const Vec3& wo, float e_spec) const;

    Color base_;
    float metallic_, roughness_, alpha_, specular_, transmission_;
    void update_f0();       // f0_, f0_colour_ and e_avg_ from f0_ior_ and specular_color_
    float f0_ior_ = 0.04f;  // the dielectric's Fresnel at normal incidence (set_ior)
    float f0_ = 0.04f;      // the albedo tables' F0: f0_ior_, or the largest channel of f0_colour_
    Color specular_color_ = Color::Ones(), f0_colour_ = Color::Constant(0.04f);
    bool coloured_ = false;       // specular_color_ is not white
    Color tint_ = Color::Ones();  // set_transmission_tint
    float e_avg_ = 0;             // specular_ x the lobe's cosine-weighted mean albedo
    // set_wo's cache: wo.z(), specular_albedo(wo.z()) and the lobe probability (valid: cached_wo_z_ > 0).
    float cached_wo_z_ = -1, cached_wo_x_ = 0, cached_wo_y_ = 0, cached_e_o_ = 0, cached_ps_ = 0;
    float coat_ = 0, coat_roughness_ = 0, coat_alpha_ = 1;  // set_clearcoat
    float cached_e_coat_ = 0, cached_pc_ = 0;
    Color sheen_ = Color::Zero();  // set_sheen
    float sheen_max_ = 0, sheen_roughness_ = 0.07f;
    bool anisotropic_ = false;  // set_anisotropy
    float alpha_x_ = 0, alpha_y_ = 0;
    // The specular lobe's D G1 G1 and visible-normal pdf, isotropic or not.
    float specular_dgg(const Vec3& wm, const Vec3& wo, const Vec3& wi) const;
    float specular_vndf_pdf(const Vec3& wo, const Vec3& wi) const;
};

}  // namespace dynsky
