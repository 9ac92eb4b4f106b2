#include "renderer/streaming_floor.h"

#include <tbb/parallel_for.h>

#include <chrono>

namespace dynsky {

double time_streaming_floor(const SkyImage& sky, std::vector<float>* out) {
    const int n = sky.resolution;
    out->resize(size_t(n) * n);
    auto start = std::chrono::steady_clock::now();
    tbb::parallel_for(tbb::blocked_range<int>(0, n, 16), [&](const tbb::blocked_range<int>& rows) {
        for (int j = rows.begin(); j != rows.end(); ++j) {
            const float* p = &sky.rgb[size_t(j) * n * 3];
            float* o = &(*out)[size_t(j) * n];
            for (int i = 0; i < n; ++i) o[i] = luminance(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
        }
    });
    // Keep the compiler from dropping the pass: the result is observable through out.
    asm volatile("" : : "r"(out->data()) : "memory");
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace dynsky
