#include "cli/sky_output.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "util/error.h"
#include "util/math.h"

namespace dynsky::cli {

void check_extension(const std::string& option, const std::string& path, const std::string& ext) {
    if (file_extension(path) != ext) throw_file_error(path, option + " must name a " + ext + " file");
}

void write_preview(const std::string& path, const Image& linear) {
    std::vector<float> lum;
    lum.reserve(linear.pixels.size() / 3);
    for (int y = 0; y < linear.height; ++y)
        for (int x = 0; x < linear.width; ++x) {
            float l = luminance(Color(linear.at(x, y, 0), linear.at(x, y, 1), linear.at(x, y, 2)));
            if (l > 0) lum.push_back(l);
        }
    float ev = 0;
    if (!lum.empty()) {
        ev = std::log2(0.18f / median(std::move(lum)));
    }
    write_image(path, tonemap_to_display(linear, ev));
    std::printf("preview: %s (exposure %+.2f EV)\n", path.c_str(), ev);
}

}  // namespace dynsky::cli
