// The Hosek-Wilkie analytic sky (SIGGRAPH 2012) and solar radiance function (IEEE CG&A 2013), from
// the authors' v1.4a tables shipped in sky/data/hosek-wilkie (3-clause BSD, see LICENSE there;
// FORMAT.md explains the layout).
//
// Units. The RGB sky dataset holds, per channel, the spectral sky radiance integrated against the
// CIE 1931 colour-matching functions taken to linear Rec.709 primaries:
//     RGB = M_709 * integral L(lambda) (x_bar, y_bar, z_bar)(lambda) d lambda      [W m^-2 sr^-1]
// (so luminance in cd m^-2 is 683 * (0.2126 R + 0.7152 G + 0.0722 B)). A clear zenith of ~7 gives
// ~5 kcd m^-2 and the sky ~15 klux on the ground, as measured skies do, which fixes this reading;
// renderers that want per-nanometre "average spectral radiance" (pbrt-v4's RGB, Mitsuba 3's sunsky)
// divide by the integral of y_bar, 106.857 nm. The solar function is spectral, W m^-2 sr^-1 nm^-1
// in 11 bands (320..720 nm); we convert it with the same integral (CIE 1931 2-degree table, 5 nm,
// sky/data/cie) so sun and sky share one unit. Mitsuba 3 does the same thing with a fitted constant
// (SPEC_TO_RGB_SUN_CONV = 467.07 over an 11-band mean, i.e. ~42.5 nm per band).
//
// Range: turbidity 1..10, ground albedo 0..1, sun elevation 0..90 degrees. Elevations below 0 are
// out of the model's range: callers clamp (sky/clear_sky.h does, with a warning).
//
// Solar disc: the model's own radius, 0.51/2 = 0.255 degrees (the real sun's mean radius is
// 0.2666 deg; the model's solar radiance was fitted with the smaller disc, so its irradiance,
// radiance times this disc, is the model's direct irradiance).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "util/math.h"

namespace dynsky {

constexpr int kHosekWilkieBands = 11;                                // 320, 360, ..., 720 nm
constexpr double kHosekWilkieSolarRadius = 0.51 / 2 * kPiD / 180.0;  // radians

// The tables, as read from sky/data/hosek-wilkie and sky/data/cie.
struct HosekWilkieData {
    std::array<std::vector<double>, 3> sky_params;             // datasetRGB1..3: 2 x 10 x 6 x 9
    std::array<std::vector<double>, 3> sky_radiance;           // datasetRGBRad1..3: 2 x 10 x 6
    std::array<std::vector<double>, kHosekWilkieBands> solar;  // solarDatasetNNN: 10 x 45 x 4
    std::array<std::array<double, 6>, kHosekWilkieBands> limb_darkening;
    // CIE 1931 2-degree colour-matching functions, 5 nm steps from cie_start_nm.
    double cie_start_nm = 360, cie_step_nm = 5;
    std::vector<Eigen::Vector3d> cie_xyz;
};

// Reads the tables from a folder holding rgb.txt and solar_spectral.txt, and a CIE CSV file.
// Throws dynsky::Error naming the file and the problem (missing section, wrong count, bad number).
HosekWilkieData load_hosek_wilkie_data(const std::string& folder, const std::string& cie_csv);

// The shipped tables (data_path("sky/data/...")), loaded once, thread-safe.
const HosekWilkieData& hosek_wilkie_data();

// Throws dynsky::Error if turbidity is outside [1, 10] or albedo outside [0, 1].
void validate_hosek_wilkie_range(double turbidity, double albedo);

// XYZ -> linear Rec.709 RGB (D65, IEC 61966-2-1 primaries).
Eigen::Matrix3d xyz_to_rec709();

// The model configured for one turbidity, albedo and sun elevation (radians, in [0, pi/2]).
class HosekWilkieSky {
  public:
    HosekWilkieSky(double turbidity, double albedo, double sun_elevation,
                   const HosekWilkieData& data = hosek_wilkie_data());

    // Sky radiance of one channel (0 R, 1 G, 2 B) for view zenith angle theta and angle gamma
    // between view and sun, radians: the reference implementation's
    // arhosek_tristim_skymodel_radiance. W m^-2 sr^-1 (see the file comment).
    double sky_radiance(int channel, double theta, double gamma) const;
    // All three channels, from cos(theta), gamma and cos(gamma) (the hot path of image making).
    // cos_theta is clamped to [0, 1]; negative results (the fit dips below 0 in corners) become 0.
    Color sky_radiance_rgb(double cos_theta, double gamma, double cos_gamma) const;

    // Direct solar spectral radiance, W m^-2 sr^-1 nm^-1, for wavelength 320..720 nm at angle
    // gamma from the sun's centre (limb darkened), 0 outside the disc; sky not included. Matches
    // the reference arhosekskymodel_solar_radiance_internal2 at this state's sun elevation.
    double solar_spectral_radiance(double wavelength_nm, double gamma) const;
    // The same integrated to linear Rec.709 RGB, W m^-2 sr^-1 (the sky's unit). A low sun is
    // redder than Rec.709 can hold (negative blue): such colours are desaturated towards the grey
    // of the same luminance until no channel is negative, so the luminance is exact.
    Color solar_radiance_rgb(double gamma) const;
    // Direct normal irradiance from the whole disc, W m^-2 in the same unit (integral of
    // solar_radiance_rgb over the disc's solid angle).
    Color solar_irradiance_rgb() const;
    // Same over the ring sin(gamma)/sin(R) in [s0, s1] of the disc (exact integral of the
    // limb-darkening polynomial), for energy-conserving splats of the disc into images.
    Color solar_irradiance_rgb(double s0, double s1) const;

    double turbidity() const { return turbidity_; }
    double albedo() const { return albedo_; }
    double sun_elevation() const { return elevation_; }

  private:
    double turbidity_, albedo_, elevation_;
    double config_[3][9];
    double scale_[3];
    std::array<double, kHosekWilkieBands> solar_centre_;  // disc-centre radiance per band (no limb darkening)
    const HosekWilkieData* data_;
    // solar_radiance_rgb(gamma) = sum_j rgb_limb_[j] mu^j, mu the limb-darkening cosine.
    std::array<Eigen::Array3d, 6> rgb_limb_;
};

}  // namespace dynsky
