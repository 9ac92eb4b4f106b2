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

#include "sky/cloud_mask.h"
#include "sky/hdr_recovery.h"
#include "sky/sky_image.h"

namespace dynsky {

// How skies become what the networks see: sky/hdr_recovery.h's log map HDR -> [0, 1] (its
// parameters are the model's: stored in model.json and the dataset's meta.json) and the cloud rule
// for I_cm (sky/cloud_mask.h, on the sky encoded as a camera would: encode_sky_for_mask).
// Defaults: the log map spans 0..300 W m^-2 sr^-1 (the sky and sunlit clouds of the ARM and
// procedural sequences reach about 100; only the sun and its nearest aureole clip), and red/blue >
// 0.75 (WSISEG's best threshold; on the ARM day it calls 53 % of the sky cloud, the imager's own
// masks 55 %, while the paper's 0.46 calls 79 %).
struct NetworkFormParams {
    UnitMapParams unit_map{1.0, 300.0};
    CloudMaskParams cloud_rule{CloudRule::RedBlueRatio, kWsisegBestRedBlueThreshold};
};

struct CloudModelInfo {
    std::string name;
    int resolution = 0;            // N: the networks' fixed input size
    double dt_seconds = 0.0;       // Delta t of one medium step
    double flow_scale = 0.04;      // magnitude channel 1 = flow_scale * N pixels per step
    std::vector<int> flow_widths, cloud_widths;
    NetworkFormParams form;
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
    // image's finer detail is advected the way the model moved the coarse image), inverse map,
    // sun re-inserted from the input; time advanced by Delta t. The input is validated.
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

// The [0, 1] form of an HDR sky (CV_32FC3, 0 outside the disc) and back: sky/hdr_recovery.h's
// hdr_to_unit / unit_to_hdr. to_network_form also area-resamples to `resolution` when it is given
// and differs; from_network_form takes time, sun and source from `like`.
cv::Mat to_network_form(const SkyImage& sky, const NetworkFormParams& form, int resolution = 0);
SkyImage from_network_form(const cv::Mat& image, const SkyImage& like, const NetworkFormParams& form);

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
NetworkFrame network_frame(const SkyImage& sky, const std::vector<unsigned char>& not_sky, int resolution,
                           const NetworkFormParams& form);

// The same frame at another resolution: image area-averaged (0 outside the new disc), a pixel valid
// only if all pixels under it were, cloud where most of the pixels under it were.
NetworkFrame resample_frame(const NetworkFrame& frame, int resolution);

// The cloud mask of an image in the [0, 1] form (mapped back to HDR, encoded as a camera would,
// the rule applied), CV_8UC1 255 = cloud, 0 outside the disc.
cv::Mat network_cloud_mask(const cv::Mat& image, const NetworkFormParams& form);

// A photograph from one of the camera presets (sky/photo_import.h: "arm-tsi", "mobotix"), imported
// at import_resolution exactly as `dynsky sky import --preset P --res R` does (the preset's mask,
// HDR calibrated from the file name's time and the preset's place), then as above. The import's
// not-sky pixels (arm, shadow band, masts) are what the frame marks as not valid.
NetworkFrame network_frame_from_photo(const std::string& path, const std::string& preset, int import_resolution,
                                      int resolution, const NetworkFormParams& form);
// The HDR sky of the same import (what `dynsky sky import --preset P` writes), with its not-sky mask.
SkyImage import_preset_photo(const std::string& path, const std::string& preset, int import_resolution,
                             std::vector<unsigned char>* not_sky = nullptr);

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
