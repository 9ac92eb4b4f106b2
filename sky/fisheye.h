// The canonical sky image: an equidistant fisheye of the upper hemisphere (../shared/CONVENTIONS.md).
//
// World frame: +Y up, north -Z, east +X. Zenith angle theta = acos(y), azimuth phi = atan2(x, -z).
// Image plane (u, v) in [-1, 1]^2, v down, north at the top, east at the LEFT:
//   u = -r sin(phi), v = -r cos(phi), r = 2 theta / pi.
// Pixel coordinates: continuous (x, y) = (column, row) with pixel (i, j)'s centre at (i, j), OpenCV's
// convention; u = 2 (x + 0.5) / N - 1. The sky disc is the pixels whose centre has r <= 1.
#pragma once

#include <opencv2/core.hpp>

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

// Direction <-> continuous pixel coordinates of an N x N fisheye, for any direction (below the
// horizon gives r > 1). Double precision, for image warps and the motion code.
Vec3d direction_from_pixel(double x, double y, int n);
void pixel_from_direction(const Vec3d& w, int n, double* x, double* y);

// Bilinear lookup of an N x N x 3 fisheye (row-major floats) that uses only the neighbours whose
// centres lie inside the disc, renormalising their weights (so the black corners never darken the
// rim). x, y as above. Returns false when no neighbour is inside (the caller picks a fallback).
// kTestDisc = false skips the tests, for callers that know all four neighbours lie inside (the
// renderer's camera rays away from the rim: the tests cost 8 divisions).
template <bool kTestDisc = true, typename Real>
bool bilinear_in_disc(const float* rgb, int n, Real x, Real y, Color* out) {
    const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
    const Real tx = x - x0, ty = y - y0;
    Color sum = Color::Zero();
    Real weight = 0;
    for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
            const int i = x0 + dx, j = y0 + dy;
            if (kTestDisc && (i < 0 || j < 0 || i >= n || j >= n || pixel_center_uv(i, j, n).squaredNorm() > 1.0f))
                continue;
            const Real w = (dx ? tx : 1 - tx) * (dy ? ty : 1 - ty);
            const float* p = &rgb[(size_t(j) * n + i) * 3];
            sum += Color(p[0], p[1], p[2]) * float(w);
            weight += w;
        }
    // (The float lookup of the renderer keeps any positive weight; the double one needs 1e-12.)
    if (!(weight > (sizeof(Real) == sizeof(float) ? Real(0) : Real(1e-12)))) return false;
    *out = sum / float(weight);
    return true;
}

}  // namespace dynsky::fisheye

namespace dynsky {

// The sky disc of an N x N image as a CV_8UC1 mask (255 inside).
cv::Mat sky_disc_mask(int resolution);

}  // namespace dynsky
