// Template part of Distribution2D (included by distribution_2d.h).
#pragma once

#include <tbb/parallel_for.h>

namespace dynsky {

template <typename WeightFn>
void Distribution2D::build_with(int width, int height, WeightFn&& weight) {
    width_ = width, height_ = height;
    weights_.resize(size_t(width) * height);
    row_cdf_.resize(size_t(width + 1) * height);
    row_sum_.resize(size_t(height));
    marginal_cdf_.resize(size_t(height) + 1);
    tbb::parallel_for(tbb::blocked_range<int>(0, height, 8), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y != rows.end(); ++y) {
            float* w = &weights_[size_t(y) * width];
            float* cdf = &row_cdf_[size_t(y) * (width + 1)];
            double sum = 0;
            cdf[0] = 0;
            for (int x = 0; x < width; ++x) {
                float v = weight(x, y);
                w[x] = v;
                sum += v;
                cdf[x + 1] = float(sum);
            }
            row_sum_[size_t(y)] = sum;
            if (sum > 0) {
                float inv = float(1.0 / sum);
                for (int x = 1; x <= width; ++x) cdf[x] *= inv;
                cdf[width] = 1.0f;
            }
        }
    });
    finish_marginal();
}

}  // namespace dynsky
