// The canonical sky image: an equidistant fisheye of the upper hemisphere (../shared/CONVENTIONS.md).
//
// World frame: +Y up, north -Z, east +X. Zenith angle theta = acos(y), azimuth phi = atan2(x, -z).
// Image plane (u, v) in [-1, 1]^2, v down, north at the top, east at the LEFT:
//   u = -r sin(phi), v = -r cos(phi), r = 2 theta / pi.
#pragma once

#include "util/math.h"

namespace dynsky::fisheye {

// Centre of pixel (i, j) of an N x N image in (u, v).
inline Vec2 pixel_center_uv(int i, int j, int n) {
    return Vec2(2.0f * (i + 0.5f) / n - 1.0f, 2.0f * (j + 0.5f) / n - 1.0f);
}

// sin(theta) / theta, exact at theta = 0.
inline double sinc(double theta) { return theta < 1e-4 ? 1.0 - theta * theta / 6.0 : std::sin(theta) / theta; }

// Unit direction for (u, v); meaningful for r <= 1 (r > 1 is below the horizon).
Vec3 direction_from_uv(const Vec2& uv);
Vec3d direction_from_uv(double u, double v);

// (u, v) of a direction. Returns false for directions below the horizon (y < 0).
bool uv_from_direction(const Vec3& w, Vec2* uv);
bool uv_from_direction(const Vec3d& w, double* u, double* v);

// Zenith angle and azimuth (CONVENTIONS.md) of a direction, azimuth in [0, 2 pi).
double zenith_angle(const Vec3d& w);
double azimuth(const Vec3d& w);
Vec3d direction_from_angles(double theta, double phi);

// dw / (du dv) = (pi^2 / 4) sin(theta) / theta.
inline double solid_angle_jacobian(double theta) { return kPiD * kPiD / 4.0 * sinc(theta); }

// Solid angle of pixel (i, j) of an N x N image (0 outside the disc, using the pixel centre).
// Exactly (pi^2 / N^2) sin(theta)/theta at the centre, the convention's rule.
double pixel_solid_angle(int i, int j, int n);

// Densities: p_w = p_uv * 4 theta / (pi^2 sin theta), p_uv per unit area of [-1, 1]^2.
inline double pdf_solid_angle_from_uv(double pdf_uv, double theta) { return pdf_uv / solid_angle_jacobian(theta); }
inline double pdf_uv_from_solid_angle(double pdf_w, double theta) { return pdf_w * solid_angle_jacobian(theta); }

}  // namespace dynsky::fisheye
