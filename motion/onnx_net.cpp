#include "motion/onnx_net.h"

#include <opencv2/core/utils/logger.hpp>

#include <filesystem>

#include "util/error.h"

namespace dynsky {

namespace fs = std::filesystem;

std::string shape_text(const cv::Mat& m) {
    if (m.empty()) return "an empty image";
    return std::to_string(m.cols) + " x " + std::to_string(m.rows) + " x " + std::to_string(m.channels()) +
           (m.depth() == CV_32F ? " float" : " non-float");
}

// N x N x C planes -> a 1 x C x N x N blob (NCHW), as the ONNX graphs expect.
cv::Mat to_blob(const std::vector<cv::Mat>& images) {
    int channels = 0;
    for (const cv::Mat& m : images) channels += m.channels();
    const int n = images[0].rows, w = images[0].cols;
    int dims[4] = {1, channels, n, w};
    cv::Mat blob(4, dims, CV_32F);
    int c = 0;
    for (const cv::Mat& m : images) {
        std::vector<cv::Mat> planes;
        cv::split(m, planes);
        for (const cv::Mat& p : planes) {
            cv::Mat dst(n, w, CV_32F, blob.ptr<float>(0, c++));
            p.copyTo(dst);
        }
    }
    return blob;
}

cv::Mat from_blob(const cv::Mat& blob, const std::string& what) {
    if (blob.dims != 4 || blob.size[0] != 1)
        throw Error(what + ": the network returned a " + std::to_string(blob.dims) +
                    "-d tensor, expected 1 x C x N x N");
    const int c = blob.size[1], n = blob.size[2], w = blob.size[3];
    std::vector<cv::Mat> planes;
    for (int k = 0; k < c; ++k)
        planes.push_back(cv::Mat(n, w, CV_32F, const_cast<float*>(blob.ptr<float>(0, k))).clone());
    cv::Mat out;
    cv::merge(planes, out);
    return out;
}

QuietOpenCv::QuietOpenCv() : old_level(int(cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT))) {}
QuietOpenCv::~QuietOpenCv() { cv::utils::logging::setLogLevel(cv::utils::logging::LogLevel(old_level)); }

cv::dnn::Net read_onnx(const std::string& path) {
    QuietOpenCv quiet;
    if (!fs::exists(path)) throw_file_error(path, "model file not found");
    if (!fs::is_regular_file(path))
        throw_file_error(path, "not a file (a folder or a device), where a model file belongs");
    if (fs::file_size(path) == 0) throw_file_error(path, "model file is empty");
    try {
        cv::dnn::Net net = cv::dnn::readNetFromONNX(path);
        if (net.empty()) throw_file_error(path, "OpenCV could not build a network from this ONNX file");
        net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
        net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
        return net;
    } catch (const cv::Exception& e) {
        throw_file_error(path, "not an ONNX model OpenCV can load (" + std::string(e.err) + ")");
    }
}

cv::Mat run_net(cv::dnn::Net& net, const cv::Mat& blob, const std::string& what) {
    try {
        net.setInput(blob);
        return net.forward().clone();
    } catch (const cv::Exception& e) {
        throw Error(what + ": the network failed to run on a " + std::to_string(blob.size[1]) + " x " +
                    std::to_string(blob.size[2]) + " x " + std::to_string(blob.size[3]) + " input (" + e.err + ")");
    }
}

cv::Mat probe_net(cv::dnn::Net& net, const cv::Mat& blob, const std::string& onnx_path, int resolution) {
    cv::Mat out;
    try {
        net.setInput(blob);
        out = net.forward().clone();
    } catch (const cv::Exception& e) {
        const std::string n = std::to_string(resolution);
        throw_file_error(onnx_path, "does not run on the input model.json describes (" + std::to_string(blob.size[1]) +
                                        " channels at " + n + " x " + n +
                                        "): a network made for another input or size, another kind of model, or "
                                        "an edited model.json? OpenCV: " +
                                        e.err);
    }
    return from_blob(out, onnx_path);
}

}  // namespace dynsky
