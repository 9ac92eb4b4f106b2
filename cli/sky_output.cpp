#include "cli/sky_output.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "util/error.h"
#include "util/exposure.h"

namespace dynsky::cli {

void check_extension(const std::string& option, const std::string& path, const std::string& ext) {
    // A usage error (exit 2): the message starts with the option (docs/exit-codes.md).
    if (file_extension(path) != ext) throw Error(option + " " + path + ": must name a " + ext + " file");
}

void write_preview(const std::string& path, const Image& linear, bool say) {
    const float ev = exposure_median(linear);
    write_image(path, tonemap_to_display(linear, ev));
    if (say) std::printf("preview: %s (exposure %+.2f EV)\n", path.c_str(), ev);
}

}  // namespace dynsky::cli
