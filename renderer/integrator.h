// Unidirectional path tracing under an environment light: next-event estimation of the sky
// combined with BSDF sampling by multiple importance sampling (power heuristic), Russian
// roulette, a maximum depth, and stochastic transparency for alpha MASK/BLEND. Image tiles run
// in parallel on oneTBB; every pixel has its own random stream derived from (seed, pixel), so the
// same seed gives the same image on any number of threads.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>

#include "renderer/accel.h"
#include "renderer/env_light.h"
#include "util/image.h"

namespace dynsky {

enum class LightStrategy { Mis, LightOnly, BsdfOnly };

struct RenderSettings {
    int width = 640, height = 360;
    int spp = 16;
    int max_depth = 8;       // path vertices after the camera
    int rr_start_depth = 3;  // Russian roulette from this depth on
    uint64_t seed = 0;
    LightStrategy strategy = LightStrategy::Mis;
    bool compute_variance = false;  // per-pixel variance of the pixel mean (for tests)
    bool quiet = false;             // no progress bar
    int tile_size = 16;
};

struct RenderStats {
    double seconds = 0;
    uint64_t camera_rays = 0, extension_rays = 0, shadow_rays = 0;
    uint64_t total_rays() const { return camera_rays + extension_rays + shadow_rays; }
};

struct RenderResult {
    Image color;     // linear radiance, 3 channels
    Image variance;  // variance of each pixel's mean (3 channels) if requested
    RenderStats stats;
};

// Optional observer of every ray traced (benchmarks replay them through plain Embree).
using RayObserver = std::function<void(const Ray&, bool shadow)>;

class PathIntegrator {
  public:
    PathIntegrator(const Accel& accel, const EnvLight& light, const RenderSettings& settings);

    RenderResult render(const Camera& camera) const;
    // Radiance along one camera ray (for tests).
    Color trace(const Ray& ray, class Rng& rng, RenderStats* stats) const;

    void set_ray_observer(RayObserver observer) { observer_ = std::move(observer); }

  private:
    // tan_half: tan(yfov / 2) of the camera, computed once per render.
    Ray camera_ray(const Camera& camera, float tan_half, float aspect, float px, float py) const;
    // Visibility along a shadow ray through alpha-tested and blended surfaces (transmittance).
    float transmittance(const Ray& ray, RenderStats* stats) const;
    // Whether a hit is skipped by alpha (MASK below cutoff, or BLEND chosen as transparent).
    bool passes_through(const SurfaceHit& hit, float u) const;
    float surface_alpha(const SurfaceHit& hit) const;

    const Accel& accel_;
    const EnvLight& light_;
    RenderSettings settings_;
    RayObserver observer_;
};

// Offset for spawning rays off a surface: relative to the magnitude of the position.
Vec3 offset_ray_origin(const Vec3& p, const Vec3& n, const Vec3& w);

}  // namespace dynsky
