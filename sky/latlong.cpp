#include "sky/latlong.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

#include "sky/fisheye.h"
#include "util/error.h"

namespace dynsky {

Vec3d latlong_direction(double u, double v) {
    return fisheye::direction_from_angles(kPiD * v, 2 * kPiD * u - kPiD / 2);
}

void latlong_uv(const Vec3d& w, double* u, double* v) {
    double theta = fisheye::zenith_angle(w);
    double phi = fisheye::azimuth(w);  // [0, 2 pi)
    double uu = (phi + kPiD / 2) / (2 * kPiD);
    *u = uu >= 1.0 ? uu - 1.0 : uu;
    *v = theta / kPiD;
}

double latlong_pixel_solid_angle(int row, int width, int height) {
    return (2 * kPiD / width) * (std::cos(kPiD * row / height) - std::cos(kPiD * (row + 1) / height));
}

Color sample_sky(const SkyImage& sky, const Vec3d& w) {
    double u, v;
    if (!fisheye::uv_from_direction(w, &u, &v)) return Color::Zero();
    const int n = sky.resolution;
    double x = (u + 1) / 2 * n - 0.5, y = (v + 1) / 2 * n - 0.5;
    Color c;
    if (fisheye::bilinear_in_disc(sky.rgb.data(), n, x, y, &c)) return c;
    // At the very rim no neighbour's centre is inside the disc: take the nearest pixel inside.
    double r = std::sqrt(u * u + v * v), k = r > 0 ? std::min(1.0, (1.0 - 1.0 / n) / r) : 1.0;
    int i = std::clamp(int(std::floor((u * k + 1) / 2 * n)), 0, n - 1);
    int j = std::clamp(int(std::floor((v * k + 1) / 2 * n)), 0, n - 1);
    return sky.pixel(i, j);
}

Color sample_latlong(const Image& latlong, const Vec3d& w) {
    double u, v;
    latlong_uv(w, &u, &v);
    const int W = latlong.width, H = latlong.height;
    double x = u * W - 0.5, y = v * H - 0.5;
    int i0 = int(std::floor(x)), j0 = int(std::floor(y));
    double fx = x - i0, fy = y - j0;
    Color out = Color::Zero();
    for (int dj = 0; dj < 2; ++dj) {
        int j = std::clamp(j0 + dj, 0, H - 1);
        for (int di = 0; di < 2; ++di) {
            int i = ((i0 + di) % W + W) % W;
            double wgt = (di ? fx : 1 - fx) * (dj ? fy : 1 - fy);
            for (int c = 0; c < 3; ++c) out[c] += float(wgt) * latlong.at(i, j, std::min(c, latlong.channels - 1));
        }
    }
    return out;
}

Image sky_to_latlong(const SkyImage& sky, int width, const Color& ground) {
    if (width < 4 || width % 2 != 0)
        throw Error("lat-long width " + std::to_string(width) + " must be even and at least 4 (the image is W x W/2)");
    if (width > 65536) throw Error("lat-long width " + std::to_string(width) + " is over 65536 pixels");
    const int W = width, H = width / 2;
    Image out(W, H, 3);
    // The finest fisheye pixel spacing on the sphere: pi/N radially, (pi/N) sin(theta)/theta >= 2/N
    // around. Sub-samples no more than half of that apart see every fisheye pixel a lat-long pixel covers.
    const double texel = 2.0 / sky.resolution;
    tbb::parallel_for(tbb::blocked_range<int>(0, H), [&](const tbb::blocked_range<int>& rows) {
        for (int r = rows.begin(); r != rows.end(); ++r) {
            const double theta0 = kPiD * r / H, theta1 = kPiD * (r + 1) / H;
            const double max_sin = (theta0 <= kPiD / 2 && theta1 >= kPiD / 2)
                                       ? 1.0
                                       : std::max(std::sin(theta0), std::sin(theta1));
            const int n_theta = std::clamp(int(std::ceil(2 * (theta1 - theta0) / texel)), 1, 32);
            const int n_phi = std::clamp(int(std::ceil(2 * (2 * kPiD / W) * max_sin / texel)), 1, 32);
            for (int c = 0; c < W; ++c) {
                Eigen::Array3d sum = Eigen::Array3d::Zero();
                double weight = 0;
                for (int a = 0; a < n_theta; ++a) {
                    double v = (r + (a + 0.5) / n_theta) / H;
                    double wgt = std::sin(kPiD * v);
                    for (int b = 0; b < n_phi; ++b) {
                        double u = (c + (b + 0.5) / n_phi) / W;
                        Vec3d w = latlong_direction(u, v);
                        Color L = w.y() >= 0 ? sample_sky(sky, w) : ground;
                        sum += wgt * L.cast<double>();
                        weight += wgt;
                    }
                }
                Eigen::Array3d mean = weight > 0 ? Eigen::Array3d(sum / weight) : Eigen::Array3d::Zero();
                for (int k = 0; k < 3; ++k) out.at(c, r, k) = float(mean[k]);
            }
        }
    });
    write_sky_metadata(sky, &out.metadata);
    out.metadata.strings["dynsky:layout"] =
        "equirectangular W x W/2, top row zenith, centre column azimuth 90 deg (east), azimuth increasing to the right "
        "(Blender environment mapping with north = +Y)";
    return out;
}

}  // namespace dynsky
