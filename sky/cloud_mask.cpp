#include "sky/cloud_mask.h"

#include <algorithm>
#include <cmath>

#include "util/color.h"
#include "util/error.h"

namespace dynsky {

namespace {

constexpr float kClearValue = 100.0f / 255.0f;

// WSISEG label coding read as [0, 1] values: 255 cloud, 100 clear, 0 not sky.
int label_class(float v) { return v > 0.7f ? 2 : (v > 0.2f ? 1 : 0); }

void check_same_size(const Image& a, const Image& labels, const std::string& name) {
    if (a.width != labels.width || a.height != labels.height)
        throw_file_error(name, "labels are " + std::to_string(labels.width) + "x" + std::to_string(labels.height) +
                                   " but the image is " + std::to_string(a.width) + "x" + std::to_string(a.height));
    if (a.channels < 3) throw_file_error(name, "the cloud rule needs an RGB image");
}

}  // namespace

CloudRule parse_cloud_rule(const std::string& name) {
    if (name == "rb") return CloudRule::RedBlueRatio;
    if (name == "nbr") return CloudRule::NormalizedBlueRed;
    throw Error("unknown cloud rule '" + name + "' (use rb for red/blue > t, nbr for (b-r)/(b+r) < t)");
}

const char* cloud_rule_name(CloudRule rule) { return rule == CloudRule::RedBlueRatio ? "rb" : "nbr"; }

double cloud_score(float r, float b, CloudRule rule) {
    if (rule == CloudRule::RedBlueRatio) {
        if (b <= 0) return r <= 0 ? 1.0 : 1e6;
        return double(r) / double(b);
    }
    if (r + b <= 0) return 0.0;
    return (double(b) - double(r)) / (double(b) + double(r));
}

bool is_cloud(float r, float, float b, const CloudMaskParams& params) {
    double s = cloud_score(r, b, params.rule);
    return params.rule == CloudRule::RedBlueRatio ? s > params.threshold : s < params.threshold;
}

Image cloud_mask(const Image& encoded, const CloudMaskParams& params, const std::vector<unsigned char>* sky) {
    if (encoded.channels < 3) throw Error("the cloud rule needs an RGB image");
    Image out(encoded.width, encoded.height, 1);
    for (int y = 0; y < encoded.height; ++y)
        for (int x = 0; x < encoded.width; ++x) {
            size_t p = size_t(y) * encoded.width + x;
            if (sky && !(*sky)[p]) continue;
            out.at(x, y, 0) = is_cloud(encoded.at(x, y, 0), encoded.at(x, y, 1), encoded.at(x, y, 2), params)
                                  ? 1.0f
                                  : kClearValue;
        }
    return out;
}

Image encode_sky_for_mask(const SkyImage& sky) {
    int n = sky.resolution;
    std::vector<float> lum;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            if (sky.in_disc(i, j)) lum.push_back(luminance(sky.pixel(i, j)));
    float scale = 1.0f;
    if (!lum.empty()) {
        const float p99 = quantile(std::move(lum), 0.99);
        if (p99 > 0) scale = 1.0f / p99;
    }
    Image out(n, n, 3);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            if (!sky.in_disc(i, j)) continue;
            Color c = sky.pixel(i, j);
            for (int k = 0; k < 3; ++k) out.at(i, j, k) = linear_to_srgb(c[k] * scale);
        }
    return out;
}

double MaskAgreement::accuracy() const {
    long long t = total();
    return t ? double(true_cloud + true_clear) / double(t) : 0.0;
}

double MaskAgreement::cloud_iou() const {
    long long u = true_cloud + false_cloud + missed_cloud;
    return u ? double(true_cloud) / double(u) : 0.0;
}

void MaskAgreement::add(const MaskAgreement& o) {
    true_cloud += o.true_cloud;
    false_cloud += o.false_cloud;
    missed_cloud += o.missed_cloud;
    true_clear += o.true_clear;
}

MaskAgreement compare_with_labels(const Image& encoded, const Image& labels, const CloudMaskParams& params,
                                  const std::string& name) {
    check_same_size(encoded, labels, name);
    MaskAgreement a;
    for (int y = 0; y < encoded.height; ++y)
        for (int x = 0; x < encoded.width; ++x) {
            int truth = label_class(labels.at(x, y, 0));
            if (truth == 0) continue;
            bool cloud = is_cloud(encoded.at(x, y, 0), encoded.at(x, y, 1), encoded.at(x, y, 2), params);
            if (truth == 2) (cloud ? a.true_cloud : a.missed_cloud)++;
            else (cloud ? a.false_cloud : a.true_clear)++;
        }
    return a;
}

LabelledScoreHistogram::LabelledScoreHistogram(CloudRule rule, double lo, double hi, int bins)
    : rule_(rule), lo_(lo), hi_(hi), cloud_(size_t(bins), 0), clear_(size_t(bins), 0) {
    if (!(hi > lo) || bins < 2) throw Error("score histogram: need hi > lo and at least 2 bins");
}

int LabelledScoreHistogram::bin(double score) const {
    int n = int(cloud_.size());
    return std::clamp(int(std::floor((score - lo_) / (hi_ - lo_) * n)), 0, n - 1);
}

void LabelledScoreHistogram::add_image(const Image& encoded, const Image& labels, const std::string& name) {
    check_same_size(encoded, labels, name);
    for (int y = 0; y < encoded.height; ++y)
        for (int x = 0; x < encoded.width; ++x) {
            int truth = label_class(labels.at(x, y, 0));
            if (truth == 0) continue;
            int b = bin(cloud_score(encoded.at(x, y, 0), encoded.at(x, y, 2), rule_));
            (truth == 2 ? cloud_ : clear_)[size_t(b)]++;
        }
}

MaskAgreement LabelledScoreHistogram::at(double threshold) const {
    // Bins wholly on the cloud side of the threshold count as cloud.
    int n = int(cloud_.size());
    int edge = std::clamp(int(std::lround((threshold - lo_) / (hi_ - lo_) * n)), 0, n);
    MaskAgreement a;
    for (int b = 0; b < n; ++b) {
        bool cloud = rule_ == CloudRule::RedBlueRatio ? b >= edge : b < edge;
        if (cloud) {
            a.true_cloud += cloud_[size_t(b)];
            a.false_cloud += clear_[size_t(b)];
        } else {
            a.missed_cloud += cloud_[size_t(b)];
            a.true_clear += clear_[size_t(b)];
        }
    }
    return a;
}

double LabelledScoreHistogram::best_threshold() const {
    int n = int(cloud_.size());
    double best_t = lo_, best_acc = -1;
    for (int e = 0; e <= n; ++e) {
        double t = lo_ + (hi_ - lo_) * e / n;
        double acc = at(t).accuracy();
        if (acc > best_acc) best_acc = acc, best_t = t;
    }
    return best_t;
}

}  // namespace dynsky
