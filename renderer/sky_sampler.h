// Importance samplers for the sky above the horizon, behind one interface (EnvLight uses it).
//
// Every sampler is built per frame from per-pixel weights that EnvLight computes in one streaming
// pass: w(i, j) = luminance x dw/(du dv) at the pixel centre (0 for pixels whose centre lies
// outside the disc), i.e. proportional to the power each pixel sends. Pixel-based samplers pick a
// pixel in proportion to w and a point uniformly inside it, so their density is constant per
// pixel in (u, v) and p_w = p_uv / J(theta); pdf() recomputes it from the direction alone, and
// sample() reports pdf(wi) of the direction it returns, so the two agree exactly.
//
// Methods (pbrt-v4 / Mitsuba names where they exist):
//   uniform  uniform hemisphere (ignores the sky)          cosine  cos(theta) about the zenith
//   cdf      piecewise-constant 2D CDF (row CDFs + marginal, two binary searches)
//   alias    Walker/Vose alias tables: one over rows, one per row (rows built in parallel)
//   mip      hierarchical warp down a MIP pyramid of the weights (Clarberg et al. 2005)
//   sun+X    sun/sky split: the sun disc (SkyImage::sun_direction or the brightest compact spot)
//            is cut out of X's weights and sampled as a uniform cone, mixed by power
//   X+mis    MIS compensation (Karlik et al. 2019, as pbrt-v4): weights from max(L - mean L, 0),
//            all-ones if nothing is left. Only valid when BSDF sampling covers the rest (MIS).
//
// Parameters (SkySamplerOptions, defaults): method cdf; sun_split false; mis_compensation false
// (`dynsky render` and the frame stage use "cdf+mis", recommended_sky_sampler() + MIS). Sun split:
// cone of the solar disc's radius (0.53 deg), or the brightest compact spot when no sun direction.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sky/sky_image.h"
#include "util/math.h"

namespace dynsky {

enum class SkySamplerMethod { Uniform, Cosine, Cdf, Alias, Mip };

struct SkySamplerOptions {
    SkySamplerMethod method = SkySamplerMethod::Cdf;  // the defaults are recommended_sky_sampler()
    bool sun_split = false;
    bool mis_compensation = false;
};

// "sun+alias+mis" etc. and back; parse throws dynsky::Error listing the valid names.
std::string sky_sampler_name(const SkySamplerOptions& options);
SkySamplerOptions parse_sky_sampler(const std::string& name);
// Every method, each without and with the sun split (uniform/cosine only without), no "+mis".
std::vector<std::string> sky_sampler_base_names();
// The default the renderer uses (chosen from docs/sampling/README.md's measurements), without
// MIS compensation; the render command adds "+mis" since it always combines strategies by MIS.
SkySamplerOptions recommended_sky_sampler();
// What the path tracer's commands use (render's default --sampler, every frame of animate and
// compare): the recommended sampler with MIS compensation ("cdf+mis").
SkySamplerOptions path_tracer_sky_sampler();

// The per-pixel weights EnvLight hands to a sampler's build (one streaming pass over the image).
struct SkyWeights {
    std::vector<float>* values = nullptr;  // n x n, finite, >= 0 (see the file comment)
    const uint16_t* jacobian = nullptr;    // n x n fixed-point dw/(du dv), the scale of values (0 off the disc)
    int n = 0;
    // MIS compensation still to apply: the final weight is max(value - mis_floor x jacobian, 0).
    // Samplers fuse it into their own pass over the weights (one pass per frame less) and store the
    // final weights back into values wherever they read values later.
    float mis_floor = 0;

    // Turns row j's values (values' own row, or wherever a sampler moved them) into its final
    // weights in place.
    void finish_row(int j, float* row) const;
    // Applies mis_floor to every value in place (for samplers that need all final weights before
    // they start), then sets it to 0.
    void apply_compensation();
};

class SkySampler {
  public:
    virtual ~SkySampler() = default;
    // A sampler may change the weights in place (compensation, the sun split zeroing the sun) and
    // read them later instead of copying: they must stay alive and unchanged until the next build.
    virtual void build(const SkyImage& sky, SkyWeights& weights) = 0;
    // False when the build left nothing to sample (every final weight 0).
    virtual bool has_weight() const { return true; }
    // A direction above the horizon, its density per unit solid angle (= pdf(wi)) and its fisheye
    // uv as fisheye::uv_from_direction(wi) gives it (the caller's radiance lookup reads it: the
    // mapping, an atan, is computed once); false when no sample is produced (empty sky, a sample
    // outside the disc), which counts as zero.
    virtual bool sample(const Vec2& u, Vec3* wi, float* pdf, Vec2* uv) const = 0;
    // Density per unit solid angle of sampling w (0 below the horizon).
    virtual float pdf(const Vec3& w) const = 0;
    // pdf(w) for a w whose uv (fisheye::uv_from_direction) the caller already has: the same value.
    virtual float pdf_uv(const Vec3& w, const Vec2& uv) const { return pdf(w); }
    virtual size_t memory_bytes() const = 0;
    // The sun cone of a sun split (cos of its half-angle, probability); probability 0 if none.
    virtual float sun_probability() const { return 0; }
    // The 2D CDF of the "cdf" method (tests compare against it); null for the others.
    virtual const class Distribution2D* distribution() const { return nullptr; }
};

std::unique_ptr<SkySampler> make_sky_sampler(const SkySamplerOptions& options);

}  // namespace dynsky
