// Template part of Distribution2D (included by distribution_2d.h).
#pragma once

#include <tbb/parallel_for.h>

namespace dynsky {

template <typename RowFn>
void Distribution2D::build_rows(int width, int height, RowFn&& row_weights) {
    width_ = width, height_ = height;
    row_prefix_.resize(size_t(width + 1) * height);
    marginal_.resize(size_t(height) + 1);
    tbb::parallel_for(tbb::blocked_range<int>(0, height, 16), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y != rows.end(); ++y) {
            float* p = &row_prefix_[size_t(y) * (width + 1)];
            p[0] = 0;
            row_weights(y, p + 1);
            for (int x = 1; x <= width; ++x) p[x] += p[x - 1];
        }
    });
    finish_marginal();
}

}  // namespace dynsky
