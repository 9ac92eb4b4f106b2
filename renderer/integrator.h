// Unidirectional path tracing under an environment light: next-event estimation of the sky
// combined with BSDF sampling by multiple importance sampling (power heuristic), Russian
// roulette, a maximum depth, and stochastic transparency for alpha MASK/BLEND. Image tiles run
// in parallel on oneTBB; every pixel has its own random stream derived from (seed, pixel), so the
// same seed gives the same image on any number of threads.
//
// Beside the colour a render gives the passes users composite and denoise with ("AOVs", named as
// Cycles names its passes), a render region, adaptive sampling by rounds (a pixel stops once the
// relative error of its mean falls under a threshold; its samples are a prefix of the same
// pixel's samples in a non-adaptive render, so both agree bitwise on what they share), a time
// limit, and two firefly remedies that are off by default (clamp of indirect light, Cycles'
// "Clamp Indirect"; roughness regularisation after the first bounce, Cycles' "Filter Glossy").
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>

#include "renderer/accel.h"
#include "renderer/bsdf.h"
#include "renderer/env_light.h"
#include "renderer/material_eval.h"
#include "renderer/zsobol_sampler.h"
#include "util/error.h"
#include "util/image.h"

namespace dynsky {

enum class LightStrategy { Mis, LightOnly, BsdfOnly };

// Extra passes of a render (glossary: AOV). In the EXR (render_layers) they are named as Cycles
// names its passes: "Denoising Albedo", "Normal", "Depth", the alpha as the image's "A", and
// "Sample Count".
struct AovSelection {
    bool albedo = false;  // base colour at the first surface seen (0 on the sky), averaged
    bool normal = false;  // world shading normal there, facing the camera (0 on the sky), averaged
    bool depth = false;   // camera-space Z depth of the first sample's surface (1e10 on the sky)
    // Share of samples that see a surface (1) rather than the sky (0); with it the sky seen from
    // the camera is transparent and the colour premultiplied (Cycles' Film > Transparent).
    bool alpha = false;
    bool sample_count = false;  // samples taken in the pixel (adaptive sampling, time limit)
    bool any() const { return albedo || normal || depth || alpha || sample_count; }
};

// "albedo,normal,depth,alpha,samples" (any subset, any order; "" none). Throws dynsky::Error.
AovSelection parse_aovs(const std::string& list);

// A rectangle of pixels [x0, x1) x [y0, y1) of the full image; empty (x1 <= x0): the whole image.
struct PixelRegion {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    bool empty() const { return x1 <= x0 || y1 <= y0; }
};

// "x0,y0,x1,y1" checked against a width x height image. Throws dynsky::Error.
PixelRegion parse_region(const std::string& text, int width, int height);

struct RenderSettings {
    int width = 640, height = 360;
    int spp = 16;            // samples per pixel (the most, with adaptive sampling or a time limit)
    int max_depth = 8;       // path vertices after the camera
    int rr_start_depth = 3;  // Russian roulette from this depth on
    uint64_t seed = 0;
    LightStrategy strategy = LightStrategy::Mis;
    bool compute_variance = false;  // per-pixel variance of the pixel mean (for tests)
    bool quiet = false;             // no progress bar
    int tile_size = 16;
    PixelRegion region;  // render only these pixels; the result is cropped to them
    AovSelection aovs;
    // Adaptive sampling (0: off): after each round of round_spp samples a pixel whose error
    // estimate (adaptive_error_estimates) is under the threshold takes no more samples.
    float noise_threshold = 0;
    int round_spp = 16;
    double time_limit_seconds = 0;  // no new round starts after this much time (0: none); the first always runs
    // An interrupt (util/interrupt.h stop_requested) ends the render after its round of samples, as
    // the time limit does: the samples taken are kept (RenderResult::stopped). Samples in rounds.
    bool stop_on_request = false;
    // Fireflies, both off (0) by default so references stay unbiased:
    float clamp_indirect = 0;  // light that scattered at two or more surfaces: sum of RGB at most this, per sample
    float filter_glossy = 0;   // Cycles' Filter Glossy: after the first bounce, roughen by the path's smallest pdf
    // Where the sample values come from: independent PCG32 streams per pixel (Random, the reference
    // pattern) or Owen-scrambled Sobol in Z order (renderer/zsobol_sampler.h).
    SamplePattern pattern = SamplePattern::Random;
};

// "random" or "sobol". Throws dynsky::Error.
SamplePattern parse_sample_pattern(const std::string& name);

// The relative error of a pixel's mean from its n luminance samples (sum and sum of squares):
// sqrt(variance of the mean) / mean; 0 when every sample is 0, infinite for n < 2.
double pixel_relative_error(int n, double sum, double sum_squares);

// Adaptive sampling's error estimate of each pixel of a width x height image (row-major: its sample
// count n and the sums of its samples' luminance and squared luminance): the larger of its own
// relative error (pixel_relative_error) and its neighbourhood's, the sample variances of the
// (2 radius + 1)^2 pixels around it (fewer at the image's edges) averaged, for the pixel's n, over
// their mean luminance. On its own, a pixel none of whose first samples found a small light (a lamp
// the size of a hand, a caustic) had a variance of 0 and stopped at once: 83 % of a floor lit by a
// 20 cm emitter stopped after 16 samples and the image came out 3-6 times too dark. Its neighbours
// that found the light say it is there.
std::vector<double> adaptive_error_estimates(int width, int height, const std::vector<int>& n,
                                             const std::vector<double>& lum_sum, const std::vector<double>& lum_sum2,
                                             int radius);
constexpr int kAdaptiveNeighbourhoodRadius = 4;  // 9 x 9 pixels

struct RenderStats {
    double seconds = 0;
    uint64_t camera_rays = 0, extension_rays = 0, shadow_rays = 0;
    uint64_t total_rays() const { return camera_rays + extension_rays + shadow_rays; }
};

struct RenderResult {
    Image color;     // linear radiance, 3 channels (the region's size when one is given)
    Image variance;  // variance of each pixel's mean (3 channels) if requested
    // The passes asked for (empty otherwise): albedo and normal 3 channels, the rest 1.
    Image albedo, normal, depth, alpha, sample_count;
    // 1 channel: with adaptive sampling, the estimate each pixel stopped at (or its last one:
    // adaptive_error_estimates); else with compute_variance, its pixel_relative_error.
    Image relative_error;
    RenderStats stats;
    int rounds = 0;        // sampling rounds run
    bool stopped = false;  // an interrupt ended it early (RenderSettings::stop_on_request)
};

// One multi-channel image of the colour and its passes, channels named for the EXR: R, G, B
// (A with alpha), then "Denoising Albedo.R/G/B", "Normal.X/Y/Z", "Depth.Z", "Sample Count.X".
Image render_layers(const RenderResult& result);

// What the path's first surface gave, for the passes.
struct FirstHit {
    bool surface = false;  // false: the camera ray reached the sky
    Color albedo = Color::Zero();
    Vec3 normal = Vec3::Zero(), position = Vec3::Zero();
};

// Optional observer of every ray traced (benchmarks replay them through plain Embree, each kind
// as the path tracer traces it: camera rays in coherent batches, the rest one by one).
enum class RayKind { Camera, Continuation, Shadow };
using RayObserver = std::function<void(const Ray&, RayKind)>;

class PathIntegrator {
  public:
    PathIntegrator(const Accel& accel, const EnvLight& light, const RenderSettings& settings);

    RenderResult render(const Camera& camera) const;
    // Radiance along one camera ray (for tests); first_hit, when given, receives the passes' data.
    Color trace(const Ray& ray, class Rng& rng, RenderStats* stats, FirstHit* first_hit = nullptr) const;

    void set_ray_observer(RayObserver observer) { observer_ = std::move(observer); }

  private:
    struct PixelState;
    struct PixelExtra;
    struct TilePixel {
        int x, y;
        PixelState* state;
    };
    struct TileScratch;
    // The path tracer over any source of samples with uniform() and uniform2() (Rng, ZSobolSampler).
    // primary: the camera ray's first intersection when already traced (Accel::intersect_coherent).
    template <class Sampler>
    Color trace_path(const Ray& ray, Sampler& sampler, RenderStats* stats, FirstHit* first_hit,
                     const RTCRayHit* primary = nullptr) const;
    // tan_half: tan(yfov / 2) of the camera (ymag for orthographic ones), computed once per render.
    Ray camera_ray(const Camera& camera, float tan_half, float aspect, float px, float py) const;
    // Takes samples [state.n, state.n + count) of each of n pixels (of one tile), sample by sample: the
    // camera rays of one round over the pixels are traced together (coherent, as packets), then each
    // path goes on alone. A pixel's samples use its own stream in its own order, as before.
    void sample_tile(const Camera& camera, float tan_half, float aspect, const TilePixel* pixels, int n, int count,
                     RenderStats* stats) const;
    void store_pixel(const Camera& camera, const PixelState& state, int x, int y, RenderResult* result) const;
    // Visibility along a shadow ray through alpha-tested, blended and transmissive surfaces (per channel:
    // glass tints what passes).
    Color transmittance(const Ray& ray, RenderStats* stats) const;
    // Light reflected towards wo (local) from the scene's punctual lights at a shading point,
    // each light's shadow ray traced (Scene::lights; radiance, not yet times the path's weight).
    Color punctual_light(const ShadingPoint& sp, const MetalRoughBsdf& bsdf, const Vec3& wo, const SurfaceHit& hit,
                         RenderStats* stats) const;
    // Whether a hit is skipped: by alpha (MASK below cutoff, or BLEND chosen as transparent), or an
    // unlit surface met by a path that has scattered since the camera (camera_path false).
    bool passes_through(const SurfaceHit& hit, float u, bool camera_path) const;
    float surface_alpha(const SurfaceHit& hit) const;

    const Accel& accel_;
    const EnvLight& light_;
    RenderSettings settings_;
    RayObserver observer_;
};

// Where a ray leaving a surface hit towards w starts: the hit's position moved off the surface along
// the unit normal n, to w's side, by its error bound (SurfaceHit::position_error) projected on n
// (pbrt-v4's OffsetRayOrigin), so the ray cannot hit the surface it leaves, at any scene scale.
Vec3 offset_ray_origin(const SurfaceHit& hit, const Vec3& n, const Vec3& w);

}  // namespace dynsky
