// Stored timelines (motion/sky_timeline.h SkyTimeline::save / load): the medium steps, the flows
// between them and the sun patches, written once so that frames rendered anywhere read them.
//
// Exactness is the point: steps are float EXRs (zip, lossless) and flows float .npy, so the values
// read back are the values computed; every double and float of the metadata goes through JSON,
// whose numbers round-trip. A frame made from a loaded timeline therefore has the same bits as the
// frame of a run that computed the steps itself.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "motion/sky_timeline.h"

#include <sys/stat.h>
#include "util/atomic_file.h"
#include "util/error.h"
#include "util/npy.h"
#include "util/parse.h"
#include "util/progress.h"

namespace dynsky {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Throws naming `file` unless every value of `a` is finite and within [lo, hi].
void check_values(const NpyArray& a, const std::string& file, const std::string& what, float lo, float hi) {
    for (size_t k = 0; k < a.data.size(); ++k) {
        const float v = a.data[k];
        if (!std::isfinite(v) || v < lo || v > hi)
            throw_file_error(file, "value " + std::to_string(k) + " is " + number_text(v) + ": not " + what +
                                       " (expected finite values in [" + number_text(lo) + ", " + number_text(hi) +
                                       "]); a damaged timeline: make it again");
    }
}

// 2: the steps keep the input's sun and frames are relit to the clock (SkyTimeline::relight_to_clock).
// 3 since 2026-12-07: the suns' patches record where in its pixel the sun was cut (fx, fy), which
// insert_sun moves them by; a timeline of 2 would give other frames than a run without it.
constexpr const char* kFormat = "dynsky sky timeline 3";

std::string numbered(const std::string& folder, const char* prefix, int i, const char* ext) {
    char name[64];
    std::snprintf(name, sizeof name, "%s_%04d%s", prefix, i, ext);
    return (fs::path(folder) / name).string();
}

// Stands in for the model of a loaded timeline: its name and sun habit, never asked for a step
// (the stored steps answer, and asking beyond them is an error before the model is reached).
class StoredStepModel : public MediumStepModel {
  public:
    StoredStepModel(std::string name, bool own_sun, double native_dt)
        : name_(std::move(name)), own_sun_(own_sun), native_dt_(native_dt) {}
    SkyImage step(const std::vector<std::shared_ptr<const SkyImage>>&, double) override {
        throw Error("stored sky timeline: the model cannot run here");
    }
    std::string name() const override { return name_; }
    bool makes_own_sun() const override { return own_sun_; }
    double native_dt() const override { return native_dt_; }

  private:
    std::string name_;
    bool own_sun_;
    double native_dt_;
};

json vec_json(const std::optional<Vec3>& v) {
    if (!v) return nullptr;
    return json::array({(*v)[0], (*v)[1], (*v)[2]});
}

std::optional<Vec3> vec_from(const json& j) {
    if (j.is_null()) return std::nullopt;
    return Vec3(j.at(0).get<float>(), j.at(1).get<float>(), j.at(2).get<float>());
}

}  // namespace

// How often a timeline being saved describes the steps written so far.
constexpr std::chrono::seconds kDescriptionInterval{10};

void SkyTimeline::save(const std::string& folder, int last_step, const std::string& settings, bool quiet) {
    if (last_step < 1) throw Error("sky timeline: a stored timeline holds at least steps 0 and 1");
    const OutputFolder made(folder);  // removed again if this fails before writing anything
    // Found before the steps are computed (minutes for a long timeline), not at the first write.
    check_output_file((fs::path(folder) / "timeline.json").string());
    remove_stale_temporaries(folder);  // of a killed run into the same folder
    step(1);                           // the input's cloud opacity comes with step 1
    // An earlier timeline's description goes before any of its steps is replaced: a run that stops
    // midway (a full disk, Ctrl-C) must not leave it describing this run's steps.
    remove_stale_marker((fs::path(folder) / "timeline.json").string());
    json clock = nullptr;
    if (clock_)
        clock = {{"start",
                  {clock_->start.year, clock_->start.month, clock_->start.day, clock_->start.hour, clock_->start.minute,
                   clock_->start.second}},
                 {"lat", clock_->where.latitude_deg},
                 {"lon", clock_->where.longitude_deg},
                 {"elevation", clock_->where.elevation_m}};
    json steps = json::array(), flows = json::array(), suns = json::array();
    // Each step is written as soon as it is computed, and the description after it: a run that
    // stops midway (Ctrl-C, a killed job, a full disk) leaves a timeline of the steps it finished,
    // which animate --timeline renders up to their end. Written only at the end, an hour of steps
    // was lost with the last minute.
    ProgressBar progress(last_step + 1, "sky timeline", quiet);
    auto described = std::chrono::steady_clock::now();
    int described_step = 0, written_step = -1;
    // timeline.json of steps 0..last (their files written), replaced atomically.
    auto describe = [&](int last) {
        auto first = [](const json& list, int n) {  // a step the error stopped midway is left out
            json r = json::array();
            for (int k = 0; k < n; ++k) r.push_back(list[size_t(k)]);
            return r;
        };
        json j = {{"format", kFormat},
                  {"settings", settings},
                  {"dt", dt_},
                  {"last_step", last},
                  {"model", model_->name()},
                  {"model_makes_own_sun", model_->makes_own_sun()},
                  {"model_native_dt", model_->native_dt()},
                  {"input_time", input_time_},
                  {"input_units", input_units_},
                  {"input_sun",
                   input_sun_ ? json::array({(*input_sun_)[0], (*input_sun_)[1], (*input_sun_)[2]}) : json(nullptr)},
                  {"input_look_transmittance", input_look_transmittance_},
                  {"radiance_scale", radiance_scale_},
                  {"clock", clock},
                  {"steps", first(steps, last + 1)},
                  {"flows", first(flows, last)},
                  {"suns", first(suns, last + 1)}};
        write_file_atomic((fs::path(folder) / "timeline.json").string(), j.dump(1) + "\n");
        described = std::chrono::steady_clock::now(), described_step = last;
    };
    try {
        for (int i = 0; i <= last_step; ++i) {
            auto s = step(i);
            const std::string file = numbered(folder, "step", i, ".exr");
            save_sky(file, *s);
            // The model's cloud opacity (float .npy), when it gave one.
            json opacity = nullptr;
            if (size_t(i) < model_opacity_.size() && !model_opacity_[size_t(i)].empty()) {
                cv::Mat o = model_opacity_[size_t(i)];
                if (o.type() != CV_32FC1) throw Error("sky timeline: a cloud opacity map is not 1-channel float");
                if (!o.isContinuous()) o = o.clone();
                const std::string opacity_file = numbered(folder, "opacity", i, ".npy");
                write_npy(opacity_file, {size_t(o.rows), size_t(o.cols)}, o.ptr<float>());
                opacity = fs::path(opacity_file).filename().string();
            }
            steps.push_back({{"file", fs::path(file).filename().string()},
                             {"time", s->time_seconds},
                             {"sun", vec_json(s->sun_direction)},
                             {"source", s->source},
                             {"cloud_opacity", opacity}});
            json excess = json::array();
            for (const Color& c : suns_[size_t(i)].excess) excess.push_back({c[0], c[1], c[2]});
            suns.push_back({{"di", suns_[size_t(i)].di},
                            {"dj", suns_[size_t(i)].dj},
                            {"excess", excess},
                            {"fx", suns_[size_t(i)].fx},
                            {"fy", suns_[size_t(i)].fy}});
            if (i > 0) {
                cv::Mat f = flow(i - 1);
                if (f.type() != CV_32FC2 || !f.isContinuous()) f = f.clone();
                if (f.type() != CV_32FC2) throw Error("sky timeline: a flow is not 2-channel float");
                const std::string flow_file = numbered(folder, "flow", i - 1, ".npy");
                write_npy(flow_file, {size_t(f.rows), size_t(f.cols), 2}, f.ptr<float>());
                flows.push_back(fs::path(flow_file).filename().string());
                // After the files it names: a folder without it (a killed keys job before step 1) is
                // not a timeline, and one describes only steps that are whole. After step 1, every
                // kDescriptionInterval, after the last step and when an error stops the run: written
                // after every step, a long timeline of small steps wrote gigabytes of descriptions.
                written_step = i;
                if (i == last_step || i == 1 || std::chrono::steady_clock::now() - described >= kDescriptionInterval)
                    describe(i);
            }
            progress.advance();
        }
    } catch (...) {
        // Stopped by an error (a model's, a full disk): the steps written so far are described.
        if (written_step > described_step) try {
                describe(written_step);
            } catch (...) {  // the error that stopped it is the one to report
            }
        throw;
    }
    progress.finish();
}

namespace {

// A file's identity: inode, size and modification time (empty when it is gone). A replaced file
// is a new inode (written whole and renamed in).
std::string file_identity(const std::string& path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) return "";
    return std::to_string(st.st_ino) + ":" + std::to_string(st.st_size) + ":" + std::to_string(st.st_mtim.tv_sec) +
           "." + std::to_string(st.st_mtim.tv_nsec);
}

}  // namespace

void SkyTimeline::check_stored_unchanged() const {
    const std::string path = (fs::path(stored_folder_) / "timeline.json").string();
    if (file_identity(path) != stored_identity_)
        throw_file_error(path,
                         "the stored sky timeline was replaced or removed while this run read it (another keys "
                         "run?): its frames would mix two timelines; run again once the timeline is complete");
}

SkyTimeline SkyTimeline::load(const std::string& folder, std::string* settings) {
    const std::string path = (fs::path(folder) / "timeline.json").string();
    const std::string identity = file_identity(path);
    std::ifstream in(path, std::ios::binary);
    if (!in)
        throw_file_error(folder,
                         "no stored sky timeline here (timeline.json missing: make it with 'dynsky sky "
                         "timeline' or 'dynsky animate --stage keys')");
    json j;
    try {
        j = json::parse(in);
        if (j.at("format").get<std::string>() != kFormat)
            throw_file_error(path, "not a stored sky timeline of this version (format '" +
                                       j.at("format").get<std::string>() + "', this dynsky reads '" + kFormat +
                                       "'): make it again with 'dynsky sky timeline'");
        SkyTimeline t;
        t.dt_ = j.at("dt").get<double>();
        t.stored_last_step_ = j.at("last_step").get<int>();
        if (!(t.dt_ > 0) || t.stored_last_step_ < 1) throw_file_error(path, "bad Delta t or step count");
        t.stored_folder_ = folder;
        t.stored_identity_ = identity;
        t.model_ = std::make_unique<StoredStepModel>(j.at("model").get<std::string>(),
                                                     j.at("model_makes_own_sun").get<bool>(),
                                                     j.at("model_native_dt").get<double>());
        t.input_time_ = j.at("input_time").get<double>();
        t.input_units_ = j.value("input_units", std::string());  // absent before 2026-12-07: unsaid
        if (!j.at("input_sun").is_null())
            t.input_sun_ = Vec3d(j["input_sun"][0].get<double>(), j["input_sun"][1].get<double>(),
                                 j["input_sun"][2].get<double>());
        // Before 2026-12-05 stored at least 0.05 under another name.
        t.input_look_transmittance_ = j.contains("input_look_transmittance")
                                          ? j.at("input_look_transmittance").get<double>()
                                          : j.at("input_transmittance").get<double>();
        t.radiance_scale_ = j.value("radiance_scale", 1.0);  // absent before 2026-12-04: at scale
        if (!(t.radiance_scale_ > 0 && std::isfinite(t.radiance_scale_)))
            throw_file_error(path, "radiance_scale is not a positive number");
        if (!j.at("clock").is_null()) {
            const json& c = j["clock"];
            const json& s = c.at("start");
            UtcTime start{s.at(0).get<int>(), s.at(1).get<int>(), s.at(2).get<int>(),
                          s.at(3).get<int>(), s.at(4).get<int>(), s.at(5).get<double>()};
            t.clock_ = SunClock{start, GeoLocation{c.at("lat").get<double>(), c.at("lon").get<double>(),
                                                   c.at("elevation").get<double>()}};
        }
        for (const json& p : j.at("suns")) {
            SunPatch patch;
            patch.di = p.at("di").get<std::vector<int>>();
            patch.dj = p.at("dj").get<std::vector<int>>();
            for (const json& c : p.at("excess"))
                patch.excess.emplace_back(c[0].get<float>(), c[1].get<float>(), c[2].get<float>());
            // Where in its pixel the sun was cut (format 3 on).
            if (!p.contains("fx") || !p.contains("fy") || !p["fx"].is_number() || !p["fy"].is_number())
                throw_file_error(path, "a sun patch without its position in its pixel (fx, fy)");
            patch.fx = p["fx"].get<double>(), patch.fy = p["fy"].get<double>();
            t.suns_.push_back(std::move(patch));
        }
        if (int(t.suns_.size()) != t.stored_last_step_ + 1 || int(j.at("steps").size()) != t.stored_last_step_ + 1 ||
            int(j.at("flows").size()) != t.stored_last_step_)
            throw_file_error(path, "the step, flow and sun lists do not agree with last_step");
        t.steps_.resize(size_t(t.stored_last_step_) + 1);
        // The model's cloud opacity maps (absent in timelines stored before there were any).
        t.model_opacity_.resize(t.steps_.size());
        for (size_t i = 0; i < t.steps_.size(); ++i) {
            const json& e = j["steps"][i];
            if (!e.contains("cloud_opacity") || e["cloud_opacity"].is_null()) continue;
            const std::string file = (fs::path(folder) / e["cloud_opacity"].get<std::string>()).string();
            NpyArray a = read_npy(file);
            if (a.shape.size() != 2 || a.shape[0] != a.shape[1] || a.shape[0] == 0)
                throw_file_error(file, "is not a square cloud opacity map");
            check_values(a, file, "a cloud opacity", -1e-3f, 1.001f);
            cv::Mat o(int(a.shape[0]), int(a.shape[1]), CV_32FC1);
            std::copy(a.data.begin(), a.data.end(), o.ptr<float>());
            t.model_opacity_[i] = o;
        }
        t.stored_steps_json_ = j.at("steps").dump();
        if (settings) *settings = j.at("settings").get<std::string>();
        t.step(0);  // read now: a broken folder fails before any frame
        return t;
    } catch (const json::exception& e) {
        throw_file_error(path, std::string("not a readable stored sky timeline: ") + e.what());
    }
}

void SkyTimeline::verify_stored() {
    for (int i = 0; i <= stored_last_step_; ++i) {
        stored_step(i);
        if (i < stored_last_step_) stored_flow(i);
    }
}

std::shared_ptr<const SkyImage> SkyTimeline::stored_step(int i) {
    if (i > stored_last_step_)
        throw_file_error(stored_folder_, "the stored sky timeline ends at step " + std::to_string(stored_last_step_) +
                                             " (t = " + std::to_string(stored_last_step_ * dt_) +
                                             " s); make it again with a --duration covering every frame");
    if (!steps_[size_t(i)]) {
        const json entry = json::parse(stored_steps_json_).at(size_t(i));
        SkyImage s = load_sky((fs::path(stored_folder_) / entry.at("file").get<std::string>()).string());
        check_stored_unchanged();  // the step read is this timeline's
        // The metadata as computed (the EXR's sun is normalised again on reading).
        s.time_seconds = entry.at("time").get<double>();
        s.sun_direction = vec_from(entry.at("sun"));
        s.source = entry.at("source").get<std::string>();
        steps_[size_t(i)] = std::make_shared<const SkyImage>(std::move(s));
        // Frames run forwards: steps two behind are not needed again (step 0 is: t = 0's exposure).
        for (int k = 1; k < i - 1; ++k) steps_[size_t(k)].reset();
    }
    return steps_[size_t(i)];
}

cv::Mat SkyTimeline::stored_flow(int i) const {
    const std::string file = numbered(stored_folder_, "flow", i, ".npy");
    NpyArray a = read_npy(file);
    check_stored_unchanged();  // the flow read is this timeline's
    const int n = steps_[0]->resolution;
    if (a.shape != std::vector<size_t>{size_t(n), size_t(n), 2})
        throw_file_error(file, "is not an N x N x 2 flow of this timeline's N = " + std::to_string(n));
    // A step moves a cloud less than across the whole image; anything else is a damaged file
    // (a NaN here crashed the warp).
    check_values(a, file, "a flow (pixels per step)", -2.0f * float(n), 2.0f * float(n));
    cv::Mat f(n, n, CV_32FC2);
    std::copy(a.data.begin(), a.data.end(), f.ptr<float>());
    return f;
}

}  // namespace dynsky
