#include "util/colour_space.h"

#include <OpenEXR/ImfChromaticities.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>

#include "util/error.h"

namespace dynsky {

Chromaticities rec709_chromaticities() { return {0.64f, 0.33f, 0.30f, 0.60f, 0.15f, 0.06f, 0.3127f, 0.3290f}; }
Chromaticities aces_ap0_chromaticities() {
    return {0.7347f, 0.2653f, 0.0f, 1.0f, 0.0001f, -0.0770f, 0.32168f, 0.33767f};
}
Chromaticities aces_ap1_chromaticities() {
    return {0.713f, 0.293f, 0.165f, 0.830f, 0.128f, 0.044f, 0.32168f, 0.33767f};
}

bool same_chromaticities(const Chromaticities& a, const Chromaticities& b) {
    for (size_t k = 0; k < a.size(); ++k)
        if (!(std::abs(a[k] - b[k]) <= 1e-3f)) return false;
    return true;
}

std::string describe_chromaticities(const Chromaticities& c) {
    if (same_chromaticities(c, aces_ap1_chromaticities())) return "AP1 (ACEScg)";
    if (same_chromaticities(c, aces_ap0_chromaticities())) return "AP0 (ACES2065-1)";
    if (same_chromaticities(c, rec709_chromaticities())) return "Rec.709";
    std::ostringstream s;
    s << "red " << c[0] << "," << c[1] << " green " << c[2] << "," << c[3] << " blue " << c[4] << "," << c[5]
      << " white " << c[6] << "," << c[7];
    return s.str();
}

namespace {

Imf::Chromaticities to_imf(const Chromaticities& c) {
    return Imf::Chromaticities(Imath::V2f(c[0], c[1]), Imath::V2f(c[2], c[3]), Imath::V2f(c[4], c[5]),
                               Imath::V2f(c[6], c[7]));
}

// OpenEXR's matrices act on row vectors (XYZ = RGB * M): the 3 x 3 part, transposed.
Eigen::Matrix3d column_form(const Imath::M44f& m) {
    Eigen::Matrix3d out;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) out(r, c) = m[c][r];
    return out;
}

Eigen::Vector3d white_xyz(float x, float y) { return Eigen::Vector3d(x / y, 1.0, (1.0 - x - y) / y); }

}  // namespace

Eigen::Matrix3d rec709_from(const Chromaticities& from) {
    for (size_t k = 1; k < from.size(); k += 2)
        if (!(std::isfinite(from[k - 1]) && std::isfinite(from[k]) && std::abs(from[k]) > 1e-6f))
            throw Error("chromaticities " + describe_chromaticities(from) + ": not a colour space (a y of 0)");
    // The primaries' triangle in xy (twice its area): Rec.709's is 0.11, AP0's 0.68.
    const double area = double(from[2] - from[0]) * (from[5] - from[1]) -
                        double(from[4] - from[0]) * (from[3] - from[1]);
    if (!(std::abs(area) > 1e-4))
        throw Error("chromaticities " + describe_chromaticities(from) + ": the primaries span no colour space");
    const Eigen::Matrix3d to_xyz = column_form(Imf::RGBtoXYZ(to_imf(from), 1.0f));
    if (!(std::abs(to_xyz.determinant()) > 1e-9) || !to_xyz.allFinite())
        throw Error("chromaticities " + describe_chromaticities(from) + ": the primaries span no colour space");
    const Chromaticities rec709 = rec709_chromaticities();
    const Eigen::Matrix3d from_xyz = column_form(Imf::XYZtoRGB(to_imf(rec709), 1.0f));
    Eigen::Matrix3d adapt = Eigen::Matrix3d::Identity();
    if (std::abs(from[6] - rec709[6]) > 1e-4f || std::abs(from[7] - rec709[7]) > 1e-4f) {
        // Bradford's cone response (Lam 1985), the chromatic adaptation of ACES and ICC v4.
        Eigen::Matrix3d bradford;
        bradford << 0.8951, 0.2664, -0.1614, -0.7502, 1.7135, 0.0367, 0.0389, -0.0685, 1.0296;
        const Eigen::Vector3d source = bradford * white_xyz(from[6], from[7]);
        const Eigen::Vector3d target = bradford * white_xyz(rec709[6], rec709[7]);
        adapt = bradford.inverse() * target.cwiseQuotient(source).asDiagonal() * bradford;
    }
    return from_xyz * adapt * to_xyz;
}

std::optional<Chromaticities> file_primaries(const std::optional<Chromaticities>& chromaticities, bool aces_container,
                                             const std::string& oiio_colour_space) {
    std::optional<Chromaticities> c = chromaticities;
    if (!c && aces_container) c = aces_ap0_chromaticities();
    if (!c) {
        std::string space = oiio_colour_space;
        std::transform(space.begin(), space.end(), space.begin(), [](unsigned char ch) { return std::tolower(ch); });
        if (space == "acescg" || space == "lin_ap1" || space == "aces - acescg") c = aces_ap1_chromaticities();
        else if (space == "aces2065-1" || space == "lin_ap0" || space == "aces - aces2065-1")
            c = aces_ap0_chromaticities();
    }
    if (c && same_chromaticities(*c, rec709_chromaticities())) return std::nullopt;
    return c;
}

}  // namespace dynsky
