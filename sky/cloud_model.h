// The medium-timescale cloud model of "Deep Dynamic Cloud Lighting" (Satilmis & Bashford-Rogers):
// every step Delta t, xi(I) = CloudNet(I concat FlowNet(I)), run with OpenCV's dnn module from the
// two ONNX files that networks/train.py writes (docs/networks.md).
//
// A model folder holds flownet.onnx, cloudnet.onnx and model.json (resolution N, Delta t, the
// flow encoding's scale, widths). The networks see N x N images in [0, 1] (sky/hdr_recovery.h's
// forward map of the HDR sky, 0 outside the disc):
//   FlowNet:  image (3) -> flow (3): cos, sin of the direction, magnitude / (flow_scale N) in [0, 1]
//   CloudNet: image (3) concat flow (3) -> next image (3), before clamping
// Skies of another resolution are stepped at N and the change is carried back to their own
// resolution (CloudModel::step); the sun, which the [0, 1] form cannot hold, is re-inserted from the
// input sky.
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>

#include <functional>
#include <string>
#include <vector>

#include "sky/sky_image.h"

namespace dynsky {

struct CloudModelInfo {
    std::string name;
    int resolution = 0;            // N: the networks' fixed input size
    double dt_seconds = 0.0;       // Delta t of one medium step
    double flow_scale = 0.04;      // magnitude channel 1 = flow_scale * N pixels per step
    std::vector<int> flow_widths, cloud_widths;
    std::string folder;
};

// One medium step on the networks' [0, 1] form.
struct NetworkStep {
    cv::Mat next;  // N x N CV_32FC3, clamped to [0, 1], 0 outside the disc
    cv::Mat flow;  // N x N CV_32FC3, FlowNet's encoded output
};

class CloudModel {
  public:
    // Reads FOLDER/model.json, FOLDER/flownet.onnx and FOLDER/cloudnet.onnx and runs each network
    // once on zeros to check that it takes and returns N x N images. Throws dynsky::Error naming the
    // file and the problem (missing, unreadable, not ONNX, wrong shapes).
    static CloudModel load(const std::string& folder);

    const CloudModelInfo& info() const { return info_; }

    // The raw networks, for checking against PyTorch. `image` and `flow` are N x N CV_32FC3;
    // anything else throws dynsky::Error saying what was expected.
    cv::Mat run_flownet(const cv::Mat& image);
    cv::Mat run_cloudnet(const cv::Mat& image, const cv::Mat& flow);

    // xi on the [0, 1] form.
    NetworkStep step_network(const cv::Mat& image);

    // xi on an HDR sky of any resolution: forward map, step at N, carry the change back (the
    // image's finer detail is advected by the predicted flow), inverse map, sun re-inserted from
    // the input; time advanced by Delta t. The input is validated (validate_sky).
    SkyImage step(const SkyImage& sky);

    // K recursive steps from `sky`; on_step(k, sky_k) is called for k = 1..K (the state stays in
    // the [0, 1] form between steps, so nothing is lost to repeated HDR round trips).
    void rollout(const SkyImage& sky, int steps, const std::function<void(int, const SkyImage&)>& on_step);

    // Decodes FlowNet's output into a CV_32FC2 displacement in pixels at N (+x right, +y down).
    cv::Mat decode_flow(const cv::Mat& encoded) const;

  private:
    CloudModelInfo info_;
    cv::dnn::Net flownet_, cloudnet_;
    cv::Mat disc_;  // CV_8UC1 sky disc at N
};

// The [0, 1] form of an HDR sky at its own resolution (CV_32FC3, 0 outside the disc) and back.
// These wrap sky/hdr_recovery.h's forward and inverse maps; to_network_form also resamples to
// `resolution` (area average) when it is given and differs.
cv::Mat to_network_form(const SkyImage& sky, int resolution = 0);
SkyImage from_network_form(const cv::Mat& image, const SkyImage& like);

// A frame as the networks see it, at their resolution N.
struct NetworkFrame {
    cv::Mat image;               // N x N CV_32FC3 in [0, 1], 0 outside the disc
    cv::Mat valid;               // N x N CV_8UC1: 255 where the sky was seen (inside the disc, not hidden)
    cv::Mat cloud;               // N x N CV_8UC1: 255 where the cloud mask (sky/cloud_mask.h) says cloud
    double time_seconds = 0.0;
};

// From a sky of any resolution. `not_sky` (sky.resolution^2 values, 1 = hidden by the camera's arm,
// band or masts and filled in by the import) may be empty (everything seen). A pixel at N is valid
// only if every input pixel under it was seen.
NetworkFrame network_frame(const SkyImage& sky, const std::vector<unsigned char>& not_sky, int resolution);

// The same frame at another resolution: image area-averaged (0 outside the new disc), a pixel valid
// only if all pixels under it were, cloud mask recomputed from the resampled image.
NetworkFrame resample_frame(const NetworkFrame& frame, int resolution);

// The cloud mask (sky/cloud_mask.h's rule) of an image in the [0, 1] form, CV_8UC1 255 = cloud,
// 0 outside the disc.
cv::Mat network_cloud_mask(const cv::Mat& image);

// A photograph from one of the camera presets (sky/photo_import.h: "arm-tsi", "mobotix"), imported
// at import_resolution exactly as `dynsky sky import --preset P` does (the preset's per-frame mask
// included), then as above.
NetworkFrame network_frame_from_photo(const std::string& path, const std::string& preset, int import_resolution,
                                      int resolution);

// .npy files (NumPy's format, little-endian float32 or uint8, C order): how the Python side and
// the C++ side exchange datasets and reference input/output pairs.
struct NpyArray {
    std::vector<size_t> shape;
    std::vector<float> data;  // uint8 files are converted to float
};
NpyArray read_npy(const std::string& path);  // throws dynsky::Error naming the file
void write_npy(const std::string& path, const std::vector<size_t>& shape, const float* data);
void write_npy(const std::string& path, const std::vector<size_t>& shape, const unsigned char* data);

}  // namespace dynsky
