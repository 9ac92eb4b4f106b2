// Small math vocabulary shared by sky and renderer (Eigen does the linear algebra).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

namespace dynsky {

using Vec2 = Eigen::Vector2f;
using Vec3 = Eigen::Vector3f;
using Vec4 = Eigen::Vector4f;
using Vec3d = Eigen::Vector3d;
using Color = Eigen::Array3f;  // linear RGB, Rec.709 primaries

// An optional direction in double precision (a sky's sun_direction, stored in float).
inline std::optional<Vec3d> to_double(const std::optional<Vec3>& v) {
    return v ? std::optional<Vec3d>(v->cast<double>()) : std::nullopt;
}

constexpr float kPi = 3.14159265358979323846f;
constexpr double kPiD = 3.14159265358979323846;
constexpr float kInvPi = 1.0f / kPi;

// Order statistics of a sample (taken by value and reordered; it must not be empty): the value of
// rank n / 2, and of rank floor(q (n - 1)) for q in [0, 1].
template <typename T>
T median(std::vector<T> v) {
    std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
    return v[v.size() / 2];
}
// The median as reports give it: the middle value, the mean of the two middle ones for an even
// count (median() is the upper of them: a rank, for robust estimates inside the code).
inline double middle_mean(std::vector<double> v) {
    const size_t n = v.size();
    std::nth_element(v.begin(), v.begin() + long(n / 2), v.end());
    const double upper = v[n / 2];
    if (n % 2 == 1) return upper;
    return 0.5 * (upper + *std::max_element(v.begin(), v.begin() + long(n / 2)));
}
template <typename T>
T quantile(std::vector<T> v, double q) {
    const size_t k = size_t(q * double(v.size() - 1));
    std::nth_element(v.begin(), v.begin() + long(k), v.end());
    return v[k];
}

// Rec. 709 luminance Y of linear RGB: the one place its weights are written (SIMD code loads them).
inline constexpr float kLuminanceR = 0.2126f, kLuminanceG = 0.7152f, kLuminanceB = 0.0722f;
template <typename T>
inline T luminance(T r, T g, T b) {
    return T(0.2126) * r + T(0.7152) * g + T(0.0722) * b;
}
inline float luminance(const Color& c) { return luminance(c[0], c[1], c[2]); }

// Luminous efficacy of the sky's units: luminance in cd m^-2 (illuminance in lx) is 683 x Y of the
// radiance (irradiance) in W m^-2 sr^-1 (W m^-2); glossary.
inline constexpr double kLumensPerWatt = 683.0;

template <typename T>
inline T clamp(T x, T lo, T hi) {
    return std::min(std::max(x, lo), hi);
}

inline float safe_sqrt(float x) { return std::sqrt(std::max(0.0f, x)); }

// 0 below 0, 1 above 1, 3 x^2 - 2 x^3 between: a switch without kinks at its ends.
inline double smoothstep01(double x) {
    x = std::clamp(x, 0.0, 1.0);
    return x * x * (3 - 2 * x);
}

// Orthonormal basis from one unit vector (Duff et al. 2017, "Building an Orthonormal Basis, Revisited").
inline void orthonormal_basis(const Vec3& n, Vec3* t, Vec3* b) {
    float sign = std::copysign(1.0f, n.z());
    float a = -1.0f / (sign + n.z());
    float bb = n.x() * n.y() * a;
    *t = Vec3(1.0f + sign * n.x() * n.x() * a, sign * bb, -sign * n.x());
    *b = Vec3(bb, sign + n.y() * n.y() * a, -n.y());
}

}  // namespace dynsky
