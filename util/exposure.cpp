#include "util/exposure.h"

#include <cmath>
#include <cstdio>
#include <vector>

namespace dynsky {

float exposure_log_average(const Image& linear) {
    if (linear.channels < 3) return 0.0f;
    double sum_log = 0;
    size_t count = 0;
    for (size_t p = 0; p < size_t(linear.width) * linear.height; ++p) {
        const float* c = &linear.pixels[p * linear.channels];
        float y = luminance(c[0], c[1], c[2]);
        if (!(y > 0) || !std::isfinite(y)) continue;
        sum_log += std::log(double(y) + 1e-6);
        ++count;
    }
    if (count == 0) return 0.0f;
    double log_avg = std::exp(sum_log / count);
    return float(std::log2(0.18 / log_avg));
}

float exposure_median(const Image& linear, float middle_grey) {
    std::vector<float> lum;
    lum.reserve(linear.pixels.size() / 3);
    for (int y = 0; y < linear.height; ++y)
        for (int x = 0; x < linear.width; ++x) {
            float l = luminance(Color(linear.at(x, y, 0), linear.at(x, y, 1), linear.at(x, y, 2)));
            if (l > 0) lum.push_back(l);
        }
    if (lum.empty()) return 0.0f;
    return std::log2(middle_grey / median(std::move(lum)));
}

float exposure_for_irradiance(const Color& irradiance) {
    double e = luminance(irradiance);
    if (!(e > 0)) return 0.0f;
    return float(std::log2(0.18 * kPiD / (0.4 * e)));
}

void write_display_preview(const std::string& path, const Image& linear, bool say) {
    const float ev = exposure_median(linear);
    write_image(path, tonemap_to_display(linear, ev));
    if (say) std::printf("preview: %s (exposure %+.2f EV)\n", path.c_str(), ev);
}

}  // namespace dynsky
