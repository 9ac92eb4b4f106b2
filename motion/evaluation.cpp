#include "motion/evaluation.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "motion/advect_residual.h"
#include "motion/advection.h"
#include "motion/cloud_model.h"
#include "motion/flow.h"
#include "motion/metrics.h"
#include "motion/network_step_model.h"
#include "motion/photo_sequence.h"
#include "motion/sun_patch.h"
#include "sky/photo_import.h"
#include "sky/sun_position.h"
#include "util/atomic_file.h"
#include "util/chart.h"
#include "util/error.h"
#include "util/file_hash.h"
#include "util/image.h"
#include "util/interrupt.h"
#include "util/json_file.h"
#include "util/parse.h"
#include "util/progress.h"

namespace dynsky {

namespace {

// A file name as a Markdown link's target: what CommonMark or a URL reads as syntax (a space ends
// the target, '#' starts a fragment, '%' an escape, parentheses and angle brackets the link) is
// percent-encoded; "my report_64.png" showed no chart.
std::string link_target(const std::string& name) {
    std::string out;
    for (const char c : name) {
        if (std::string(" #%()<>[]\\").find(c) == std::string::npos) {
            out += c;
        } else {
            char hex[4];
            std::snprintf(hex, sizeof hex, "%%%02X", static_cast<unsigned char>(c));
            out += hex;
        }
    }
    return out;
}

namespace fs = std::filesystem;

struct Accumulator {
    double mse = 0, psnr = 0, ssim = 0;
    int count = 0;
    void add(const ImageComparison& c) { mse += c.mse, psnr += c.psnr, ssim += c.ssim, ++count; }
    MethodScore mean() const {
        MethodScore s;
        s.frames = count;
        if (count) s.mse = mse / count, s.psnr = psnr / count, s.ssim = ssim / count;
        return s;
    }
};

cv::Mat saturated_mask(const cv::Mat& unit) {
    std::vector<cv::Mat> ch;
    cv::split(unit, ch);
    return (ch[0] >= 0.999f) | (ch[1] >= 0.999f) | (ch[2] >= 0.999f);
}

// The wind fitted to a measured flow, where there is cloud to track (else everywhere seen).
Wind oracle_wind(const cv::Mat& flow, const cv::Mat& valid, const cv::Mat& cloud, double dt) {
    cv::Mat w = valid & cloud;
    if (cv::countNonZero(w) < 0.01 * cv::countNonZero(valid)) w = valid;
    return fit_wind(flow, w, dt);
}

std::string fmt(const char* f, double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

// Which frames of `seq` a model folder was trained on or chose itself with: every frame before the
// held-out part of a sequence in its split.json, and every frame of a sequence its model.json lists
// as trained on with no split to say what was held out. Frames are matched by capture time against
// the named sequences of the shared data, so a copy of their photographs, a renamed folder or skies
// imported from them are found too; a folder's name decides nothing.
struct TrainedFrames {
    std::vector<char> trained;           // per frame of seq
    std::string matched;                 // "arm_tsi frames 100-107 (trained on: before 240)"; empty: none
    std::vector<std::string> unchecked;  // training sequences whose photographs could not be read
};

// A frame whose next 20 minutes (the same camera) the model was trained on is not held out: at
// 10 m/s a layer at 1500 m crosses the view within 60 degrees of the zenith in about that time.
// Less than 20 minutes (by a second: capture times are whole seconds, and the same instant computed
// two ways differs in the last digits, which decided whether a frame exactly 20 minutes ahead counted).
constexpr double kSeenAheadSeconds = 20 * 60 - 1;

TrainedFrames model_training_frames(const PhotoSequence& seq, const std::string& model_folder,
                                    const std::string& shared) {
    TrainedFrames r;
    r.trained.assign(seq.photos.size(), 0);
    if (model_folder == "advect") return r;
    const fs::path split_path = fs::path(model_folder) / "split.json",
                   info_path = fs::path(model_folder) / "model.json";
    const nlohmann::json split = fs::exists(split_path) ? read_json(split_path.string()) : nlohmann::json::object();
    std::vector<std::string> sources;
    for (const auto& [name, v] : split.items()) sources.push_back(name);
    if (fs::exists(info_path)) {
        const nlohmann::json info = read_json(info_path.string());
        if (info.contains("trained_on") && info["trained_on"].is_array())
            for (const auto& name : info["trained_on"])
                if (name.is_string() &&
                    std::find(sources.begin(), sources.end(), name.get<std::string>()) == sources.end())
                    sources.push_back(name.get<std::string>());
    }
    for (const std::string& name : sources) {
        const nlohmann::json part = split.contains(name) ? split[name] : nlohmann::json::object();
        // A split made since 2026-12-07 names the photographs trained on and when they were taken
        // (split.json "trained_photos", "trained_utc_s": [first, last]): matched wherever they
        // lie. Frame numbers alone number the data set's own folder, which need not be the shared
        // sequence: a model trained on 25 frames of a copy was scored on them as held out.
        std::vector<std::string> trained_names;
        if (part.contains("trained_photos") && part["trained_photos"].is_array())
            for (const auto& v : part["trained_photos"])
                if (v.is_string()) trained_names.push_back(v.get<std::string>());
        double first = std::nan(""), last = std::nan("");
        if (part.contains("trained_utc_s") && part["trained_utc_s"].is_array() && part["trained_utc_s"].size() == 2 &&
            part["trained_utc_s"][0].is_number() && part["trained_utc_s"][1].is_number())
            first = part["trained_utc_s"][0].get<double>(), last = part["trained_utc_s"][1].get<double>();
        const double dt = part.contains("dt_s") && part["dt_s"].is_number() ? part["dt_s"].get<double>() : 30.0;
        if (std::isfinite(first) && first > last) std::swap(first, last);
        if (!trained_names.empty() || std::isfinite(first)) {
            // The camera of its photographs (the split's "preset", else the named sequences'): times
            // of another camera are other skies.
            std::string preset = part.contains("preset") && part["preset"].is_string()
                                     ? part["preset"].get<std::string>()
                                     : std::string();
            if (preset.empty() && name.rfind("arm_", 0) == 0) preset = "arm-tsi";
            if (preset.empty() && name == "mobotix") preset = "mobotix";
            // Names without times (a split of a data set built before frames_utc_s): the times
            // their names carry, on the camera's clock, so that imported skies of them and copies
            // under other names are found too.
            if (!std::isfinite(first) && !preset.empty()) {
                double offset = 0;
                try {
                    offset = camera_preset(preset).filename_utc_offset_hours;
                } catch (const Error&) {}
                for (const std::string& trained : trained_names)
                    if (const std::string iso = time_from_file_name(trained, offset); !iso.empty()) {
                        double t = std::nan("");
                        try {
                            t = utc_seconds(iso);
                        } catch (const Error&) {  // not a date after all: matched by its name alone
                            continue;
                        }
                        first = std::isfinite(first) ? std::min(first, t) : t;
                        last = std::isfinite(last) ? std::max(last, t) : t;
                    }
            }
            const double tolerance = std::max(1.0, 0.25 * dt);
            int count = 0, ahead = 0, lo = -1, hi = -1;
            for (size_t k = 0; k < seq.photos.size(); ++k) {
                const std::string base = fs::path(seq.photos[k]).filename().string();
                const bool timed = k < seq.utc.size() && std::isfinite(seq.utc[k]) && std::isfinite(first) &&
                                   (seq.preset.empty() || preset.empty() || seq.preset == preset);
                if (std::find(trained_names.begin(), trained_names.end(), base) != trained_names.end() ||
                    (timed && seq.utc[k] >= first - tolerance && seq.utc[k] <= last + tolerance)) {
                    r.trained[k] = 1, ++count;
                    lo = lo < 0 ? int(k) : lo, hi = int(k);
                } else if (timed && first - seq.utc[k] > 0 && first - seq.utc[k] <= kSeenAheadSeconds) {
                    r.trained[k] = 1, ++ahead;  // the same clouds, trained on later (below)
                }
            }
            if (ahead > 0)
                r.matched += (r.matched.empty() ? "" : "; ") + std::to_string(ahead) + " frames up to " +
                             std::to_string(std::lround(kSeenAheadSeconds / 60)) + " minutes before " + name +
                             "'s frames trained on (the same clouds, later)";
            if (count > 0)
                r.matched += (r.matched.empty() ? "" : "; ") + name + " frames trained on: " + std::to_string(count) +
                             " of these (" + (count == hi - lo + 1 ? "" : "among ") + "frames " + std::to_string(lo) +
                             "-" + std::to_string(hi) + "; its split.json " +
                             (trained_names.empty() ? std::string("gives the times of the photographs it trained on")
                                                    : "names the " + std::to_string(trained_names.size()) +
                                                          " photographs it trained on") +
                             ")";
            continue;
        }
        PhotoSequence known;
        try {
            known = named_photo_sequence(name, shared);
        } catch (const Error&) {
            // Procedural sources (proc_00, ...) are not photographs; a named one whose folder is
            // missing cannot be checked.
            if (name.rfind("proc", 0) != 0) r.unchecked.push_back(name);
            continue;
        }
        // Held out from this frame on (every frame trained on when the split does not say).
        int heldout = int(known.photos.size());
        if (split.contains(name) && split[name].contains("heldout") && split[name]["heldout"].is_array() &&
            !split[name]["heldout"].empty() && split[name]["heldout"][0].is_number_integer())
            heldout = split[name]["heldout"][0].get<int>();
        const bool same_folder = !seq.preset.empty() && fs::path(seq.folder) == fs::path(known.folder);
        int lo = -1, hi = -1, ahead = 0;
        for (size_t k = 0; k < seq.photos.size(); ++k) {
            int index = -1;
            if (same_folder) {
                index = int(k);
            } else if (k < seq.utc.size() && std::isfinite(seq.utc[k]) &&
                       (seq.preset.empty() || seq.preset == known.preset)) {
                const double t = seq.utc[k], tolerance = std::max(1.0, 0.25 * known.dt);
                for (size_t i = 0; i < known.utc.size() && index < 0; ++i)
                    if (std::abs(known.utc[i] - t) <= tolerance) index = int(i);
            }
            if (index >= 0 && index < heldout) {
                r.trained[k] = 1;
                lo = lo < 0 ? index : std::min(lo, index), hi = std::max(hi, index);
                continue;
            }
            // Trained on what came after it: the same clouds, later, within the time a wind takes to
            // carry them across the view (the ARM clear morning's last 20 minutes are the cloud field
            // that the broken-cumulus sequence, trained on, starts with 30 s later).
            if (same_folder || k >= seq.utc.size() || !std::isfinite(seq.utc[k]) ||
                (!seq.preset.empty() && seq.preset != known.preset))
                continue;
            for (int i = 0; i < std::min(heldout, int(known.utc.size())); ++i)
                if (const double lead = known.utc[size_t(i)] - seq.utc[k]; lead > 0 && lead <= kSeenAheadSeconds) {
                    r.trained[k] = 1, ++ahead;
                    break;
                }
        }
        if (ahead > 0)
            r.matched += (r.matched.empty() ? "" : "; ") + std::to_string(ahead) + " frames up to " +
                         std::to_string(std::lround(kSeenAheadSeconds / 60)) + " minutes before " + name +
                         "'s frames trained on (the same clouds, later)";
        if (lo >= 0)
            r.matched += (r.matched.empty() ? "" : "; ") + name + " frames " + std::to_string(lo) + "-" +
                         std::to_string(hi) + " trained on" +
                         (heldout < int(known.photos.size())
                              ? ", its split.json holding out frames " + std::to_string(heldout) +
                                    " on (frame numbers only, read as the shared sequence's: a data set built "
                                    "from part of it numbers its frames otherwise)"
                              : std::string(": model.json lists it, with no split.json to say what was held out"));
    }
    return r;
}

}  // namespace

EvaluationResult evaluate_cloud_model(const EvaluationOptions& o) {
    std::vector<int> horizons = parse_int_list(o.horizons, "--horizons");
    const std::vector<int> resolutions = parse_int_list(o.resolutions, "--resolutions");
    int hmax = horizons.back();
    if (o.limit < 0) throw Error("--limit: must be >= 0");
    check_import_resolution(o.import_resolution);
    for (int r : resolutions)
        if (r > o.import_resolution || o.import_resolution % r != 0)
            throw Error("--resolutions " + std::to_string(r) + ": must divide --import-res " +
                        std::to_string(o.import_resolution));
    if (o.sequence.empty() == o.photos.empty())
        throw Error(
            "--sequence, --photos: give exactly one of --sequence (arm-tsi, arm-clear, arm-dusk, mobotix) and --photos DIR --preset P");
    if (!o.photos.empty()) {
        std::error_code ec;
        if (!fs::exists(o.photos, ec)) throw_file_error(o.photos, "no such folder (--photos)");
        if (!fs::is_directory(o.photos, ec))
            throw_file_error(o.photos, "not a folder (--photos takes a folder of photographs or of imported skies)");
    }
    if (!o.photos.empty() && o.preset.empty() && !folder_holds_skies(o.photos)) {
        // The skies' folder the hint suggests: beside the photographs' (SKIES/ was the photographs' own
        // name when they were in a folder called so).
        fs::path photos_folder = fs::path(o.photos).lexically_normal();
        if (photos_folder.filename().empty()) photos_folder = photos_folder.parent_path();  // "DIR/"
        const std::string skies_folder = photos_folder.string() + "_skies/";
        throw Error(
            "--photos needs --preset (arm-tsi or mobotix) for photographs; a folder of skies imported with "
            "'dynsky sky import' (.exr, any camera) needs none: for another camera's photographs, import them "
            "first, under one sky circle ('dynsky sky import " +
            o.photos + " --lat DEG --lon DEG --utc-offset H --detect-obstructions -o " + skies_folder +
            "'), then --photos " + skies_folder);
    }
    const std::string shared = o.shared.empty() && !o.sequence.empty() ? default_shared_dir() : o.shared;
    // A folder that is not there yet (`-o out/`): an existing one is refused by the checks below.
    if (o.report.empty() || (o.report.back() == '/' && !fs::exists(o.report)))
        throw Error("--out " + o.report + ": a folder; give the report's file (" +
                    (fs::path(o.report) / "eval.md").lexically_normal().string() + "; a .csv and charts beside it)");
    if (const std::string ext = file_extension(o.report); ext == ".csv" || ext == ".png")
        throw Error("--out " + o.report + ": the report is Markdown, and its table (.csv) and charts (.png) are " +
                    "written beside it under its name: give a .md name, e.g. " +
                    fs::path(o.report).replace_extension(".md").string());
    // The report and what is written beside it must not replace an input or land in an input
    // folder (the photographs, the shared data of a named sequence, a model folder).
    std::vector<std::string> outputs = {o.report, fs::path(o.report).replace_extension(".csv").string()};
    for (int r : resolutions)
        for (const char* ext : {".csv", ".png"})
            outputs.push_back(fs::path(o.report).replace_extension("").string() + "_" + std::to_string(r) + ext);
    {
        const bool model_folder = o.model != "auto" && o.model != "advect" && o.model != "paper";
        check_outputs_are_not_inputs(outputs, {o.photos, shared, model_folder ? o.model : ""});
        for (const std::string& out : outputs) check_output_file(out);  // before the scoring, not after
    }
    // The models.
    const std::string folder = resolve_cloud_model(o.model);
    if (folder != "advect" && cloud_model_kind(folder) != "advect-residual")
        throw Error("--model " + o.model + ": a " + cloud_model_kind(folder) +
                    " model; the evaluation scores an advect-residual model (auto, advect or its folder) and the "
                    "paper's FlowNet + CloudNet beside it in its own column (--no-paper leaves it out)");
    AdvectResidualNetwork model = folder == "advect" ? AdvectResidualNetwork::pure_advection()
                                                     : AdvectResidualNetwork::load(folder);
    AdvectResidualNetwork advect = AdvectResidualNetwork::pure_advection(model.info().resolution, model.info().dt);
    for (int r : resolutions)  // said before the photographs are read, not at the first frame scored
        if (r < model.info().resolution)
            throw Error("--resolutions " + std::to_string(r) + ": below the " +
                        std::to_string(model.info().resolution) + " px the model steps at (its smallest)");
    PhotoSequence seq = o.sequence.empty() ? photo_sequence_from_folder(o.photos, o.preset)
                                           : named_photo_sequence(o.sequence, shared);

    std::optional<CloudModel> paper;
    std::string paper_folder, paper_note;  // paper_note: why the paper's model was asked for and not scored
    if (o.paper) {
        try {
            paper_folder = resolve_cloud_model("paper");
            paper = CloudModel::load(paper_folder);
        } catch (const Error&) {
            paper_note = "the paper's model is not installed: not scored";
            if (!o.quiet) std::fprintf(stderr, "dynsky: note: %s\n", paper_note.c_str());
        }
    }
    const NetworkFormParams& form = model.info().form;
    // The paper's model steps its own Delta t: as many steps per frame as fit the folder's cadence
    // (one step per 60 s Mobotix frame scored it on half the motion), else it is left out.
    int paper_steps = 1;
    if (paper && paper->info().dt > 0) {
        const double k = seq.dt / paper->info().dt;
        paper_steps = int(std::lround(k));
        if (paper_steps < 1 || std::abs(k - paper_steps) > 0.1 * k) {
            // Said in the report too (-q hid it, and the report had no paper column and no word why).
            paper_note = "the paper's model steps " + fmt("%g", paper->info().dt) +
                         " s, which does not divide the photographs' cadence of " + fmt("%g", seq.dt) +
                         " s: not scored";
            if (!o.quiet) std::fprintf(stderr, "dynsky: note: %s\n", paper_note.c_str());
            paper.reset();
        }
    }

    // Which start frames: the held-out part of a sequence the model was trained on, else all.
    const int count = int(seq.photos.size());
    // A short folder (the default 1,2,6 on five photographs) scores the horizons it can hold.
    if (o.frames.empty() && count - 2 - hmax < 0) {
        std::vector<int> fit;
        for (int h : horizons)
            if (count - 2 - h >= 0) fit.push_back(h);
        if (!fit.empty()) {
            std::string dropped, kept;
            auto append = [](std::string& list, int h) { list += (list.empty() ? "" : ", ") + std::to_string(h); };
            for (int h : horizons) append(h > fit.back() ? dropped : kept, h);
            if (!o.quiet)
                std::fprintf(stderr,
                             "dynsky: note: %s holds %d frames, too few for horizon(s) %s (h + 2 frames each): "
                             "scoring %s\n",
                             seq.folder.c_str(), count, dropped.c_str(), kept.c_str());
            horizons = fit, hmax = fit.back();
        }
    }
    int first = 1, last = count - 1 - hmax;
    const TrainedFrames trained = model_training_frames(seq, folder, shared.empty() ? default_shared_dir() : shared);
    // A start frame is held out when it and the frames it predicts were never trained on (the frame
    // before it only gives the motion).
    auto held_out = [&](int k) {
        for (int j = k; j <= k + hmax && j < count; ++j)
            if (trained.trained[size_t(j)]) return false;
        return true;
    };
    std::string part = "every frame (none of them among the model's training photographs)";
    std::string unchecked;
    for (const std::string& n : trained.unchecked) unchecked += (unchecked.empty() ? "" : ", ") + n;
    if (!unchecked.empty()) {  // said in the report, and warned even with -q: the scores may flatter the model
        part = "every frame (NOT checked against the model's training photographs: " + unchecked +
               " not found; give --shared)";
        std::fprintf(stderr,
                     "dynsky: warning: the model was trained on %s, whose photographs were not found (--shared): "
                     "whether these frames are among them is not checked\n",
                     unchecked.c_str());
    }
    if (!o.frames.empty()) {
        int a = 0, b = 0;
        std::stringstream ss(o.frames);
        char dash = 0;
        std::string rest;
        if (!(ss >> a) || (ss >> dash && (dash != '-' || !(ss >> b))) || (ss >> rest) || a < 0)
            throw Error("--frames '" + o.frames + "': expected A-B, start frames from 0 (first to last)");
        if (!dash) b = a;
        // Start frames need the frame before (the previous pair's flow) and h after.
        const std::string range = "the start frames of " + seq.folder + " are 1-" + std::to_string(last) + " (" +
                                  std::to_string(count) + " frames, horizon " + std::to_string(hmax) + ")";
        if (b < a && last >= 1)
            throw Error("--frames '" + o.frames + "': the last start frame is before the first; " + range);
        if ((b < 1 || a > last) && last >= 1)
            throw Error("--frames '" + o.frames + "': none of them can be scored; " + range);
        if ((a < 1 || b > last) && last >= 1 && !o.quiet)
            std::fprintf(stderr, "dynsky: note: --frames %s scores %d-%d: %s\n", o.frames.c_str(), std::max(1, a),
                         std::min(last, b), range.c_str());
        first = std::max(1, a), last = std::min(last, b);
        part = "start frames " + o.frames + " (--frames)";
        int seen = 0;
        for (int k = first; k <= last; ++k) seen += !held_out(k);
        if (seen > 0) {
            part += ", " + std::to_string(seen) + " of them predicting frames the model was trained on (" +
                    trained.matched + ")";
            if (!o.quiet)
                std::fprintf(stderr,
                             "dynsky: note: %d of the start frames scored predict frames the model was "
                             "trained on (%s): the scores flatter it\n",
                             seen, trained.matched.c_str());
        }
    } else if (!trained.matched.empty()) {
        // The longest run of held-out start frames (a split holds out the last part in time).
        int best_first = 1, best_len = 0;
        for (int k = 1; k <= last; ++k) {
            if (!held_out(k)) continue;
            int e = k;
            while (e + 1 <= last && held_out(e + 1)) ++e;
            if (e - k + 1 > best_len) best_first = k, best_len = e - k + 1;
            k = e;
        }
        if (best_len == 0)
            throw Error(seq.folder + ": every frame that could be scored at horizon " + std::to_string(hmax) +
                        " is one the model was trained on or chose itself with (" + trained.matched +
                        "): nothing held out to score. Give photographs it never saw, or --frames A-B to score "
                        "these anyway");
        first = best_first, last = best_first + best_len - 1;
        part =
            "the frames the model was never trained on, held out (last in time; for the shipped model some "
            "settings of the rollout were chosen looking at them: docs/networks-advect-residual.md, 'What the "
            "held-out parts were used for'): " +
            trained.matched;
    }
    if (o.limit > 0) last = std::min(last, first + o.limit - 1);
    if (last < first)
        throw Error(seq.folder + ": too few frames to score horizon " + std::to_string(hmax) + " (" +
                    std::to_string(count) + " frames)");

    // Imported skies leave out the pixels their import filled when a STEM.filled.png lies beside
    // them (sky import --filled-mask); say how many have one, since the scores depend on it.
    auto describe_filled = [&](int last_start, bool* all) -> std::string {
        if (!seq.preset.empty()) return "";
        int with_mask = 0;
        for (int k = first - 1; k <= last_start + hmax; ++k)
            with_mask += fs::exists(filled_mask_path(seq.photos[size_t(k)]));
        const int used = last_start + hmax - first + 2;
        *all = with_mask == used;
        return with_mask == used ? "every sky's filled pixels (STEM.filled.png) left out"
               : with_mask == 0
                   ? "no STEM.filled.png beside the skies: pixels their imports filled are scored too"
                   : std::to_string(with_mask) + " of the " + std::to_string(used) +
                         " skies with a STEM.filled.png (their filled pixels left out), the others scored whole";
    };
    bool every_sky_masked = true;
    std::string filled_note = describe_filled(last, &every_sky_masked);
    if (!filled_note.empty() && !every_sky_masked && !o.quiet)
        std::fprintf(stderr, "dynsky: note: %s\n", filled_note.c_str());

    // Import the frames needed (first - 1 .. last + hmax) once, at the import resolution.
    const int big = o.import_resolution;
    std::vector<NetworkFrame> frames;
    ProgressBar progress(last + hmax - first + 2, "import " + seq.name, o.quiet);
    for (int k = first - 1; k <= last + hmax; ++k) {
        frames.push_back(network_frame_from_photo(seq.photos[size_t(k)], seq.preset, big, big, form));
        progress.advance();
    }
    progress.finish();
    auto frame = [&](int k) -> const NetworkFrame& { return frames[size_t(k - (first - 1))]; };

    EvaluationResult result;
    result.sequence = seq.name;
    result.first = first, result.last = last, result.dt = seq.dt;
    result.methods = {"persistence", "farneback",   "farneback-linear", "advect+prev",
                      "model+prev",  "advect+wind", "model+wind"};
    if (paper) result.methods.push_back("paper");
    std::map<int, std::map<int, std::map<std::string, Accumulator>>> acc;
    // Farneback flows of consecutive pairs at the import resolution, computed once.
    std::map<int, cv::Mat> pair_flow;
    auto flow_from = [&](int k) -> const cv::Mat& {  // k -> k + 1
        auto it = pair_flow.find(k);
        if (it == pair_flow.end()) it = pair_flow.emplace(k, farneback_flow(frame(k).image, frame(k + 1).image)).first;
        return it->second;
    };
    // The models' estimate of the same (k -> k + 1): smoothed over the pixels both frames saw
    // unclipped, and confirmed by the flow measured back (motion/flow.h), computed once.
    std::map<int, MeasuredMotion> pair_motion;
    auto motion_from = [&](int k) -> const MeasuredMotion& {
        auto it = pair_motion.find(k);
        if (it == pair_motion.end()) {
            const cv::Mat trusted = frame(k).valid & frame(k + 1).valid & ~saturated_mask(frame(k).image) &
                                    ~saturated_mask(frame(k + 1).image);
            it = pair_motion
                     .emplace(k, consistent_motion(flow_from(k), farneback_flow(frame(k + 1).image, frame(k).image),
                                                   trusted))
                     .first;
        }
        return it->second;
    };
    // From here a first interrupt ends the scoring after the start frame under way (the import
    // before it stops at once, as any command does).
    std::optional<AllowGracefulStop> graceful;
    if (o.stop_on_request)
        graceful.emplace("finishing the start frame under way, then writing the report of the frames scored");
    ProgressBar progress2(long(last - first + 1) * long(resolutions.size()), "evaluate", o.quiet);
    // Start frames outer, resolutions inner: a run stopped by an interrupt has scored every
    // resolution of the frames it reached, and reports them.
    int scored_last = last;
    for (int t = first; t <= last; ++t) {
        if (t > first && o.stop_on_request && stop_requested()) {
            scored_last = t - 1;
            break;
        }
        for (int r : resolutions) {
            std::vector<NetworkFrame> f;
            for (int k = t - 1; k <= t + hmax; ++k) f.push_back(resample_frame(frame(k), r));
            auto at = [&](int k) -> const NetworkFrame& { return f[size_t(k - (t - 1))]; };
            const cv::Mat prev_flow = flow_at_resolution(flow_from(t - 1), r);
            const MeasuredMotion prev_motion = motion_from(t - 1).at_resolution(r);
            const cv::Mat next_flow = flow_at_resolution(flow_from(t), r);
            cv::Mat start = at(t).image.clone();
            fill_saturated_pixels(&start);
            const cv::Mat wind = wind_flow(r, oracle_wind(next_flow, at(t).valid, at(t).cloud, seq.dt), seq.dt);
            std::map<std::string, std::vector<cv::Mat>> pred;
            auto collect = [&](const std::string& name) {
                return [&pred, name](int, const cv::Mat& s) { pred[name].push_back(s.clone()); };
            };
            // The clear background of the frame's sun: only the clouds move (motion/advect_residual.h).
            cv::Mat bg;
            if (at(t).sun_direction) bg = clear_background(at(t).sun_direction->cast<double>(), r, form);
            CloudFlow motion = CloudFlow::from_measured(prev_motion, seq.dt, to_double(at(t).sun_direction));
            {
                // As motion_flow does: how much of the network's correction the previous pair takes.
                cv::Mat previous = at(t - 1).image.clone();
                const cv::Mat seen = at(t - 1).valid & at(t).valid & ~saturated_mask(previous) &
                                     ~saturated_mask(at(t).image);
                fill_saturated_pixels(&previous);
                motion.correction_gain = model.correction_gain(previous, start, seen,
                                                               prev_motion.confirmed.empty() ? prev_motion.smoothed
                                                                                             : prev_motion.confirmed);
            }
            advect.rollout_network_form(start, motion, hmax, collect("advect+prev"), bg);
            model.rollout_network_form(start, motion, hmax, collect("model+prev"), bg);
            model.rollout_network_form(start, CloudFlow::from_wind(wind), hmax, collect("model+wind"), bg);
            // The same wind without the network: what model+wind's oracle wind alone is worth.
            advect.rollout_network_form(start, CloudFlow::from_wind(wind), hmax, collect("advect+wind"), bg);
            // The previous pair's flow applied h times along its streamlines (the baseline), and
            // in one straight warp by h F (its linear form).
            for (int h = 1; h <= hmax; ++h) {
                pred["farneback"].push_back(warp_in_disc(at(t).image, traced_flow(prev_flow, h)));
                pred["farneback-linear"].push_back(warp_in_disc(at(t).image, prev_flow * double(h)));
            }
            if (paper && r == paper->info().resolution) {
                cv::Mat s = start;
                for (int h = 1; h <= hmax; ++h) {
                    for (int j = 0; j < paper_steps; ++j) s = paper->step_network(s).next;
                    pred["paper"].push_back(s);
                }
            }
            const cv::Mat sat_t = saturated_mask(at(t).image);
            for (int h : horizons) {
                const cv::Mat& truth = at(t + h).image;
                const cv::Mat mask = at(t + h).valid & at(t).valid & ~sat_t & ~saturated_mask(truth);
                if (cv::countNonZero(mask) == 0) continue;
                acc[r][h]["persistence"].add(compare_images(at(t).image, truth, mask));
                for (const auto& [name, list] : pred)
                    acc[r][h][name].add(compare_images(list[size_t(h - 1)], truth, mask));
            }
            progress2.advance();
        }
    }
    progress2.finish();
    if (scored_last < last) {
        if (!o.quiet)
            std::fprintf(stderr, "dynsky: interrupted: writing the report of start frames %d..%d (of %d..%d)\n", first,
                         scored_last, first, last);
        part += "; STOPPED by an interrupt after start frame " + std::to_string(scored_last) + " of " +
                std::to_string(first) + ".." + std::to_string(last);
        last = scored_last, result.last = scored_last;
        filled_note = describe_filled(last, &every_sky_masked);  // of the skies scored
        note_stopped_early();                                    // exit kInterrupted once the report is written
    }
    for (auto& [r, by_h] : acc)
        for (auto& [h, by_m] : by_h)
            for (auto& [m, a] : by_m) result.scores[r][h][m] = a.mean();

    // The report.
    std::ostringstream md, csv;
    csv << "resolution,horizon,ahead_s,method,psnr_db,ssim,mse,frames\n";
    md << "# Cloud model evaluation: " << (folder == "advect" ? "advect" : model.info().name) << " on " << seq.name
       << "\n\n";
    // Which model exactly: two runs of the same name told apart (a researcher's audit: reports of two
    // trainings were headed alike and named no folder).
    // A folder inside the working folder by its relative path (the reports in docs/ name no machine).
    auto shown = [](const std::string& path) {
        std::error_code ec;
        const fs::path rel = fs::relative(path, ec);
        return !ec && !rel.empty() && rel.begin()->string() != ".." ? rel.string() : path;
    };
    if (folder != "advect") {
        md << "Model: `" << shown(folder) << "` (kind " << model.info().kind << ", " << model.info().resolution
           << " px; " << describe_file((fs::path(folder) / "model.onnx").string()) << ")";
        if (paper)
            md << "; the paper's form: `" << shown(paper_folder) << "` ("
               << describe_file((fs::path(paper_folder) / "flownet.onnx").string()) << ", "
               << describe_file((fs::path(paper_folder) / "cloudnet.onnx").string()) << ")";
        md << ".\n\n";
    }
    md << "Photographs: `" << seq.folder << "` (" << count << " frames every " << seq.dt << " s, "
       << (seq.preset.empty() ? std::string("imported skies") : "preset " + seq.preset) << "); scored: " << part
       << ", start frames " << first << ".." << last << ". Imported at " << big
       << " px and area-averaged to each resolution; network form; pixels seen in both frames and not saturated"
       << (filled_note.empty() ? "" : " (" + filled_note + ")")
       << ". "
          "PSNR/SSIM: means of per-frame values. farneback = the previous pair's flow applied h times along its "
          "streamlines (motion/advection.h traced_flow; the rim extended so it never pulls in black); "
          "farneback-linear = one warp by h times that flow; the verdicts take the better of the two at each horizon; "
          "model+wind = from one frame with the wind fitted to the following pair's measured motion (an oracle: it "
          "has seen the frame after), advect+wind = that wind with no network"
       << (paper ? "; paper = the paper's FlowNet + CloudNet, " + std::to_string(paper_steps) + " step(s) of " +
                       fmt("%g", paper->info().dt) + " s per frame"
                 : std::string())
       << (paper_note.empty() ? std::string() : "; " + paper_note) << ".\n\n";
    // An earlier report under this name goes just before this one is written (after the scoring: a
    // bad photograph, Ctrl-C or a failure during it keeps the earlier report whole): a run stopped
    // midway through writing left its new CSV beside the old report and charts.
    remove_earlier_outputs(outputs);
    for (int r : resolutions) {
        md << "## " << r << " px\n\n| horizon | ahead |";
        for (const std::string& m : result.methods)
            if (!result.scores[r].empty() && result.scores[r].begin()->second.count(m)) md << " " << m << " PSNR |";
        md << " frames |\n|---:|---:|";
        for (const std::string& m : result.methods)
            if (!result.scores[r].empty() && result.scores[r].begin()->second.count(m)) md << "---:|";
        md << "---:|\n";
        // The chart shows each method over the better Farneback form (the margins are tenths of a dB
        // on PSNRs of 30-45 dB: drawn as PSNRs the lines lie on top of each other); the paper's
        // model, 10-20 dB below, only in the table.
        auto charted = [&](const std::string& m) {
            return m != "paper" && m != "farneback-linear" && !result.scores[r].empty() &&
                   result.scores[r].begin()->second.count(m);
        };
        std::ostringstream chart_csv;
        // The chart's values, not the scores (those are in the report's CSV): said in the header.
        chart_csv << "horizon (steps); the other columns: PSNR minus the better Farneback form's (dB)";
        for (const std::string& m : result.methods)
            if (charted(m)) chart_csv << "," << (m == "farneback" ? std::string("farneback (better form)") : m);
        chart_csv << "\n";
        for (int h : horizons) {
            auto& by_m = result.scores[r][h];
            md << "| " << h << " | " << h * seq.dt << " s |";
            chart_csv << h;
            int frames_scored = 0;
            for (const std::string& m : result.methods) {
                if (!by_m.count(m)) continue;
                const MethodScore& s = by_m[m];
                md << " " << fmt("%.2f", s.psnr) << " dB |";
                if (charted(m)) {
                    double best = by_m["farneback"].psnr;
                    if (by_m.count("farneback-linear")) best = std::max(best, by_m["farneback-linear"].psnr);
                    chart_csv << "," << fmt("%.4f", s.psnr - best);
                }
                csv << r << ',' << h << ',' << h * seq.dt << ',' << m << ',' << fmt("%.4f", s.psnr) << ','
                    << fmt("%.5f", s.ssim) << ',' << fmt("%.7f", s.mse) << ',' << s.frames << '\n';
                frames_scored = s.frames;
            }
            md << " " << frames_scored << " |\n";
            chart_csv << "\n";
        }
        // Verdicts: the model against each baseline, at every horizon.
        // b: the baselines, the best of them at each horizon.
        auto beats = [&](const std::string& a, const std::vector<std::string>& b) {
            std::string out;
            bool all = true;
            for (int h : horizons) {
                auto& by_m = result.scores[r][h];
                double best = -1e300;
                for (const std::string& m : b)
                    if (by_m.count(m)) best = std::max(best, by_m[m].psnr);
                if (!by_m.count(a) || best == -1e300) return std::string("n/a");
                const double d = by_m[a].psnr - best;
                all = all && d > 0;
                out += (out.empty() ? "" : ", ") + fmt("%+.2f dB", d);
            }
            return std::string(all ? "yes" : "NO") + " (" + out + ")";
        };
        md << "\nmodel+prev beats farneback (the better of its two forms) at every horizon: "
           << beats("model+prev", {"farneback", "farneback-linear"})
           << "; model+wind beats persistence at every horizon: " << beats("model+wind", {"persistence"})
           << "; model+wind beats advect+wind (the same wind, no network): " << beats("model+wind", {"advect+wind"})
           << ".\n\n";
        const std::string base = fs::path(o.report).replace_extension("").string() + "_" + std::to_string(r);
        write_file_atomic(base + ".csv", chart_csv.str());
        make_line_chart(base + ".csv", base + ".png",
                        seq.name + ", " + std::to_string(r) + " px: PSNR over the Farneback baseline", "steps ahead",
                        "PSNR minus Farneback's (dB)", false);
        md << "![PSNR over the Farneback baseline against horizon at " << r << " px]("
           << link_target(fs::path(base + ".png").filename().string()) << ")\n\n";
    }
    // The paper's table: MSE, PSNR and SSIM one step ahead.
    md << "## One step ahead (the paper's table)\n\n";
    if (std::find(horizons.begin(), horizons.end(), 1) == horizons.end())
        md << "Not scored: horizon 1 is not among --horizons (" << o.horizons << ").\n";
    else md << "| resolution | method | MSE | PSNR | SSIM |\n|---:|---|---:|---:|---:|\n";
    for (int r : resolutions)
        for (const std::string& m : result.methods)
            if (result.scores[r].count(1) && result.scores[r][1].count(m)) {
                const MethodScore& s = result.scores[r][1][m];
                md << "| " << r << " | " << m << " | " << fmt("%.5f", s.mse) << " | " << fmt("%.2f dB", s.psnr) << " | "
                   << fmt("%.3f", s.ssim) << " |\n";
            }
    result.markdown = md.str();
    if (!fs::path(o.report).parent_path().empty()) fs::create_directories(fs::path(o.report).parent_path());
    write_file_atomic(fs::path(o.report).replace_extension(".csv").string(), csv.str());
    write_file_atomic(o.report, result.markdown);
    if (!o.quiet) std::printf("%s\nwrote %s\n", result.markdown.c_str(), o.report.c_str());
    return result;
}

}  // namespace dynsky
