// Running the cloud networks' ONNX files with OpenCV's dnn module (CPU, OpenCV's own backend):
// loading with errors that name the file, and N x N x C images in and out as 1 x C x N x N blobs.
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>

#include <string>
#include <vector>

namespace dynsky {

// "64 x 64 x 3 float", for messages.
std::string shape_text(const cv::Mat& m);

// N x N x C planes (concatenated along channels) -> a 1 x C x N x N blob (NCHW), and back.
cv::Mat to_blob(const std::vector<cv::Mat>& images);
cv::Mat from_blob(const cv::Mat& blob, const std::string& what);

// Throws dynsky::Error naming the file: not found, empty, or not ONNX that OpenCV can run.
cv::dnn::Net read_onnx(const std::string& path);
// One forward pass; throws naming `what` when OpenCV fails.
cv::Mat run_net(cv::dnn::Net& net, const cv::Mat& blob, const std::string& what);

// The first run of a model folder's network, on zeros at model.json's resolution: a network made
// for another size fails inside OpenCV's layers, reported as "ONNX_PATH: does not run at
// model.json's resolution N x N ...". Returns the output as an image (from_blob).
cv::Mat probe_net(cv::dnn::Net& net, const cv::Mat& blob, const std::string& onnx_path, int resolution);

// OpenCV logs its own lines about a bad model before throwing; dynsky reports the problem itself.
struct QuietOpenCv {
    QuietOpenCv();
    ~QuietOpenCv();
    int old_level;
};

}  // namespace dynsky
