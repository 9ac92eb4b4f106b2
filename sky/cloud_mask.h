// The binary cloud mask I_cm (../shared/CONVENTIONS.md): which sky pixels are cloud.
//
// The paper's rule: red / blue > 0.46, on the camera's ENCODED values (8-bit photographs as they
// come, not linear light). The normalised blue-red ratio (b - r) / (b + r) < t is the same rule
// (a monotone function of r / b: t = (1 - k) / (1 + k) for ratio threshold k); it is offered because
// the literature states thresholds in both forms. The threshold depends on the camera: measured
// agreement with the WSISEG human labels is in docs/sky-import.md (0.46 is far too low there; about
// 0.75 is best), and on the Mobotix's dark exposure 0.46 calls nearly everything cloud.
//
// Mask images use the WSISEG coding: 255 cloud, 100 clear sky, 0 not sky.
#pragma once

#include <string>
#include <vector>

#include "sky/sky_image.h"
#include "util/image.h"

namespace dynsky {

enum class CloudRule {
    RedBlueRatio,       // cloud if r / b > threshold (the paper's, threshold 0.46)
    NormalizedBlueRed,  // cloud if (b - r) / (b + r) < threshold
};

CloudRule parse_cloud_rule(const std::string& name);  // "rb" | "nbr"; throws dynsky::Error
const char* cloud_rule_name(CloudRule rule);

struct CloudMaskParams {
    CloudRule rule = CloudRule::RedBlueRatio;
    double threshold = 0.46;
};

// Threshold measured best on WSISEG (tuned on the even-numbered half, checked on the odd half;
// docs/sky-import.md). The paper's own value stays the default.
constexpr double kWsisegBestRedBlueThreshold = 0.75;

// The rule's score of one encoded pixel (r / b, or (b - r) / (b + r)); black pixels score as
// cloud-neutral grey (ratio 1, normalised 0).
double cloud_score(float r, float b, CloudRule rule);
bool is_cloud(float r, float g, float b, const CloudMaskParams& params);

// Mask of an encoded RGB image (values in [0, 1]): one channel, 1 = cloud, 100/255 = clear,
// 0 where sky (if given: width*height, nonzero = sky) is 0.
Image cloud_mask(const Image& encoded, const CloudMaskParams& params, const std::vector<unsigned char>* sky = nullptr);

// A canonical sky (linear radiance) as a camera would encode it, for the rule: exposed so the
// disc's 99th-percentile luminance maps to 1, clamped, sRGB-encoded. Outside the disc: 0.
Image encode_sky_for_mask(const SkyImage& sky);

// Agreement of a predicted mask with human labels, counted over labelled sky pixels.
struct MaskAgreement {
    long long true_cloud = 0, false_cloud = 0, missed_cloud = 0, true_clear = 0;
    long long total() const { return true_cloud + false_cloud + missed_cloud + true_clear; }
    double accuracy() const;   // (correct) / total
    double cloud_iou() const;  // true_cloud / (true_cloud + false_cloud + missed_cloud)
    void add(const MaskAgreement& other);
};

// Compares the rule on `encoded` with `labels` (one channel; WSISEG coding 255 / 100 / 0 read as
// values in [0, 1]: > 0.7 cloud, > 0.2 clear, else not sky). Sizes must match (throws naming `name`).
MaskAgreement compare_with_labels(const Image& encoded, const Image& labels, const CloudMaskParams& params,
                                  const std::string& name = "labels");

// Labelled scores binned finely, so that the agreement at any threshold is a prefix sum: a sweep
// over thresholds costs one pass over the pixels.
class LabelledScoreHistogram {
  public:
    LabelledScoreHistogram(CloudRule rule, double lo, double hi, int bins);
    void add_image(const Image& encoded, const Image& labels, const std::string& name = "labels");
    MaskAgreement at(double threshold) const;
    // Threshold (a bin edge) with the best accuracy.
    double best_threshold() const;

  private:
    CloudRule rule_;
    double lo_, hi_;
    std::vector<long long> cloud_, clear_;  // labelled counts per bin
    int bin(double score) const;
};

}  // namespace dynsky
