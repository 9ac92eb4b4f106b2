// The colour space of pixels read from files. Inside dynsky every radiance is linear Rec.709
// (sRGB primaries, D65 white; docs/sky.md). A file that says it holds other primaries (an EXR's
// `chromaticities`, the ACES container's AP0, an ACEScg render) is converted when it is read
// (sky/sky_image.h read_radiance_image); one that says nothing is taken as Rec.709, as OpenEXR
// itself reads a file without chromaticities.
#pragma once

#include <array>
#include <optional>
#include <string>

#include "util/math.h"

namespace dynsky {

// CIE xy of the red, green and blue primaries and of the white: rx ry gx gy bx by wx wy, the order
// of OpenEXR's `chromaticities` attribute.
using Chromaticities = std::array<float, 8>;

Chromaticities rec709_chromaticities();
Chromaticities aces_ap0_chromaticities();  // ACES2065-1 (the ACES container, SMPTE ST 2065-4)
Chromaticities aces_ap1_chromaticities();  // ACEScg

// Equal within 1e-3 in every coordinate (files round them differently).
bool same_chromaticities(const Chromaticities& a, const Chromaticities& b);

// "AP1 (ACEScg)", "AP0 (ACES2065-1)", "Rec.709", else the eight numbers.
std::string describe_chromaticities(const Chromaticities& c);

// The matrix taking linear RGB in `from` to linear Rec.709 (column vectors: out = M in): to CIE
// XYZ and back with OpenEXR's RGBtoXYZ / XYZtoRGB, the white adapted to D65 by the Bradford
// transform (as ACES and ICC do) where the whites differ. Throws dynsky::Error for primaries that
// span no colour space (collinear, or a y of 0).
Eigen::Matrix3d rec709_from(const Chromaticities& from);

// The primaries a file's header names: its chromaticities when given, else AP0 for an ACES
// container (acesImageContainerFlag = 1), else those an oiio:ColorSpace of "ACEScg" / "lin_ap1" or
// "ACES2065-1" / "lin_ap0" names; nullopt when the file says nothing but Rec.709 or nothing at all.
std::optional<Chromaticities> file_primaries(const std::optional<Chromaticities>& chromaticities, bool aces_container,
                                             const std::string& oiio_colour_space);

}  // namespace dynsky
