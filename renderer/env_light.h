// The sky as a light: a canonical fisheye SkyImage above the horizon, a ground model below it.
//
// Radiance lookup and sampling density agree exactly (the classic source of fireflies when they
// don't): radiance is the nearest pixel (no filter that would blur a small sun), and sampling
// picks pixels in proportion to luminance x solid angle, uniformly in (u, v) within a pixel, so
// p_w = p_pixel / (pixel area in uv) / J(theta) with J = dw / (du dv) evaluated at the sample.
//
// Ground (below the horizon): a uniform Lambertian ground lit by the sky, radiance
// L_ground = albedo * E_sky / pi, with E_sky the sky's irradiance on a horizontal plane.
// Light samples pick the sky or the ground in proportion to their power. The sky part is sampled
// by a SkySampler (renderer/sky_sampler.h) chosen by option; all of them share the radiance
// lookup here and report pdfs that match it.
//
// Pixels that are NaN, infinite or negative (validate_sky rejects them at load; skies made in
// memory may still hold them) are treated as black, in sampling and in radiance() alike, and
// counted (bad_pixel_count), so they never reach an image.
#pragma once

#include <memory>

#include "renderer/distribution_2d.h"
#include "renderer/sky_sampler.h"
#include "sky/sky_image.h"

namespace dynsky {

struct EnvLightSample {
    Vec3 wi;  // world direction towards the light
    Color radiance;
    float pdf = 0;  // solid angle
};

class EnvLight {
  public:
    explicit EnvLight(float ground_albedo = 0.3f, const SkySamplerOptions& sampler = recommended_sky_sampler());
    EnvLight(std::shared_ptr<const SkyImage> sky, float ground_albedo,
             const SkySamplerOptions& sampler = recommended_sky_sampler());

    // The per-frame path: point at a new sky and rebuild the distribution (storage is reused
    // when the resolution is unchanged). The scene is untouched.
    void set_sky(std::shared_ptr<const SkyImage> sky);
    // Radiance below the horizon from an image instead of the ground model (a lat-long HDRI's lower
    // half, sky/latlong.h latlong_to_fisheye with lower = true, mirrored: its zenith is the nadir);
    // nullptr: back to the model. Kept across set_sky. The image is importance sampled like the sky
    // (a sampler of the same method over luminance x solid angle, nearest-pixel radiance, so sample,
    // pdf and radiance agree); the model's uniform ground is sampled uniformly.
    void set_ground_image(std::shared_ptr<const SkyImage> ground);
    double last_build_seconds() const { return build_seconds_; }

    Color radiance(const Vec3& w) const;
    // radiance(w) and pdf(w) of one direction (an escaping BSDF-sampled ray needs both): the same
    // values, the direction mapped to the fisheye once.
    Color radiance(const Vec3& w, float* pdf) const;
    // Bilinear radiance, for the sky seen directly by the camera: a camera ray carries no MIS
    // weight, so it need not match the pdf, and a low-resolution sky then looks smooth, not blocky.
    // Its direction-to-fisheye mapping takes a polynomial atan (within 2e-7 rad of libm's).
    Color radiance_filtered(const Vec3& w) const;
    // radiance_filtered of n unit directions at once (a tile's camera rays that see the sky): all
    // the texels are asked for before the first is read, so their cache misses overlap.
    void radiance_filtered(const Vec3* w, int n, Color* out) const;
    float pdf(const Vec3& w) const;
    // Starts loading the sky pixel and sampling weights that radiance(w) and pdf(w) read, so a path
    // can overlap those cache misses (the image and its weights are megabytes, read at random by
    // escaping rays) with the traversal of a ray towards w. Changes nothing else.
    void prefetch(const Vec3& w) const;
    bool sample(float u_choice, const Vec2& u, EnvLightSample* out) const;

    float ground_albedo() const { return ground_albedo_; }
    // The ground model's radiance, or the ground image's mean (solid-angle weighted).
    Color ground_radiance() const { return ground_radiance_; }
    Color sky_irradiance() const { return sky_irradiance_; }  // on a horizontal plane, W m^-2 per channel
    float sky_probability() const { return sky_probability_; }
    const SkyImage& sky() const { return *sky_; }
    // The CDF of the "cdf" sampler (an empty one for other samplers).
    const Distribution2D& distribution() const;
    const SkySampler& sampler() const { return *sampler_; }
    // Pixels treated as black because they were NaN, infinite or negative in the last sky.
    size_t bad_pixel_count() const { return bad_pixels_; }
    // Bytes held for sampling: weights, solid-angle table and the sampler's own tables.
    size_t memory_bytes() const;

    // dw / (du dv) = (pi^2/4) sin(theta)/theta as a polynomial in theta^2 = (pi^2/4) r^2:
    // no sqrt or sin per pixel, which keeps the per-frame rebuild near memory bandwidth.
    static float jacobian_from_r2(float r2);
    static float cos_theta_from_r2(float r2);

    // What the per-frame pass sums per row (rows run in parallel; the totals are added in row
    // order, so the result does not depend on the thread count). Public only for that pass's helpers.
    struct RowSums {
        float w = 0, er = 0, eg = 0, eb = 0;  // sum of weights, of RGB x cos x jacobian (fixed-point scale)
        int bad = 0;                          // pixels with a NaN, infinite or negative channel
    };

  private:
    // Pixel holding the radiance of uv (with r <= 1): itself, or for rim pixels whose centre lies
    // outside the disc, the nearest pixel inward.
    int lookup_pixel(const Vec2& uv) const;
    Color sky_radiance(const Vec2& uv) const { return pixel_radiance(lookup_pixel(uv)); }
    // radiance_filtered of w (above the horizon) at its fisheye position uv.
    Color filtered_at(const Vec3& w, const Vec2& uv) const;
    Color pixel_radiance(int k) const;
    Color ground(const Vec3& w) const;
    // Density of ground samples per unit solid angle (w below the horizon), given the ground is chosen.
    float ground_pdf(const Vec3& w) const;

    std::shared_ptr<const SkyImage> sky_;
    SkySamplerOptions sampler_options_;
    std::unique_ptr<SkySampler> sampler_;
    std::vector<float> weights_;  // per pixel luminance x jacobian (fixed-point scale)
    std::vector<RowSums> row_sums_;
    size_t bad_pixels_ = 0;
    // Per pixel dw/(du dv) in fixed point (0 off the disc), alone (read by the samplers' pass) and
    // paired with cos(theta) dw/(du dv) (one stream beside the image in the first pass).
    std::vector<uint16_t> jacobian_table_;
    std::vector<uint16_t> jacobian_pair_table_;
    double jacobian_table_sum_ = 0;
    int table_resolution_ = 0;
    float ground_albedo_;
    std::shared_ptr<const SkyImage> ground_image_;
    std::unique_ptr<SkySampler> ground_sampler_;  // over ground_image_ (null for the model)
    std::vector<float> ground_weights_;
    std::vector<uint16_t> ground_jacobian_;
    Color ground_image_mean_ = Color::Zero();
    Color ground_radiance_ = Color::Zero();
    Color sky_irradiance_ = Color::Zero();
    float sky_probability_ = 1.0f;
    double build_seconds_ = 0;
    // Buffers already backed by huge pages (see back_by_huge_pages in env_light.cpp).
    std::vector<const void*> huge_buffers_;
    void back_by_huge_pages(const void* data, size_t bytes);
};

}  // namespace dynsky
