#include "renderer/integrator.h"

#include <tbb/parallel_for.h>

#include <chrono>

#include "renderer/bsdf.h"
#include "renderer/material_eval.h"
#include "renderer/sampling.h"
#include "util/progress.h"

namespace dynsky {

Vec3 offset_ray_origin(const Vec3& p, const Vec3& n, const Vec3& w) {
    float scale = 1e-4f * std::max(1.0f, p.cwiseAbs().maxCoeff());
    Vec3 offset = scale * n;
    return n.dot(w) < 0 ? Vec3(p - offset) : Vec3(p + offset);
}

PathIntegrator::PathIntegrator(const Accel& accel, const EnvLight& light, const RenderSettings& settings)
    : accel_(accel), light_(light), settings_(settings) {}

Ray PathIntegrator::camera_ray(const Camera& camera, float tan_half, float aspect, float px, float py) const {
    float x = (2 * px / settings_.width - 1) * tan_half * aspect;
    float y = (1 - 2 * py / settings_.height) * tan_half;
    Ray ray;
    ray.origin = camera.camera_to_world.translation();
    ray.direction = (camera.camera_to_world.linear() * Vec3(x, y, -1)).normalized();
    return ray;
}

float PathIntegrator::surface_alpha(const SurfaceHit& hit) const {
    const Material& m = *hit.material;
    float alpha = m.base_alpha * hit.color.w();
    if (m.base_color_texture.present())
        alpha *= accel_.scene()
                     .textures[size_t(m.base_color_texture.texture)]
                     ->evaluate(texture_uv(m.base_color_texture, hit))
                     .w();
    return alpha;
}

bool PathIntegrator::passes_through(const SurfaceHit& hit, float u) const {
    const Material& m = *hit.material;
    if (m.alpha_mode == AlphaMode::Opaque) return false;
    float alpha = surface_alpha(hit);
    if (m.alpha_mode == AlphaMode::Mask) return alpha < m.alpha_cutoff;
    return u >= alpha;  // Blend: stochastic transparency
}

float PathIntegrator::transmittance(const Ray& shadow_ray, RenderStats* stats) const {
    if (observer_) observer_(shadow_ray, true);
    ++stats->shadow_rays;
    // Most shadow rays reach the sky unblocked: one any-hit query settles those, also in scenes
    // with alpha; only blocked rays walk the surfaces to see whether alpha lets them through.
    if (!accel_.occluded(shadow_ray)) return 1.0f;
    if (!accel_.has_non_opaque_materials()) return 0.0f;
    // Walk through the surfaces along the ray; blended ones attenuate by (1 - alpha).
    Ray ray = shadow_ray;
    float tr = 1.0f;
    for (int layer = 0; layer < 64; ++layer) {
        SurfaceHit hit;
        if (!accel_.intersect(ray, &hit)) return tr;
        const Material& m = *hit.material;
        if (m.alpha_mode == AlphaMode::Opaque) return 0.0f;
        float alpha = surface_alpha(hit);
        if (m.alpha_mode == AlphaMode::Mask) {
            if (alpha >= m.alpha_cutoff) return 0.0f;
        } else {
            tr *= 1 - clamp(alpha, 0.0f, 1.0f);
            if (tr <= 0) return 0.0f;
        }
        ray.tmin = hit.t * (1 + 1e-5f) + 1e-5f;
        ++stats->shadow_rays;
    }
    return tr;
}

Color PathIntegrator::trace(const Ray& camera_ray_in, Rng& rng, RenderStats* stats) const {
    Color L = Color::Zero(), beta = Color::Ones();
    Ray ray = camera_ray_in;
    float prev_bsdf_pdf = 0;  // 0 at the camera: directly visible sky gets full weight
    const bool use_light = settings_.strategy != LightStrategy::BsdfOnly;
    const bool use_bsdf_hits = settings_.strategy != LightStrategy::LightOnly;

    for (int depth = 0;; ++depth) {
        SurfaceHit hit;
        bool found = false;
        for (int layer = 0; layer < 64; ++layer) {
            if (observer_) observer_(ray, false);
            found = accel_.intersect(ray, &hit);
            if (!found || !passes_through(hit, rng.uniform())) break;
            ray.tmin = hit.t * (1 + 1e-5f) + 1e-5f;  // continue through the transparent surface
            ++stats->extension_rays;
        }
        if (!found) {
            Vec3 w = ray.direction.normalized();
            if (depth == 0) {
                L += beta * light_.radiance_filtered(w);
                break;
            }
            Color le = light_.radiance(w);
            if (use_bsdf_hits) {
                float weight = settings_.strategy == LightStrategy::Mis ? power_heuristic(prev_bsdf_pdf, light_.pdf(w))
                                                                        : 1.0f;
                L += beta * le * weight;
            }
            break;
        }

        ShadingPoint sp = evaluate_material(accel_.scene(), hit, -ray.direction.normalized());
        L += beta * sp.emission;  // emitters are reached by BSDF sampling only
        if (depth >= settings_.max_depth) break;

        MetalRoughBsdf bsdf(sp.base_color, sp.metallic, sp.roughness, sp.specular);
        Vec3 wo = sp.to_local(-ray.direction.normalized());
        if (wo.z() <= 0) break;

        // Next-event estimation of the sky (and ground).
        if (use_light) {
            float uc = rng.uniform();
            Vec2 ul = rng.uniform2();
            EnvLightSample ls;
            if (light_.sample(uc, ul, &ls) && sp.geometric_normal.dot(ls.wi) > 0) {
                Vec3 wi = sp.to_local(ls.wi);
                Color f = bsdf.eval(wo, wi);
                if (wi.z() > 0 && (f > 0).any()) {
                    Ray shadow;
                    shadow.origin = offset_ray_origin(hit.position, sp.geometric_normal, ls.wi);
                    shadow.direction = ls.wi;
                    float tr = transmittance(shadow, stats);
                    if (tr > 0) {
                        float weight = settings_.strategy == LightStrategy::Mis
                                           ? power_heuristic(ls.pdf, bsdf.pdf(wo, wi))
                                           : 1.0f;
                        L += beta * f * (wi.z() * tr * weight / ls.pdf) * ls.radiance;
                    }
                }
            }
        } else {
            rng.uniform(), rng.uniform(), rng.uniform();  // keep streams aligned across strategies
        }

        // Continue the path by sampling the BSDF.
        float ulobe = rng.uniform();
        Vec2 ub = rng.uniform2();
        BsdfSample bs;
        if (!bsdf.sample(wo, ulobe, ub, &bs)) break;
        Vec3 wi_world = sp.to_world(bs.wi);
        if (sp.geometric_normal.dot(wi_world) <= 0) break;  // below the true surface: no light leaks
        beta *= bs.f * (bs.wi.z() / bs.pdf);
        prev_bsdf_pdf = bs.pdf;

        if (depth + 1 >= settings_.rr_start_depth) {
            float q = std::max(0.05f, 1 - beta.maxCoeff());
            if (rng.uniform() < q) break;
            beta /= 1 - q;
        }
        if (!(beta.maxCoeff() > 0) || !beta.allFinite()) break;
        ray.origin = offset_ray_origin(hit.position, sp.geometric_normal, wi_world);
        ray.direction = wi_world;
        ray.tmin = 0;
        ray.tmax = std::numeric_limits<float>::infinity();
        ++stats->extension_rays;
    }
    return L;
}

RenderResult PathIntegrator::render(const Camera& camera) const {
    const int w = settings_.width, h = settings_.height, ts = settings_.tile_size;
    RenderResult result;
    result.color = Image(w, h, 3);
    if (settings_.compute_variance) result.variance = Image(w, h, 3);
    const float tan_half = std::tan(camera.yfov / 2);
    const float aspect = float(w) / h;  // the image decides; glTF aspectRatio only matters to rasterisers
    const int tiles_x = (w + ts - 1) / ts, tiles_y = (h + ts - 1) / ts;
    ProgressBar progress(tiles_x * tiles_y, "render", settings_.quiet);
    std::atomic<uint64_t> camera_rays{0}, extension_rays{0}, shadow_rays{0};
    auto start = std::chrono::steady_clock::now();

    tbb::parallel_for(0, tiles_x * tiles_y, [&](int tile) {
        RenderStats stats;
        int x0 = (tile % tiles_x) * ts, y0 = (tile / tiles_x) * ts;
        for (int y = y0; y < std::min(y0 + ts, h); ++y)
            for (int x = x0; x < std::min(x0 + ts, w); ++x) {
                Rng rng(mix_bits(settings_.seed * 0x9E3779B97F4A7C15ULL + 1), uint64_t(y) * w + x);
                Eigen::Array3d sum = Eigen::Array3d::Zero(), sum2 = Eigen::Array3d::Zero();
                for (int s = 0; s < settings_.spp; ++s) {
                    Vec2 jitter = rng.uniform2();
                    Ray ray = camera_ray(camera, tan_half, aspect, x + jitter.x(), y + jitter.y());
                    ++stats.camera_rays;
                    Color c = trace(ray, rng, &stats);
                    if (!c.allFinite()) c = Color::Zero();  // never let one bad path poison a pixel
                    Eigen::Array3d cd = c.cast<double>();
                    sum += cd;
                    sum2 += cd * cd;
                }
                Eigen::Array3d mean = sum / settings_.spp;
                for (int k = 0; k < 3; ++k) result.color.at(x, y, k) = float(mean[k]);
                if (settings_.compute_variance && settings_.spp > 1) {
                    Eigen::Array3d var = (sum2 / settings_.spp - mean * mean) *
                                         (double(settings_.spp) / (settings_.spp - 1));
                    for (int k = 0; k < 3; ++k)
                        result.variance.at(x, y, k) = float(std::max(0.0, var[k]) / settings_.spp);
                }
            }
        camera_rays += stats.camera_rays, extension_rays += stats.extension_rays, shadow_rays += stats.shadow_rays;
        progress.advance();
    });
    progress.finish();
    result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    result.stats.camera_rays = camera_rays, result.stats.extension_rays = extension_rays;
    result.stats.shadow_rays = shadow_rays;
    return result;
}

}  // namespace dynsky
