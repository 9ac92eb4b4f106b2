#include "sky/clear_sky.h"

#include <array>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <sstream>

#include "sky/fisheye.h"
#include "util/error.h"

namespace dynsky {

namespace {

// A sun below the horizon is raised to it, keeping its azimuth (north if it is at the nadir).
Vec3d raise_to_horizon(const Vec3d& sun) {
    if (sun.y() >= 0) return sun;
    Vec3d flat(sun.x(), 0.0, sun.z());
    double n = flat.norm();
    return n > 1e-12 ? Vec3d(flat / n) : Vec3d(0, 0, -1);
}

}  // namespace

void validate_clear_sky_params(const ClearSkyParams& params) {
    validate_hosek_wilkie_range(params.turbidity, params.ground_albedo);
    const Vec3d& s = params.sun_direction;
    if (!s.allFinite() || !(s.norm() > 1e-9)) throw Error("the sun direction must be a finite, non-zero vector");
}

double twilight_factor(double depression_deg) {
    const double d = std::clamp(depression_deg, 0.0, 18.0);
    return std::pow(10.0, d <= 12 ? -0.43 * d : -0.43 * 12 - 0.175 * (d - 12));
}

double ClearSkyModel::model_elevation(const Vec3d& sun) { return std::asin(std::clamp(sun.y(), 0.0, 1.0)); }

ClearSkyModel::ClearSkyModel(const ClearSkyParams& params, bool warn)
    : params_((validate_clear_sky_params(params), params)),
      sun_(params.sun_direction.normalized()),
      model_sun_(raise_to_horizon(sun_)),
      clamped_(sun_.y() < 0),
      model_(params.turbidity, params.ground_albedo, model_elevation(sun_)) {
    if (clamped_) twilight_ = float(twilight_factor(-std::asin(sun_.y()) * 180 / kPiD));
    // Said once per run: compare and animate make a clear sky per frame (the same line 4-5 times).
    static std::atomic<bool> said{false};
    if (warn && clamped_ && !said.exchange(true))
        std::fprintf(stderr, "dynsky: warning: %s\n", clamp_warning().c_str());
}

std::string ClearSkyModel::clamp_warning() const {
    if (!clamped_) return "";
    std::ostringstream s;
    s.precision(3);
    s << std::fixed << "the sun is " << -std::asin(sun_.y()) * 180 / kPiD
      << " deg below the horizon, outside the Hosek-Wilkie model's 0..90 deg: the sky is the sunset's (the sun at the "
         "horizon) dimmed for twilight by "
      << std::scientific << std::setprecision(1) << twilight_ << " (its colours stay the sunset's; no stars or moon)";
    return s.str();
}

Color ClearSkyModel::sky_radiance(const Vec3d& w_in) const {
    double n = w_in.norm();
    if (!(n > 0)) return Color::Zero();
    Vec3d w = w_in / n;
    if (w.y() < 0) return Color::Zero();
    double cos_gamma = std::clamp(w.dot(model_sun_), -1.0, 1.0);
    return twilight_ * model_.sky_radiance_rgb(w.y(), std::acos(cos_gamma), cos_gamma);
}

Color ClearSkyModel::sun_radiance(const Vec3d& w_in) const {
    if (!params_.sun_disc) return Color::Zero();
    double n = w_in.norm();
    if (!(n > 0)) return Color::Zero();
    Vec3d w = w_in / n;
    if (w.y() < 0) return Color::Zero();
    // atan2 of |cross| and dot keeps precision at the sub-degree angles of the disc.
    double gamma = std::atan2(w.cross(sun_).norm(), w.dot(sun_));
    return model_.solar_radiance_rgb(gamma);
}

Color ClearSkyModel::sun_irradiance() const { return params_.sun_disc ? model_.solar_irradiance_rgb() : Color::Zero(); }

void ClearSkyModel::splat_sun_disc(int n, const std::function<void(int, int, const Color&)>& add) const {
    const Vec3d& s = sun_direction();
    Vec3d t = (std::abs(s.x()) < 0.9 ? Vec3d::UnitX() : Vec3d::UnitY()).cross(s).normalized();
    Vec3d b = s.cross(t);
    const double radius_px = kHosekWilkieSolarRadius / (kPiD / n);
    if (radius_px >= 2) {
        // Resolved (N of about 1400 and more): each pixel takes its mean disc radiance over an 8 x 8
        // grid of directions in it. Splatted, the pixels caught unequal numbers of the rings' samples
        // and the limb-darkened disc came out speckled (37 % from pixel to pixel within 0.1 degree of
        // the centre at 4096 px).
        double cx, cy;
        fisheye::pixel_from_direction(s, n, &cx, &cy);
        const int reach = int(std::ceil(radius_px)) + 2;
        constexpr int kGrid = 8;
        std::vector<std::pair<std::array<int, 2>, Color>> pixels;
        Color total = Color::Zero();
        for (int j = int(std::floor(cy)) - reach; j <= int(std::ceil(cy)) + reach; ++j)
            for (int i = int(std::floor(cx)) - reach; i <= int(std::ceil(cx)) + reach; ++i) {
                if (i < 0 || j < 0 || i >= n || j >= n) continue;
                const double omega = fisheye::pixel_solid_angle(i, j, n);
                if (!(omega > 0)) continue;
                Color sum = Color::Zero();
                for (int b = 0; b < kGrid; ++b)
                    for (int a = 0; a < kGrid; ++a) {
                        const Vec3d w = fisheye::direction_from_pixel(i - 0.5 + (a + 0.5) / kGrid,
                                                                      j - 0.5 + (b + 0.5) / kGrid, n);
                        if (w.y() < 0) continue;
                        const double gamma = std::atan2(w.cross(s).norm(), w.dot(s));
                        if (gamma < kHosekWilkieSolarRadius) sum += model().solar_radiance_rgb(gamma);
                    }
                if (sum.maxCoeff() <= 0) continue;
                const Color mean = sum / float(kGrid * kGrid);
                pixels.push_back({{i, j}, mean});
                total += mean * float(omega);
            }
        // The grid's sum is within a fraction of a percent of the disc's irradiance; a disc whole
        // above the horizon is brought to it exactly, as the splat is.
        const double elevation = std::asin(std::clamp(s.y(), -1.0, 1.0));
        Color factor = Color::Ones();
        if (elevation > kHosekWilkieSolarRadius + kPiD / n)
            for (int c = 0; c < 3; ++c)
                if (total[c] > 0) factor[c] = model().solar_irradiance_rgb()[c] / total[c];
        for (const auto& [ij, radiance] : pixels) add(ij[0], ij[1], radiance.cwiseProduct(factor));
        return;
    }
    const int rings = std::max(16, int(std::ceil(5 * radius_px)));
    const int sectors = std::max(32, int(std::ceil(4 * kPiD * radius_px)));
    const double sin_r = std::sin(kHosekWilkieSolarRadius);
    for (int r = 0; r < rings; ++r) {
        double s0 = std::sqrt(double(r) / rings), s1 = std::sqrt(double(r + 1) / rings);
        Color share = model().solar_irradiance_rgb(s0, s1) / float(sectors);
        double gamma = std::asin(std::sqrt(0.5 * (s0 * s0 + s1 * s1)) * sin_r);
        for (int k = 0; k < sectors; ++k) {
            double phi = 2 * kPiD * (k + 0.5) / sectors;
            Vec3d w = std::cos(gamma) * s + std::sin(gamma) * (std::cos(phi) * t + std::sin(phi) * b);
            double u, v;
            if (!fisheye::uv_from_direction(w, &u, &v)) continue;  // below the horizon
            int i = 0, j = 0;
            double omega = 0;
            // A rim pixel whose centre is outside the disc holds no sky: the sample goes to the
            // nearest pixel inwards that does (a sun whole above the horizon lost 90 % of its light
            // at 64 px 0.65 degrees up, all of it 0.3 degrees up).
            const double r = std::hypot(u, v);
            for (int step = 0; step < 6 && omega <= 0; ++step) {
                const double inwards = r > 0 ? std::max(0.0, r - step / double(n)) / r : 1.0;
                i = std::clamp(int(std::floor((u * inwards + 1) / 2 * n)), 0, n - 1);
                j = std::clamp(int(std::floor((v * inwards + 1) / 2 * n)), 0, n - 1);
                omega = fisheye::pixel_solid_angle(i, j, n);
            }
            if (omega <= 0) continue;
            add(i, j, share / float(omega));
        }
    }
}

SkyImage make_clear_sky(const ClearSkyParams& params, int resolution, bool warn) {
    if (resolution < 1 || resolution > 32768)
        throw Error("sky resolution " + std::to_string(resolution) + " is not in 1..32768 pixels");
    ClearSkyModel model(params, warn);
    const int n = resolution;
    SkyImage sky(n);

    tbb::parallel_for(tbb::blocked_range<int>(0, n), [&](const tbb::blocked_range<int>& rows) {
        for (int j = rows.begin(); j != rows.end(); ++j) {
            for (int i = 0; i < n; ++i) {
                Vec2 uv = fisheye::pixel_center_uv(i, j, n);
                if (uv.squaredNorm() > 1.0f) continue;
                Vec3d w = fisheye::direction_from_uv(double(uv.x()), double(uv.y()));
                sky.set_pixel(i, j, model.sky_radiance(w));
            }
        }
    });

    if (params.sun_disc)
        model.splat_sun_disc(n, [&](int i, int j, const Color& c) { sky.set_pixel(i, j, sky.pixel(i, j) + c); });

    sky.sun_direction = model.sun_direction().cast<float>();
    std::ostringstream source;
    source << "hosek-wilkie turbidity=" << params.turbidity << " albedo=" << params.ground_albedo
           << (params.sun_disc ? "" : " no-sun");
    sky.source = source.str();
    sky.units = kAbsoluteRadiance;
    return sky;
}

Color clear_sky_radiance(const ClearSkyParams& params, const Vec3d& direction) {
    static std::atomic<bool> warned{false};
    ClearSkyModel model(params, false);
    if (model.elevation_clamped() && !warned.exchange(true))
        std::fprintf(stderr, "dynsky: warning: %s\n", model.clamp_warning().c_str());
    return model.radiance(direction);
}

}  // namespace dynsky
