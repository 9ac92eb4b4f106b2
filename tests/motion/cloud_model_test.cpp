// The shipped cloud model through OpenCV's dnn: agreement with PyTorch, skill on held-out real
// frames, rollout stability, the sky-level step, and clear errors for bad models and inputs.
#include "motion/cloud_model.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "sky/clear_sky.h"
#include "sky/fisheye.h"
#include "sky/procedural_clouds.h"
#include "motion/advection.h"
#include "motion/metrics.h"
#include "motion/sun_patch.h"
#include "sky/preset_import.h"
#include "util/npy.h"
#include "tests/test_support.h"
#include "util/data_path.h"
#include "util/error.h"

namespace dynsky {
namespace {

namespace fs = std::filesystem;

const char* kShippedModel = "networks/models/arm_tsi";

std::string shipped_model() { return data_path(kShippedModel); }

// The model is loaded once for the whole suite (loading runs both networks once).
CloudModel& model() {
    static CloudModel m = CloudModel::load(shipped_model());
    return m;
}

cv::Mat npy_image(const std::string& path) {
    NpyArray a = read_npy(path);
    EXPECT_EQ(a.shape.size(), 3u) << path;
    cv::Mat m(int(a.shape[0]), int(a.shape[1]), CV_32FC3);
    std::copy(a.data.begin(), a.data.end(), m.ptr<float>());
    return m;
}

std::string error_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

ProceduralSkyParams procedural_params() {
    ProceduralSkyParams p;
    p.seed = 11;
    p.coverage = 0.5;
    p.clear_sky.sun_direction = fisheye::direction_from_angles(40.0 * kPiD / 180.0, 150.0 * kPiD / 180.0);
    return p;
}

TEST(CloudModel, LoadsTheShippedModel) {
    const CloudModelInfo& info = model().info();
    EXPECT_GE(info.resolution, 32);
    EXPECT_DOUBLE_EQ(info.dt, 30.0);  // trained on the 30 s ARM cadence
    EXPECT_GT(info.flow_scale, 0.0);
    EXPECT_FALSE(info.flow_widths.empty());
}

TEST(CloudModel, OpenCvAgreesWithPyTorchWithin1e4) {
    // reference_*.npy were written by networks/export.py from the PyTorch model at export time.
    const std::string dir = shipped_model();
    cv::Mat input = npy_image(dir + "/reference_input.npy");
    cv::Mat flow_ref = npy_image(dir + "/reference_flow.npy");
    cv::Mat next_ref = npy_image(dir + "/reference_next.npy");
    cv::Mat flow = model().run_flownet(input);
    cv::Mat next = model().run_cloudnet(input, flow_ref);
    double flow_err = cv::norm(flow, flow_ref, cv::NORM_INF), next_err = cv::norm(next, next_ref, cv::NORM_INF);
    EXPECT_LT(flow_err, 1e-4);
    EXPECT_LT(next_err, 1e-4);
    // The references are not trivial (a model that returned its input would not match them).
    EXPECT_GT(cv::norm(next_ref, input, cv::NORM_INF), 1e-3);
    RecordProperty("max_abs_diff_flownet", std::to_string(flow_err));
    RecordProperty("max_abs_diff_cloudnet", std::to_string(next_err));
}

TEST(CloudModel, BeatsPersistenceOnHeldOutRealFrames) {
    DYNSKY_REQUIRE_SHARED();
    // The first held-out frames of the ARM sequence (the model never saw them), imported as in
    // training; one step ahead, mean per-frame PSNR over seen sky pixels.
    nlohmann::json split;
    std::ifstream(shipped_model() + "/split.json") >> split;
    nlohmann::json meta;
    std::ifstream(shipped_model() + "/model.json") >> meta;
    const int lo = split["arm_tsi"]["heldout"][0].get<int>();
    const int n = model().info().resolution, big = meta.value("import_resolution", 2 * n);
    const std::string images = test::shared_path("skies/arm_tsi_sgp_20170524/images");
    std::vector<std::string> photos;
    for (const auto& e : fs::directory_iterator(images)) photos.push_back(e.path().string());
    std::sort(photos.begin(), photos.end());
    ASSERT_EQ(photos.size(), 300u);
    const int pairs = 8;
    std::vector<NetworkFrame> frames;
    for (int k = lo; k <= lo + pairs; ++k)
        frames.push_back(network_frame_from_photo(photos[k], "arm-tsi", big, n, model().info().form));
    double model_psnr = 0, persistence_psnr = 0;
    for (int k = 0; k < pairs; ++k) {
        cv::Mat mask = frames[k].valid & frames[k + 1].valid;
        cv::Mat predicted = model().step_network(frames[k].image).next;
        model_psnr += compare_images(predicted, frames[k + 1].image, mask).psnr / pairs;
        persistence_psnr += compare_images(frames[k].image, frames[k + 1].image, mask).psnr / pairs;
    }
    RecordProperty("model_psnr", std::to_string(model_psnr));
    RecordProperty("persistence_psnr", std::to_string(persistence_psnr));
    EXPECT_GT(model_psnr, persistence_psnr + 1.0) << "model " << model_psnr << " dB, persistence " << persistence_psnr;
}

TEST(CloudModel, FiftyStepRolloutStaysFiniteAndBounded) {
    // From a procedural sky (not in the training data at all): the state must stay in [0, 1],
    // finite, keep its mean brightness and its detail within bounds (no collapse to a flat image,
    // no runaway growth of high frequencies).
    const int n = model().info().resolution;
    SkyImage sky = render_procedural_sky(procedural_params(), 0.0, n);
    cv::Mat state = to_network_form(sky, model().info().form);
    const cv::Mat disc = sky_disc_mask(n);
    auto hf = [&](const cv::Mat& m) {
        cv::Mat blurred, d;
        cv::GaussianBlur(m, blurred, cv::Size(0, 0), 2.0);
        cv::absdiff(m, blurred, d);
        return cv::mean(d, disc);
    };
    const double mean0 = cv::mean(state, disc)[0];
    const double hf0 = hf(state)[0];
    for (int k = 1; k <= 50; ++k) {
        state = model().step_network(state).next;
        ASSERT_TRUE(cv::checkRange(state, true, nullptr, 0.0, 1.0 + 1e-6)) << "step " << k;
    }
    const double mean50 = cv::mean(state, disc)[0], hf50 = hf(state)[0];
    RecordProperty("mean_0", std::to_string(mean0));
    RecordProperty("mean_50", std::to_string(mean50));
    RecordProperty("hf_0", std::to_string(hf0));
    RecordProperty("hf_50", std::to_string(hf50));
    // Bounds measured on 360-step rollouts (docs/networks.md, Stability) with a wide margin.
    EXPECT_NEAR(mean50, mean0, 0.1);
    EXPECT_GT(hf50, 0.2 * hf0);
    EXPECT_LT(hf50, 3.0 * hf0);
}

TEST(CloudModel, SkyStepKeepsResolutionAdvancesTimeAndKeepsTheSun) {
    // A sky at another resolution than the model's, with a visible sun.
    const int n = model().info().resolution * 3 / 2;
    ProceduralSkyParams p = procedural_params();
    p.coverage = 0.2;
    SkyImage sky = render_procedural_sky(p, 0.0, n);
    sky.time_seconds = 100.0;
    SkyImage next = model().step(sky);
    EXPECT_EQ(next.resolution, n);
    EXPECT_DOUBLE_EQ(next.time_seconds, 130.0);
    validate_sky(next, "predicted sky");
    // The brightest input pixel (the sun) keeps its radiance (the [0, 1] form clips it; the model
    // re-inserts it).
    int best = 0;
    for (int p2 = 1; p2 < n * n; ++p2)
        if (sky.rgb[size_t(p2) * 3 + 1] > sky.rgb[size_t(best) * 3 + 1]) best = p2;
    const float sun_in = sky.rgb[size_t(best) * 3 + 1], sun_out = next.rgb[size_t(best) * 3 + 1];
    ASSERT_GT(sun_in, model().info().form.unit_map.max_radiance) << "the test sky should show the sun";
    EXPECT_EQ(sun_out, sun_in);
    // Nothing else gets brighter than the map's range: the sun is re-inserted, not spread.
    auto over = [&](const SkyImage& s) {
        int count = 0;
        for (float v : s.rgb) count += v > model().info().form.unit_map.max_radiance * 1.001;
        return count;
    };
    EXPECT_LE(over(next), over(sky));
}

TEST(CloudModel, MissingOrCorruptModelsGiveClearErrors) {
    const std::string dir = test::temp_dir("cloud_model_bad");
    EXPECT_NE(error_of([&] { CloudModel::load(dir + "/nowhere"); }).find("model folder not found"), std::string::npos);
    EXPECT_NE(error_of([&] { CloudModel::load(dir); }).find("model.json"), std::string::npos);
    // A copy of the shipped model, then broken piece by piece.
    for (const char* f : {"model.json", "flownet.onnx", "cloudnet.onnx"})
        fs::copy_file(shipped_model() + "/" + f, dir + "/" + f);
    EXPECT_EQ(error_of([&] { CloudModel::load(dir); }), "");
    { std::ofstream(dir + "/cloudnet.onnx") << "this is not a protobuf"; }
    std::string e = error_of([&] { CloudModel::load(dir); });
    EXPECT_NE(e.find("cloudnet.onnx"), std::string::npos) << e;
    fs::remove(dir + "/cloudnet.onnx");
    e = error_of([&] { CloudModel::load(dir); });
    EXPECT_NE(e.find("cloudnet.onnx: model file not found"), std::string::npos) << e;
    // A folder where the file belongs: named as such, not a filesystem library's message.
    fs::create_directory(dir + "/cloudnet.onnx");
    e = error_of([&] { CloudModel::load(dir); });
    EXPECT_NE(e.find("cloudnet.onnx: not a file"), std::string::npos) << e;
    fs::remove(dir + "/cloudnet.onnx");
    fs::copy_file(shipped_model() + "/cloudnet.onnx", dir + "/cloudnet.onnx");
    // model.json that disagrees with the networks' input size.
    nlohmann::json j;
    std::ifstream(dir + "/model.json") >> j;
    j["resolution"] = j["resolution"].get<int>() * 2;
    { std::ofstream(dir + "/model.json") << j.dump(); }
    e = error_of([&] { CloudModel::load(dir); });
    EXPECT_NE(e.find("flownet.onnx"), std::string::npos) << e;
    { std::ofstream(dir + "/model.json") << "{ not json"; }
    e = error_of([&] { CloudModel::load(dir); });
    EXPECT_NE(e.find("model.json: not a valid model description"), std::string::npos) << e;
    fs::remove_all(dir);
}

TEST(CloudModel, WrongInputSizeOrChannelsGiveClearErrors) {
    const int n = model().info().resolution;
    std::string e = error_of([&] { model().run_flownet(cv::Mat(n / 2, n / 2, CV_32FC3, cv::Scalar::all(0))); });
    EXPECT_NE(e.find("must be " + std::to_string(n) + " x " + std::to_string(n) + " x 3"), std::string::npos) << e;
    e = error_of([&] { model().run_flownet(cv::Mat(n, n, CV_32FC1, cv::Scalar::all(0))); });
    EXPECT_NE(e.find("x 1 float"), std::string::npos) << e;
    e = error_of([&] { model().step_network(cv::Mat(n, n, CV_8UC3, cv::Scalar::all(0))); });
    EXPECT_NE(e.find("non-float"), std::string::npos) << e;
    SkyImage black(n);
    e = error_of([&] { model().step(black); });
    EXPECT_NE(e.find("black everywhere"), std::string::npos) << e;
}

TEST(CloudModel, NpyRoundTrip) {
    const std::string dir = test::temp_dir("npy");
    std::vector<float> v = {1.5f, -2.0f, 3.25f, 0.0f, 7.0f, 1e-3f};
    write_npy(dir + "/a.npy", {2, 3}, v.data());
    NpyArray a = read_npy(dir + "/a.npy");
    EXPECT_EQ(a.shape, (std::vector<size_t>{2, 3}));
    EXPECT_EQ(a.data, v);
    std::vector<unsigned char> b = {0, 1, 255};
    write_npy(dir + "/b.npy", {3}, b.data());
    EXPECT_EQ(read_npy(dir + "/b.npy").data, (std::vector<float>{0, 1, 255}));
    { std::ofstream(dir + "/bad.npy") << "NUMPY?"; }
    EXPECT_NE(error_of([&] { read_npy(dir + "/bad.npy"); }).find("not a .npy file"), std::string::npos);
    fs::remove_all(dir);
}

}  // namespace
}  // namespace dynsky
