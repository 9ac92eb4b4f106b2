#include "renderer/integrator.h"

#include <tbb/parallel_for.h>

#include <chrono>
#include <limits>
#include <sstream>

#include "renderer/bsdf.h"
#include "renderer/material_eval.h"
#include "renderer/sampling.h"
#include "util/error.h"
#include "util/interrupt.h"
#include "util/progress.h"

namespace dynsky {

Vec3 offset_ray_origin(const SurfaceHit& hit, const Vec3& n, const Vec3& w) {
    // The least positive float keeps a hit at the origin itself off its surface.
    const float d = std::max(hit.position_error * n.cwiseAbs().sum(), std::numeric_limits<float>::min());
    const Vec3 offset = d * n;
    return n.dot(w) < 0 ? Vec3(hit.position - offset) : Vec3(hit.position + offset);
}

AovSelection parse_aovs(const std::string& list) {
    AovSelection a;
    std::stringstream in(list);
    std::string item;
    while (std::getline(in, item, ',')) {
        if (item == "albedo") a.albedo = true;
        else if (item == "normal") a.normal = true;
        else if (item == "depth") a.depth = true;
        else if (item == "alpha") a.alpha = true;
        else if (item == "samples") a.sample_count = true;
        else if (!item.empty())
            throw Error("--aovs: unknown pass '" + item + "' (choose from albedo, normal, depth, alpha, samples)");
    }
    return a;
}

PixelRegion parse_region(const std::string& text, int width, int height) {
    std::vector<int> v;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) {
        size_t used = 0;
        int value = 0;
        try {
            value = std::stoi(item, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used == 0 || used != item.size())
            throw Error("--region: '" + item + "' is not an integer (want x0,y0,x1,y1)");
        v.push_back(value);
    }
    if (v.size() != 4) throw Error("--region '" + text + "': want four integers x0,y0,x1,y1");
    PixelRegion r{v[0], v[1], v[2], v[3]};
    if (r.x0 < 0 || r.y0 < 0 || r.x1 > width || r.y1 > height || r.empty())
        throw Error("--region " + text + ": must satisfy 0 <= x0 < x1 <= " + std::to_string(width) +
                    " and 0 <= y0 < y1 <= " + std::to_string(height) + " (pixels [x0, x1) x [y0, y1))");
    return r;
}

double pixel_relative_error(int n, double sum, double sum_squares) {
    if (n < 2) return std::numeric_limits<double>::infinity();
    double mean = sum / n;
    if (mean <= 0) return sum_squares > 0 ? std::numeric_limits<double>::infinity() : 0.0;
    double variance = std::max(0.0, (sum_squares / n - mean * mean) * (double(n) / (n - 1)));
    return std::sqrt(variance / n) / mean;
}

std::vector<double> adaptive_error_estimates(int width, int height, const std::vector<int>& n,
                                             const std::vector<double>& lum_sum, const std::vector<double>& lum_sum2,
                                             int radius) {
    const size_t count = size_t(width) * height;
    if (n.size() != count || lum_sum.size() != count || lum_sum2.size() != count)
        throw Error("adaptive_error_estimates: the statistics are not width x height");
    // Each pixel's mean and sample variance, then their sums over the box, row then column, each
    // summed afresh (a running or summed-area table would carry a sun pixel's 1e14 into the
    // differences of dark boxes far from it).
    std::vector<double> mean(count), var(count);
    for (size_t p = 0; p < count; ++p) {
        const int k = n[p];
        mean[p] = k > 0 ? lum_sum[p] / k : 0.0;
        var[p] = k > 1 ? std::max(0.0, (lum_sum2[p] / k - mean[p] * mean[p]) * (double(k) / (k - 1))) : 0.0;
    }
    auto box_sum = [&](const std::vector<double>& v) {
        std::vector<double> rows(count), out(count);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                double sum = 0;
                for (int i = std::max(0, x - radius); i < std::min(width, x + radius + 1); ++i)
                    sum += v[size_t(y) * width + i];
                rows[size_t(y) * width + x] = sum;
            }
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                double sum = 0;
                for (int j = std::max(0, y - radius); j < std::min(height, y + radius + 1); ++j)
                    sum += rows[size_t(j) * width + x];
                out[size_t(y) * width + x] = sum;
            }
        return out;
    };
    const std::vector<double> mean_sum = box_sum(mean), var_sum = box_sum(var);
    std::vector<double> out(count);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const size_t p = size_t(y) * width + x;
            const int x0 = std::max(0, x - radius), x1 = std::min(width, x + radius + 1);
            const int y0 = std::max(0, y - radius), y1 = std::min(height, y + radius + 1);
            const double pixels = double(x1 - x0) * (y1 - y0);
            const double m = mean_sum[p] / pixels, v = var_sum[p] / pixels;
            double around = 0.0;
            if (n[p] < 2) around = std::numeric_limits<double>::infinity();
            else if (m > 0) around = std::sqrt(v / n[p]) / m;
            else if (v > 0) around = std::numeric_limits<double>::infinity();
            out[p] = std::max(pixel_relative_error(n[p], lum_sum[p], lum_sum2[p]), around);
        }
    return out;
}

Image render_layers(const RenderResult& r) {
    const Image& c = r.color;
    std::vector<std::pair<const Image*, std::vector<std::string>>> parts = {{&c, {"R", "G", "B"}}};
    if (!r.alpha.empty()) parts.push_back({&r.alpha, {"A"}});
    if (!r.albedo.empty())
        parts.push_back({&r.albedo, {"Denoising Albedo.R", "Denoising Albedo.G", "Denoising Albedo.B"}});
    if (!r.normal.empty()) parts.push_back({&r.normal, {"Normal.X", "Normal.Y", "Normal.Z"}});
    if (!r.depth.empty()) parts.push_back({&r.depth, {"Depth.Z"}});
    if (!r.sample_count.empty()) parts.push_back({&r.sample_count, {"Sample Count.X"}});
    int channels = 0;
    for (const auto& p : parts) channels += p.first->channels;
    Image out(c.width, c.height, channels);
    out.metadata = c.metadata;
    out.origin_x = c.origin_x, out.origin_y = c.origin_y, out.full_width = c.full_width,
    out.full_height = c.full_height;
    int at = 0;
    for (const auto& [image, names] : parts) {
        for (int y = 0; y < c.height; ++y)
            for (int x = 0; x < c.width; ++x)
                for (int k = 0; k < image->channels; ++k) out.at(x, y, at + k) = image->at(x, y, k);
        out.channel_names.insert(out.channel_names.end(), names.begin(), names.end());
        at += image->channels;
    }
    return out;
}

// What a pixel accumulates over its samples beside the colour's sum, for the variance, the relative
// error (adaptive sampling) and the passes: only a render that asks for those keeps it.
struct PathIntegrator::PixelExtra {
    Eigen::Array3d sum2 = Eigen::Array3d::Zero();
    double lum_sum = 0, lum_sum2 = 0;
    Eigen::Array3d albedo = Eigen::Array3d::Zero(), normal = Eigen::Array3d::Zero();
    double alpha = 0;
    float depth = 1e10f;  // Cycles' depth of the sky
};

// Everything a pixel accumulates over its samples (kept between rounds of adaptive sampling). Small
// (56 bytes, not 152 with the extra inline): a tile sweeps 256 of them per sample.
struct PathIntegrator::PixelState {
    Rng rng;
    int n = 0;
    bool done = false;
    Eigen::Array3d sum = Eigen::Array3d::Zero();
    PixelExtra* extra = nullptr;
    PixelState(const Rng& r, PixelExtra* e) : rng(r), extra(e) {}
};

// sample_tile's buffers, one set per thread, reused from tile to tile (no allocation or zeroing
// per tile). Nothing in a tile waits on other TBB work, so a thread never runs two tiles at once.
struct PathIntegrator::TileScratch {
    std::vector<Ray> rays;
    std::vector<RTCRayHit> primary;
    std::vector<Vec3> sky_directions;  // of the camera rays that see the sky
    std::vector<Color> sky;            // and their radiance
};

PathIntegrator::PathIntegrator(const Accel& accel, const EnvLight& light, const RenderSettings& settings)
    : accel_(accel), light_(light), settings_(settings) {}

Ray PathIntegrator::camera_ray(const Camera& camera, float tan_half, float aspect, float px, float py) const {
    float x = (2 * px / settings_.width - 1) * tan_half * aspect;
    float y = (1 - 2 * py / settings_.height) * tan_half;
    Ray ray;
    if (camera.orthographic) {
        ray.origin = camera.camera_to_world * Vec3(x, y, 0);
        ray.direction = (camera.camera_to_world.linear() * Vec3(0, 0, -1)).normalized();
        return ray;
    }
    // Eigen's product with the 3x3 block of the 4x4 matrix is not vectorised: the same sums by
    // columns, in its order (a0 x + (a1 y + a2 z)), give the same bits.
    const Eigen::Matrix4f& m = camera.camera_to_world.matrix();
    ray.origin = m.col(3).head<3>();
    ray.direction = Vec3(m.col(0).head<3>() * x + (m.col(1).head<3>() * y - m.col(2).head<3>())).normalized();
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

bool PathIntegrator::passes_through(const SurfaceHit& hit, float u, bool camera_path) const {
    const Material& m = *hit.material;
    if (m.unlit && !camera_path) return true;  // unlit surfaces are seen by the camera only
    if (m.alpha_mode == AlphaMode::Opaque) return false;
    float alpha = surface_alpha(hit);
    if (m.alpha_mode == AlphaMode::Mask) return alpha < m.alpha_cutoff;
    return u >= alpha;  // Blend: stochastic transparency
}

namespace {

// The BSDF of a shading point, its roughnesses given (Filter Glossy may raise them); each layer
// set only when present, so a plain material runs the plain model bit for bit.
MetalRoughBsdf shading_bsdf(const ShadingPoint& sp, float roughness, float coat_roughness) {
    MetalRoughBsdf bsdf(sp.base_color, sp.metallic, roughness, sp.specular, sp.transmission);
    if (sp.ior != 1.5f) bsdf.set_ior(sp.ior);  // glTF's default IOR is the BSDF's own
    if ((sp.specular_color != 1.0f).any()) bsdf.set_specular_color(sp.specular_color);
    if (sp.transmission > 0) bsdf.set_transmission_tint(sp.transmission_tint);
    if (sp.clearcoat > 0) bsdf.set_clearcoat(sp.clearcoat, coat_roughness);
    if ((sp.sheen_color > 0).any()) bsdf.set_sheen(sp.sheen_color, sp.sheen_roughness);
    if (sp.anisotropy > 0) bsdf.set_anisotropy(sp.anisotropy);
    return bsdf;
}

}  // namespace

Color PathIntegrator::transmittance(const Ray& shadow_ray, RenderStats* stats) const {
    if (observer_) observer_(shadow_ray, RayKind::Shadow);
    ++stats->shadow_rays;
    // Most shadow rays reach the sky unblocked: one any-hit query settles those, also in scenes
    // with alpha or glass; only blocked rays walk the surfaces to see what lets them through.
    if (!accel_.occluded(shadow_ray)) return Color::Ones();
    if (!accel_.has_non_opaque_materials()) return Color::Zero();
    // Walk through the surfaces along the ray: blended ones pass 1 - alpha, transmissive ones what
    // their BSDF transmits (the same share trace_path's paths pass through them).
    Ray ray = shadow_ray;
    Color tr = Color::Ones();
    for (int layer = 0; layer < 64; ++layer) {
        SurfaceHit hit;
        if (!accel_.intersect(ray, &hit, false)) return tr;
        const Material& m = *hit.material;
        if (m.unlit) {  // seen by the camera only: light passes as if it were not there
            ray.tmin = hit.t * (1 + 1e-5f) + 1e-5f;
            ++stats->shadow_rays;
            continue;
        }
        // Of the light that meets the surface (alpha), what passes through it.
        Color through = Color::Zero();
        if (m.transmission > 0) {
            const ShadingPoint sp = evaluate_material(accel_.scene(), hit, -ray.direction.normalized());
            const MetalRoughBsdf bsdf = shading_bsdf(sp, sp.roughness, sp.clearcoat_roughness);
            through = bsdf.transmitted(sp.to_local(-ray.direction.normalized()));
        }
        if (m.alpha_mode == AlphaMode::Opaque) {
            tr *= through;
        } else {
            float alpha = surface_alpha(hit);
            if (m.alpha_mode == AlphaMode::Mask) {
                if (alpha >= m.alpha_cutoff) tr *= through;
            } else {
                alpha = clamp(alpha, 0.0f, 1.0f);
                tr *= (1 - alpha) + alpha * through;
            }
        }
        if (!(tr.maxCoeff() > 0)) return Color::Zero();
        ray.tmin = hit.t * (1 + 1e-5f) + 1e-5f;
        ++stats->shadow_rays;
    }
    return tr;
}

Color PathIntegrator::punctual_light(const ShadingPoint& sp, const MetalRoughBsdf& bsdf, const Vec3& wo,
                                     const SurfaceHit& hit, RenderStats* stats) const {
    Color sum = Color::Zero();
    for (const PunctualLight& light : accel_.scene().lights) {
        Vec3 wi_world;
        float distance = std::numeric_limits<float>::infinity();
        Color incident = light.intensity;  // W/m^2 arriving at normal incidence
        if (light.type == PunctualLight::Type::Directional) {
            wi_world = -light.direction;
        } else {
            const Vec3 to_light = light.position - hit.position;
            const float d2 = to_light.squaredNorm();
            if (!(d2 > 0)) continue;
            distance = std::sqrt(d2);
            wi_world = to_light / distance;
            float falloff = 1 / d2;
            // The extension's recommended window: smooth to zero at range, inverse square inside.
            if (light.range > 0) {
                const float x = distance / light.range, x2 = x * x;
                falloff *= std::clamp(1 - x2 * x2, 0.0f, 1.0f);
            }
            if (light.type == PunctualLight::Type::Spot) {
                const float cd = light.direction.dot(-wi_world);
                const float scale = 1 / std::max(1e-3f, light.cos_inner - light.cos_outer);
                const float a = std::clamp((cd - light.cos_outer) * scale, 0.0f, 1.0f);
                falloff *= a * a;
            }
            incident *= falloff;
        }
        if (!(incident.maxCoeff() > 0) || sp.geometric_normal.dot(wi_world) <= 0) continue;
        const Vec3 wi = sp.to_local(wi_world);
        if (wi.z() <= 0) continue;
        const Color f = bsdf.eval(wo, wi);
        if (!(f > 0).any()) continue;
        Ray shadow;
        shadow.origin = offset_ray_origin(hit, sp.geometric_normal, wi_world);
        shadow.direction = wi_world;
        // Up to the light, not past it.
        if (std::isfinite(distance)) shadow.tmax = distance * (1 - 1e-4f);
        const Color tr = transmittance(shadow, stats);
        sum += f * tr * incident * wi.z();
    }
    return sum;
}

SamplePattern parse_sample_pattern(const std::string& name) {
    if (name == "random") return SamplePattern::Random;
    if (name == "sobol") return SamplePattern::ZSobol;
    throw Error("--sampler-pattern '" + name + "': choose random or sobol");
}

Color PathIntegrator::trace(const Ray& ray, Rng& rng, RenderStats* stats, FirstHit* first_hit) const {
    return trace_path(ray, rng, stats, first_hit);
}

template <class Sampler>
Color PathIntegrator::trace_path(const Ray& camera_ray_in, Sampler& rng, RenderStats* stats, FirstHit* first_hit,
                                 const RTCRayHit* primary) const {
    Color L = Color::Zero(), beta = Color::Ones();
    Ray ray = camera_ray_in;
    float prev_bsdf_pdf = 0;  // 0 at the camera: directly visible sky gets full weight
    const bool use_light = settings_.strategy != LightStrategy::BsdfOnly;
    const bool use_bsdf_hits = settings_.strategy != LightStrategy::LightOnly;
    // Smallest BSDF pdf along the path so far (Filter Glossy); none before the first bounce.
    float min_pdf = std::numeric_limits<float>::infinity();
    // Adds light that scattered at `scatterings` surfaces on its way; indirect light (two or more)
    // is clamped, as Cycles' Clamp Indirect does, to a sum of RGB of at most clamp_indirect.
    const float clamp = settings_.clamp_indirect;
    auto add = [&](Color c, int scatterings) {
        if (clamp > 0 && scatterings >= 2) {
            float sum = c.abs().sum();
            if (sum > clamp) c *= clamp / sum;
        }
        L += c;
    };

    int passes = 0;           // surfaces passed straight through (alpha, glass) on the whole path
    bool camera_path = true;  // no scattering, and no glass passed, since the camera (unlit surfaces)
    for (int depth = 0;; ++depth) {
        SurfaceHit hit;
        bool found = false;
        for (int layer = 0; layer < 64; ++layer) {
            if (observer_) observer_(ray, primary ? RayKind::Camera : RayKind::Continuation);
            found = primary ? accel_.surface_hit(ray, *primary, &hit, false) : accel_.intersect(ray, &hit, false);
            primary = nullptr;  // the camera ray's first intersection only
            if (!found || !passes_through(hit, rng.uniform(), camera_path)) break;
            ray.tmin = hit.t * (1 + 1e-5f) + 1e-5f;  // continue through the transparent surface
            ++stats->extension_rays;
        }
        if (!found) {
            Vec3 w = ray.direction.normalized();
            if (depth == 0) {
                // With an alpha pass the sky seen from the camera is transparent (A = 0 there), as
                // Cycles' Film > Transparent: the colour is premultiplied by A, so an "over" on a
                // plate shows the plate. It still lights the scene.
                if (!settings_.aovs.alpha) L += beta * light_.radiance_filtered(w);
                break;
            }
            if (use_bsdf_hits) {
                float light_pdf;
                Color le = light_.radiance(w, &light_pdf);
                float weight = settings_.strategy == LightStrategy::Mis ? power_heuristic(prev_bsdf_pdf, light_pdf)
                                                                        : 1.0f;
                add(beta * le * weight, depth);
            }
            break;
        }

        ShadingPoint sp = evaluate_material(accel_.scene(), hit, -ray.direction.normalized());
        if (depth == 0 && first_hit) {
            first_hit->surface = true;
            first_hit->albedo = sp.base_color;
            first_hit->normal = sp.normal;
            first_hit->position = hit.position;
        }
        if (hit.material->unlit) {  // reached by a camera path only (passes_through): its colour, no more
            // As the ground is shown (albedo x E_sky / pi): baked lighting looks as bright as a
            // surface of that albedo in the open under this sky, and follows the sky's brightness.
            L += beta * sp.base_color * light_.sky_irradiance() * float(1 / kPi);
            break;
        }
        add(beta * sp.emission, depth);  // emitters are reached by BSDF sampling only
        if (depth >= settings_.max_depth) break;

        // Filter Glossy (Cycles): after a bounce of pdf p, roughen to GGX alpha >= sqrt(1 - p / R) / 2,
        // so a sharp reflection seen through a rough one does not carry the sun as a firefly.
        float roughness = sp.roughness, coat_roughness = sp.clearcoat_roughness;
        if (settings_.filter_glossy > 0) {
            float blur_pdf = min_pdf / settings_.filter_glossy;
            if (blur_pdf < 1) {
                const float floor = std::sqrt(0.5f * std::sqrt(1 - blur_pdf));
                roughness = std::max(roughness, floor), coat_roughness = std::max(coat_roughness, floor);
            }
        }
        MetalRoughBsdf bsdf = shading_bsdf(sp, roughness, coat_roughness);
        Vec3 wo = sp.to_local(-ray.direction.normalized());
        if (wo.z() <= 0) break;
        bsdf.set_wo(wo);

        // Thin-walled glass (KHR_materials_transmission): with the probability of what it transmits
        // (its largest channel), the path passes straight through, as through a blended surface: a
        // null scattering that keeps the last scattering's pdf for MIS, as shadow rays (transmittance)
        // pass the same share. Otherwise it scatters by the rest of the BSDF.
        if (sp.transmission > 0 && passes < 64) {
            const Color through = bsdf.transmitted(wo);
            const float p = std::min(1.0f, through.maxCoeff());
            if (p > 0 && rng.uniform() < p) {
                beta *= through / p;
                ray.tmin = hit.t * (1 + 1e-5f) + 1e-5f;
                ++passes, ++stats->extension_rays;
                camera_path = false;
                --depth;  // not a bounce
                continue;
            }
            if (p >= 1) break;  // nothing else left to scatter
            beta /= 1 - p;
        }

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
                    shadow.origin = offset_ray_origin(hit, sp.geometric_normal, ls.wi);
                    shadow.direction = ls.wi;
                    Color tr = transmittance(shadow, stats);
                    if (tr.maxCoeff() > 0) {
                        float weight = settings_.strategy == LightStrategy::Mis
                                           ? power_heuristic(ls.pdf, bsdf.pdf(wo, wi))
                                           : 1.0f;
                        add(beta * f * (wi.z() * tr * weight / ls.pdf) * ls.radiance, depth + 1);
                    }
                }
            }
        } else {
            rng.uniform(), rng.uniform(), rng.uniform();  // keep streams aligned across strategies
        }
        // Punctual lights (KHR_lights_punctual): delta lights no BSDF sample can hit, each one
        // sampled every bounce, whatever the strategy (no random numbers: streams unchanged).
        if (!accel_.scene().lights.empty()) add(beta * punctual_light(sp, bsdf, wo, hit, stats), depth + 1);

        // Continue the path by sampling the BSDF.
        float ulobe = rng.uniform();
        Vec2 ub = rng.uniform2();
        BsdfSample bs;
        if (!bsdf.sample(wo, ulobe, ub, &bs)) break;
        Vec3 wi_world = sp.to_world(bs.wi);
        if (sp.geometric_normal.dot(wi_world) <= 0) break;  // below the true surface: no light leaks
        beta *= bs.f * (bs.wi.z() / bs.pdf);
        camera_path = false;
        prev_bsdf_pdf = bs.pdf;
        min_pdf = std::min(min_pdf, bs.pdf);

        if (depth + 1 >= settings_.rr_start_depth) {
            float q = std::max(0.05f, 1 - beta.maxCoeff());
            if (rng.uniform() < q) break;
            beta /= 1 - q;
        }
        if (!(beta.maxCoeff() > 0) || !beta.allFinite()) break;
        if (use_bsdf_hits) light_.prefetch(wi_world);  // in cache by the time the ray escapes
        ray.origin = offset_ray_origin(hit, sp.geometric_normal, wi_world);
        ray.direction = wi_world;
        ray.tmin = 0;
        ray.tmax = std::numeric_limits<float>::infinity();
        ++stats->extension_rays;
    }
    return L;
}

void PathIntegrator::sample_tile(const Camera& camera, float tan_half, float aspect, const TilePixel* pixels, int n,
                                 int count, RenderStats* stats) const {
    if (n == 0) return;
    const bool features = settings_.aovs.any();
    const bool sobol = settings_.pattern == SamplePattern::ZSobol;
    std::vector<ZSobolSampler> zsobol(sobol ? size_t(n) : 0,
                                      ZSobolSampler(settings_.width, settings_.height, settings_.spp, settings_.seed));
    thread_local TileScratch scratch;
    if (scratch.rays.size() < size_t(n)) {
        scratch.rays.resize(size_t(n)), scratch.primary.resize(size_t(n));
        scratch.sky_directions.resize(size_t(n)), scratch.sky.resize(size_t(n));
    }
    Ray* rays = scratch.rays.data();
    RTCRayHit* primary = scratch.primary.data();
    const Vec3 forward = (camera.camera_to_world.linear() * Vec3(0, 0, -1)).normalized();
    for (int s = 0; s < count; ++s) {
        for (int p = 0; p < n; ++p) {
            PixelState* st = pixels[p].state;
            if (sobol) zsobol[size_t(p)].start(pixels[p].x, pixels[p].y, st->n);
            Vec2 jitter = sobol ? zsobol[size_t(p)].uniform2() : st->rng.uniform2();
            rays[p] = camera_ray(camera, tan_half, aspect, pixels[p].x + jitter.x(), pixels[p].y + jitter.y());
            Accel::setup_ray_hit(rays[p], &primary[p]);
        }
        accel_.intersect_coherent(primary, unsigned(n));
        // The hits' mesh records start loading together, not one cache miss per path.
        for (int p = 0; p < n; ++p) accel_.prefetch(primary[p]);
        // The sky seen directly (most camera samples), looked up together: what trace_path does for
        // it, which draws no random numbers. With an alpha pass it is transparent (trace_path): not
        // looked up.
        const bool sky_seen = !settings_.aovs.alpha;
        int misses = 0;
        for (int p = 0; p < n && sky_seen; ++p)
            if (primary[p].hit.geomID == RTC_INVALID_GEOMETRY_ID)
                scratch.sky_directions[size_t(misses++)] = rays[p].direction;
        light_.radiance_filtered(scratch.sky_directions.data(), misses, scratch.sky.data());
        const Color* sky = scratch.sky.data();
        for (int p = 0; p < n; ++p) {
            PixelState* st = pixels[p].state;
            ++stats->camera_rays;
            FirstHit first;
            FirstHit* fh = features ? &first : nullptr;
            const Ray& ray = rays[p];
            Color c;
            if (primary[p].hit.geomID == RTC_INVALID_GEOMETRY_ID) {
                if (observer_) observer_(ray, RayKind::Camera);
                c = sky_seen ? *sky++ : Color::Zero();
            } else {
                c = sobol ? trace_path(ray, zsobol[size_t(p)], stats, fh, &primary[p])
                          : trace_path(ray, st->rng, stats, fh, &primary[p]);
            }
            if (!c.allFinite()) c = Color::Zero();  // never let one bad path poison a pixel
            Eigen::Array3d cd = c.cast<double>();
            st->sum += cd;
            if (PixelExtra* e = st->extra) {
                e->sum2 += cd * cd;
                double lum = luminance(cd[0], cd[1], cd[2]);
                e->lum_sum += lum, e->lum_sum2 += lum * lum;
                if (features && first.surface) {
                    e->albedo += first.albedo.cast<double>();
                    e->normal += first.normal.cast<double>().array();
                    e->alpha += 1;
                    if (st->n == 0) e->depth = (first.position - camera.camera_to_world.translation()).dot(forward);
                }
            }
            ++st->n;
        }
    }
}

void PathIntegrator::store_pixel(const Camera&, const PixelState& st, int x, int y, RenderResult* result) const {
    const int n = st.n;
    Eigen::Array3d mean = st.sum / n;
    for (int k = 0; k < 3; ++k) result->color.at(x, y, k) = float(mean[k]);
    if (!st.extra) return;
    const PixelExtra& e = *st.extra;
    if (settings_.compute_variance && n > 1) {
        Eigen::Array3d var = (e.sum2 / n - mean * mean) * (double(n) / (n - 1));
        for (int k = 0; k < 3; ++k) result->variance.at(x, y, k) = float(std::max(0.0, var[k]) / n);
    }
    const AovSelection& a = settings_.aovs;
    for (int k = 0; k < 3; ++k) {
        if (a.albedo) result->albedo.at(x, y, k) = float(e.albedo[k] / n);
        if (a.normal) result->normal.at(x, y, k) = float(e.normal[k] / n);
    }
    if (a.depth) result->depth.at(x, y, 0) = e.depth;
    if (a.alpha) result->alpha.at(x, y, 0) = float(e.alpha / n);
    if (a.sample_count) result->sample_count.at(x, y, 0) = float(n);
    if (!result->relative_error.empty())
        result->relative_error.at(x, y, 0) = float(pixel_relative_error(n, e.lum_sum, e.lum_sum2));
}

RenderResult PathIntegrator::render(const Camera& camera) const {
    const int w = settings_.width, h = settings_.height, ts = settings_.tile_size;
    if (settings_.spp < 1) throw Error("render: spp must be at least 1");
    const PixelRegion region = settings_.region.empty() ? PixelRegion{0, 0, w, h} : settings_.region;
    if (region.x0 < 0 || region.y0 < 0 || region.x1 > w || region.y1 > h)
        throw Error("render: region outside the " + std::to_string(w) + "x" + std::to_string(h) + " image");
    const int rw = region.x1 - region.x0, rh = region.y1 - region.y0;
    RenderResult result;
    result.color = Image(rw, rh, 3);
    if (settings_.compute_variance) result.variance = Image(rw, rh, 3);
    const AovSelection& aovs = settings_.aovs;
    if (aovs.albedo) result.albedo = Image(rw, rh, 3);
    if (aovs.normal) result.normal = Image(rw, rh, 3);
    if (aovs.depth) result.depth = Image(rw, rh, 1);
    if (aovs.alpha) result.alpha = Image(rw, rh, 1);
    if (aovs.sample_count) result.sample_count = Image(rw, rh, 1);
    const bool adaptive = settings_.noise_threshold > 0;
    if (adaptive || settings_.compute_variance) result.relative_error = Image(rw, rh, 1);
    const bool keep_extra = !result.relative_error.empty() || aovs.any();  // the pixels' PixelExtra
    // tan(yfov / 2) for perspective cameras, the half height for orthographic ones.
    const float tan_half = camera.orthographic ? camera.ymag : std::tan(camera.yfov / 2);
    // The image decides; a glTF aspectRatio other than the image's is warned about when the camera
    // is chosen (frame/scene_spec.cpp), its vertical field of view kept.
    const float aspect = float(w) / h;
    const int tiles_x = (rw + ts - 1) / ts, tiles_y = (rh + ts - 1) / ts, tiles = tiles_x * tiles_y;
    // Rounds of samples when a pixel may stop early (adaptive) or the clock may stop the render.
    const bool by_rounds = adaptive || settings_.time_limit_seconds > 0 || settings_.stop_on_request;
    const int round_spp = by_rounds ? std::max(1, std::min(settings_.round_spp, settings_.spp)) : settings_.spp;
    const int max_rounds = (settings_.spp + round_spp - 1) / round_spp;
    ProgressBar progress(tiles * max_rounds, "render", settings_.quiet);
    progress.set_time_limit(settings_.time_limit_seconds);
    std::atomic<uint64_t> camera_rays{0}, extension_rays{0}, shadow_rays{0};
    auto start = std::chrono::steady_clock::now();
    const uint64_t pixel_seed = mix_bits(settings_.seed * 0x9E3779B97F4A7C15ULL + 1);
    auto pixel_rng = [&](int x, int y) { return Rng(pixel_seed, uint64_t(y) * w + x); };
    // Calls f(tile pixels, tile stats) for every tile, tiles in parallel.
    auto for_each_tile = [&](auto&& f) {
        tbb::parallel_for(0, tiles, [&](int tile) {
            RenderStats stats;
            int x0 = region.x0 + (tile % tiles_x) * ts, y0 = region.y0 + (tile / tiles_x) * ts;
            thread_local std::vector<TilePixel> pixels;  // reused, as TileScratch
            const int x1 = std::min(x0 + ts, region.x1), y1 = std::min(y0 + ts, region.y1);
            pixels.resize(size_t(x1 - x0) * (y1 - y0));
            TilePixel* out = pixels.data();
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x) *out++ = {x, y, nullptr};
            f(pixels, &stats);
            camera_rays += stats.camera_rays, extension_rays += stats.extension_rays;
            shadow_rays += stats.shadow_rays;
            progress.advance();
        });
    };

    if (!by_rounds) {
        for_each_tile([&](std::vector<TilePixel>& pixels, RenderStats* stats) {
            thread_local std::vector<PixelState> states;  // reused, as TileScratch
            thread_local std::vector<PixelExtra> extras;
            if (states.size() < pixels.size()) states.resize(pixels.size(), PixelState(Rng(0, 0), nullptr));
            if (keep_extra) extras.assign(pixels.size(), PixelExtra());
            for (size_t k = 0; k < pixels.size(); ++k)
                states[k] = PixelState(pixel_rng(pixels[k].x, pixels[k].y), keep_extra ? &extras[k] : nullptr);
            for (size_t k = 0; k < pixels.size(); ++k) pixels[k].state = &states[k];
            sample_tile(camera, tan_half, aspect, pixels.data(), int(pixels.size()), settings_.spp, stats);
            for (const TilePixel& p : pixels) store_pixel(camera, *p.state, p.x - region.x0, p.y - region.y0, &result);
        });
        result.rounds = 1;
    } else {
        std::vector<PixelState> states;
        std::vector<PixelExtra> extras(keep_extra ? size_t(rw) * rh : 0);
        states.reserve(size_t(rw) * rh);
        for (int y = region.y0; y < region.y1; ++y)
            for (int x = region.x0; x < region.x1; ++x)
                states.emplace_back(pixel_rng(x, y), keep_extra ? &extras[states.size()] : nullptr);
        const size_t count_px = size_t(rw) * rh;
        std::vector<double> estimate(adaptive ? count_px : 0, std::numeric_limits<double>::infinity());
        std::vector<int> n(adaptive ? count_px : 0);
        std::vector<double> lum_sum(n.size()), lum_sum2(n.size());
        int taken = 0;
        while (taken < settings_.spp) {
            const int count = std::min(round_spp, settings_.spp - taken);
            for_each_tile([&](std::vector<TilePixel>& pixels, RenderStats* stats) {
                std::vector<TilePixel> live;  // the pixels still taking samples
                for (TilePixel p : pixels) {
                    p.state = &states[size_t(p.y - region.y0) * rw + (p.x - region.x0)];
                    if (!p.state->done) live.push_back(p);
                }
                sample_tile(camera, tan_half, aspect, live.data(), int(live.size()), count, stats);
            });
            taken += count, ++result.rounds;
            long long active = 0;
            if (adaptive) {
                // Every pixel's estimate from the statistics of all (those stopped keep theirs).
                for (size_t k = 0; k < count_px; ++k)
                    n[k] = states[k].n, lum_sum[k] = states[k].extra->lum_sum, lum_sum2[k] = states[k].extra->lum_sum2;
                const std::vector<double> now = adaptive_error_estimates(rw, rh, n, lum_sum, lum_sum2,
                                                                         kAdaptiveNeighbourhoodRadius);
                for (size_t k = 0; k < count_px; ++k) {
                    if (states[k].done) continue;
                    estimate[k] = now[k];
                    if (now[k] < settings_.noise_threshold) states[k].done = true;
                    else ++active;
                }
            } else {
                active = (long long)count_px;  // a time limit alone: every pixel takes every round
            }
            if (active == 0) break;
            if (settings_.stop_on_request && stop_requested() && taken < settings_.spp) {
                result.stopped = true;
                break;
            }
            if (settings_.time_limit_seconds > 0 &&
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >=
                    settings_.time_limit_seconds)
                break;
        }
        tbb::parallel_for(0, rh, [&](int y) {
            for (int x = 0; x < rw; ++x) store_pixel(camera, states[size_t(y) * rw + x], x, y, &result);
        });
        if (adaptive)
            for (size_t k = 0; k < estimate.size(); ++k) result.relative_error.pixels[k] = float(estimate[k]);
    }
    progress.finish();
    result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    result.stats.camera_rays = camera_rays, result.stats.extension_rays = extension_rays;
    result.stats.shadow_rays = shadow_rays;
    if (!settings_.region.empty())  // each pass knows where it lies in the full image
        for (Image* im : {&result.color, &result.variance, &result.albedo, &result.normal, &result.depth, &result.alpha,
                          &result.sample_count, &result.relative_error})
            if (!im->empty())
                im->origin_x = region.x0, im->origin_y = region.y0, im->full_width = w, im->full_height = h;
    return result;
}

}  // namespace dynsky
