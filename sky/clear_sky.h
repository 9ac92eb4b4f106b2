// Clear skies: the Hosek-Wilkie sky and sun (sky/hosek_wilkie.h) as canonical fisheye images.
//
// Radiance unit: W m^-2 sr^-1, linear Rec.709 RGB, each channel the spectral radiance integrated
// against the CIE 1931 colour-matching functions (luminance in cd m^-2 = 683 * Y). Sky and sun
// share it. See sky/hosek_wilkie.h and docs/sky.md.
//
// Sun below the horizon: the model holds for sun elevations 0..90 degrees only. A lower sun is
// clamped: the sky is evaluated with the sun raised to the horizon (same azimuth), dimmed by
// twilight_factor (the clear sky's illuminance through twilight: a decade per 2.3 degrees to
// nautical dusk, then slower to a starlit floor at 18 degrees), a warning goes to stderr, and the
// disc stays at its true place (so it is hidden once fully below the horizon). The colours stay
// the sunset's: no twilight blue, no stars.
#pragma once

#include <functional>
#include <string>

#include "sky/hosek_wilkie.h"
#include "sky/sky_image.h"
#include "util/math.h"

namespace dynsky {

struct ClearSkyParams {
    Vec3d sun_direction = Vec3d::UnitY();  // world frame (CONVENTIONS.md), towards the sun; normalised here
    double turbidity = 3.0;                // 1..10 (Linke-like: 2 very clear, 3 clear, 6+ hazy)
    double ground_albedo = 0.3;            // 0..1, the model's grey ground
    bool sun_disc = true;                  // include the solar disc (radius 0.255 deg) with limb darkening
};

// Throws dynsky::Error for out-of-range turbidity/albedo or a zero / non-finite sun direction.
void validate_clear_sky_params(const ClearSkyParams& params);

// The sky's brightness with the sun `depression_deg` below the horizon, relative to the sunset's:
// 1 at 0; log10 falls 0.43 per degree to 12 degrees (sunset ~10^3 lx, civil dusk at 6 degrees a
// few lux, nautical at 12 ~10^-2 lx: the US Naval Observatory's clear-sky table), 0.175 per degree
// to 18, then stays (starlight, ~10^-3 lx). A sky held at sunset lit a night scene at 2400 lx.
double twilight_factor(double depression_deg);

// The model configured once for many lookups (thread-safe to read).
class ClearSkyModel {
  public:
    // Validates; clamps a sun below the horizon (see the file comment). If warn, prints the clamp
    // warning on stderr.
    explicit ClearSkyModel(const ClearSkyParams& params, bool warn = true);

    // Sky only (no disc), 0 for directions below the horizon. w need not be normalised.
    Color sky_radiance(const Vec3d& w) const;
    // The solar disc only (0 outside it, below the horizon, or without sun_disc).
    Color sun_radiance(const Vec3d& w) const;
    Color radiance(const Vec3d& w) const { return sky_radiance(w) + sun_radiance(w); }
    // Direct normal irradiance from the whole disc, W m^-2 (0 without sun_disc).
    Color sun_irradiance() const;
    // The disc as fisheye pixels of an N x N sky, conserving its energy: equal-area rings of the
    // limb-darkened disc, each ring's irradiance split over sectors, each sector's share added as
    // radiance (share / pixel solid angle) to the pixel holding it; ~0.2-pixel spacing at any N.
    // Calls add(i, j, radiance) per sector above the horizon (a pixel may come several times).
    void splat_sun_disc(int n, const std::function<void(int, int, const Color&)>& add) const;

    const Vec3d& sun_direction() const { return sun_; }  // true sun, unit
    bool elevation_clamped() const { return clamped_; }
    std::string clamp_warning() const;  // "" when not clamped
    const HosekWilkieSky& model() const { return model_; }
    const ClearSkyParams& params() const { return params_; }

  private:
    static double model_elevation(const Vec3d& sun);
    ClearSkyParams params_;
    Vec3d sun_, model_sun_;
    bool clamped_ = false;
    float twilight_ = 1;  // twilight_factor of a sun below the horizon
    HosekWilkieSky model_;
};

// Canonical fisheye clear sky (N x N), radiance in W m^-2 sr^-1; sun_direction and source set.
// Pixels hold the sky at their centre; the disc is splatted conserving its energy: the sum over
// pixels of radiance * fisheye::pixel_solid_angle equals the disc's irradiance (the part above
// the horizon). Rows run in parallel (oneTBB). Throws dynsky::Error on bad parameters.
// warn: print the model's warning for a sun below the horizon (ClearSkyModel); callers making a
// sky per frame say it once themselves.
SkyImage make_clear_sky(const ClearSkyParams& params, int resolution, bool warn = true);

// Radiance of one direction: sky + sun disc (0 below the horizon). Builds the model each call; for
// many lookups use ClearSkyModel. The below-horizon warning is printed once per process.
Color clear_sky_radiance(const ClearSkyParams& params, const Vec3d& direction);

}  // namespace dynsky
