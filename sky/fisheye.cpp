#include "sky/fisheye.h"

#include <algorithm>

namespace dynsky::fisheye {

Vec3d direction_from_uv(double u, double v) {
    double r = std::sqrt(u * u + v * v);
    double theta = r * kPiD / 2.0;
    // x = sin(theta) sin(phi) = -u sin(theta)/r, z = -sin(theta) cos(phi) = v sin(theta)/r.
    double s = (kPiD / 2.0) * sinc(theta);  // sin(theta) / r
    return Vec3d(-u * s, std::cos(theta), v * s);
}

// Float versions for renderers' hot paths (single-precision trig; about 1e-6 accurate).
Vec3 direction_from_uv(const Vec2& uv) {
    float r2 = uv.squaredNorm();
    float r = std::sqrt(r2);
    float theta = r * (kPi / 2);
    float s = r > 1e-4f ? std::sin(theta) / r : (kPi / 2) * (1 - theta * theta / 6);
    return Vec3(-uv.x() * s, std::cos(theta), uv.y() * s);
}

bool uv_from_direction(const Vec3d& w, double* u, double* v) {
    if (w.y() < 0.0) return false;
    double sin_theta = std::sqrt(w.x() * w.x() + w.z() * w.z());
    double theta = std::atan2(sin_theta, w.y());
    // r / sin(theta) = (2 / pi) theta / sin(theta)
    double k = (2.0 / kPiD) / sinc(theta);
    *u = -w.x() * k;
    *v = w.z() * k;
    return true;
}

bool uv_from_direction(const Vec3& w, Vec2* uv) {
    if (w.y() < 0) return false;
    float sin_theta = std::sqrt(w.x() * w.x() + w.z() * w.z());
    float theta = std::atan2(sin_theta, w.y());
    float k = sin_theta > 1e-4f ? (2 / kPi) * theta / sin_theta : (2 / kPi) * (1 + theta * theta / 6);
    *uv = Vec2(-w.x() * k, w.z() * k);
    return true;
}

double zenith_angle(const Vec3d& w) { return std::acos(clamp(w.y() / w.norm(), -1.0, 1.0)); }

double azimuth(const Vec3d& w) {
    double phi = std::atan2(w.x(), -w.z());
    return phi < 0 ? phi + 2 * kPiD : phi;
}

Vec3d direction_from_angles(double theta, double phi) {
    return Vec3d(std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi));
}

double pixel_solid_angle(int i, int j, int n) {
    Vec2 uv = pixel_center_uv(i, j, n);
    double u = uv.x(), v = uv.y();
    double r = std::sqrt(u * u + v * v);
    if (r > 1.0) return 0.0;
    double du = 2.0 / n;
    return solid_angle_jacobian(r * kPiD / 2.0) * du * du;
}

Vec3d direction_from_pixel(double x, double y, int n) {
    double u = 2.0 * (x + 0.5) / n - 1.0, v = 2.0 * (y + 0.5) / n - 1.0;
    double r = std::sqrt(u * u + v * v);
    double theta = r * kPiD / 2, phi = std::atan2(-u, -v);
    double s = std::sin(theta);
    return Vec3d(s * std::sin(phi), std::cos(theta), -s * std::cos(phi));
}

void pixel_from_direction(const Vec3d& w, int n, double* x, double* y) {
    double theta = std::acos(std::clamp(w.y() / w.norm(), -1.0, 1.0));
    double phi = std::atan2(w.x(), -w.z());
    double r = 2.0 * theta / kPiD;
    double u = -r * std::sin(phi), v = -r * std::cos(phi);
    *x = (u + 1.0) * n / 2.0 - 0.5;
    *y = (v + 1.0) * n / 2.0 - 0.5;
}

}  // namespace dynsky::fisheye

namespace dynsky {

cv::Mat sky_disc_mask(int resolution) {
    cv::Mat mask(resolution, resolution, CV_8UC1);
    for (int j = 0; j < resolution; ++j)
        for (int i = 0; i < resolution; ++i)
            mask.at<uint8_t>(j, i) = fisheye::pixel_center_uv(i, j, resolution).squaredNorm() <= 1.0f ? 255 : 0;
    return mask;
}

}  // namespace dynsky
