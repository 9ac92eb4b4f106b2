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

#include "motion/network_form.h"
#include "sky/sky_image.h"

namespace dynsky {

struct CloudModelInfo {
    std::string name;
    int resolution = 0;        // N: the networks' fixed input size
    double dt = 0.0;           // Delta t of one medium step, seconds
    double flow_scale = 0.04;  // magnitude channel 1 = flow_scale * N pixels per step
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

  private:
    CloudModelInfo info_;
    cv::dnn::Net flownet_, cloudnet_;
    cv::Mat disc_;  // CV_8UC1 sky disc at N
};

}  // namespace dynsky
