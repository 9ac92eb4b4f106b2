#include "sky/fill_seams.h"

#include <Eigen/SparseCholesky>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "util/error.h"

namespace dynsky {

void remove_fill_seams(cv::Mat* image, const cv::Mat& region) {
    if (!image || image->empty() || region.size() != image->size() || region.type() != CV_8UC1 ||
        (image->type() != CV_32FC1 && image->type() != CV_32FC3))
        throw Error("remove_fill_seams: a CV_32FC1/3 image and a CV_8UC1 region of its size are needed");
    const int w = image->cols, h = image->rows, channels = image->channels();
    // Unknowns: the region's pixels, numbered row by row.
    std::vector<int> index(size_t(w) * h, -1);
    int count = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            if (region.at<unsigned char>(y, x)) index[size_t(y) * w + x] = count++;
    if (count == 0) return;
    // Each part of the region needs a known pixel beside it: without one its level is free (a
    // singular system).
    cv::Mat labels;
    const int parts = cv::connectedComponents(region != 0, labels, 4, CV_32S);
    std::vector<char> anchored(size_t(parts), 0);
    const int dx[4] = {1, -1, 0, 0}, dy[4] = {0, 0, 1, -1};
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            if (index[size_t(y) * w + x] < 0) continue;
            for (int k = 0; k < 4; ++k) {
                const int qx = x + dx[k], qy = y + dy[k];
                if (qx >= 0 && qy >= 0 && qx < w && qy < h && index[size_t(qy) * w + qx] < 0)
                    anchored[size_t(labels.at<int>(y, x))] = 1;
            }
        }
    for (int part = 1; part < parts; ++part)
        if (!anchored[size_t(part)])
            throw Error("remove_fill_seams: a part of the filled region touches no known pixel");
    auto value = [&](int x, int y, int c) {
        return channels == 1 ? double(image->at<float>(y, x)) : double(image->at<cv::Vec3f>(y, x)[c]);
    };
    // Per pixel p of the region: sum over its 4-neighbours q in the image of (O_p - O_q) = the
    // fill's (T_p - T_q) where q is in the region, 0 where q is known (O_q = its value).
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(size_t(count) * 5);
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(count, channels);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const int p = index[size_t(y) * w + x];
            if (p < 0) continue;
            int neighbours = 0;
            for (int k = 0; k < 4; ++k) {
                const int qx = x + dx[k], qy = y + dy[k];
                if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
                ++neighbours;
                const int q = index[size_t(qy) * w + qx];
                for (int c = 0; c < channels; ++c)
                    rhs(p, c) += q >= 0 ? value(x, y, c) - value(qx, qy, c) : value(qx, qy, c);
                if (q >= 0) entries.emplace_back(p, q, -1.0);
            }
            entries.emplace_back(p, p, double(neighbours));
        }
    Eigen::SparseMatrix<double> a(count, count);
    a.setFromTriplets(entries.begin(), entries.end());
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(a);
    const Eigen::MatrixXd solved = solver.solve(rhs);
    if (solver.info() != Eigen::Success || !solved.allFinite())
        throw Error("remove_fill_seams: the solve failed (" + std::to_string(count) + " pixels)");
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const int p = index[size_t(y) * w + x];
            if (p < 0) continue;
            for (int c = 0; c < channels; ++c) {
                if (channels == 1) image->at<float>(y, x) = float(solved(p, 0));
                else image->at<cv::Vec3f>(y, x)[c] = float(solved(p, c));
            }
        }
}

}  // namespace dynsky
