// What moves a sky over time (glossary: "sky source", "step model"): the input sky at t = 0 and
// the medium-step model xi with its Delta t, as specs, and the factory that turns them into a
// motion/sky_timeline.h SkyTimeline. `animate`, `compare` and the benchmarks build their moving
// skies here, so an option means the same thing everywhere.
#pragma once

#include <optional>
#include <string>

#include "frame/frame_metadata.h"
#include "motion/sky_timeline.h"
#include "sky/default_sky.h"
#include "sky/latlong.h"
#include "sky/sun_position.h"

namespace dynsky {

// The input sky S_0. Parameters (defaults):
//   sky             "procedural"  procedural[:SEED] (cumulus over a clear sky, known motion), clear
//                                 (Hosek-Wilkie), or a canonical fisheye .exr
//   sky_resolution  1024          N of skies made here (procedural, clear); given for a sky file
//                                 (sky_resolution_given), the file is resampled to N x N, else a
//                                 fisheye keeps its own and a lat-long its height, at most
//                                 kMovingLatlongLimit (sky/latlong.h)
//   sky_turn_deg    0             a sky file's azimuths plus this (its sun too): a downloaded HDRI's
//                                 sun put where the scene wants it; refused for skies made here
//   time            ""            ISO 8601 UTC of t = 0; the sun follows the clock from there.
//                                 Default 2026-06-21T16:00:00Z for skies made here; an EXR keeps its sun
//   latitude, longitude  48.8566, 2.3522 (Paris)
//   coverage        0.5           procedural cloud cover
//   evolution_s     900           seconds for the procedural cumulus to change shape completely
//                                 (0: frozen shapes, moved by the wind alone)
//   wind_from_deg, wind_speed_mps, cloud_height_m  270, 12, 1500  the wind at the clouds: it moves
//                                 the procedural sky's cumulus and, for any input, the clouds of the
//                                 models that take a motion (advect-residual, advect)
//   previous, previous_dt  "", 0  a frame of the same sky previous_dt seconds before the input (0:
//                                 one medium step): the motion is measured from it instead
struct SkySourceSpec {
    std::string sky = "procedural";
    int sky_resolution = 1024;
    bool sky_resolution_given = false;  // --sky-res was given: a sky file too is taken at N
    double sky_turn_deg = 0;            // --sky-turn: a sky file turned about the zenith (sky/latlong.h)
    std::string time;
    double latitude = default_sky::kLatitudeDeg, longitude = default_sky::kLongitudeDeg;
    double coverage = default_sky::kCoverage;
    double evolution_s = default_sky::kCloudEvolutionS;
    // --turbidity: of 'clear', and of the clear sky under the procedural clouds (Hosek-Wilkie, 1..10).
    double turbidity = default_sky::kTurbidity;
    double wind_from_deg = default_sky::kWindFromDeg, wind_speed_mps = default_sky::kWindSpeedMps;
    double cloud_height_m = default_sky::kCloudHeightM;
    // --wind-from or --wind-speed was given: the clouds of an input sky move with that wind, not with
    // the previous frame of a captured sequence (a folder); given with --prev, refused.
    bool wind_given = false;
    std::string previous;
    double previous_dt = 0.0;
};

// The step model xi. Parameters (defaults):
//   model            "auto"  auto | advect | paper | procedural | flow | network:FOLDER. auto: the
//                            shipped advect-residual network (networks/models/advect_residual)
//                            when installed, else advect (pure advection along the motion); paper:
//                            the paper's FlowNet + CloudNet (networks/models/arm_tsi)
//   dt               0       Delta t in seconds; 0: the model's own (a network's, advect 30), else 10
//   drift_deg_per_s  0.25    flow model: first-step drift of a single input sky (from wind_from_deg)
//   gamma            "constant"  the in-between of two steps (motion/sky_timeline.h GammaKind):
//                            constant (even pace) or paper (the paper's keys at 1/3 and 2/3)
struct StepModelSpec {
    std::string model = "auto";
    double dt = 0.0;
    double drift_deg_per_s = 0.25;
    std::string gamma = "constant";
};

// The checks of a sky and its model that need no file read (make_sky_timeline makes them first;
// `animate --count-frames` makes them so that a farm never queues a run that fails): the --sky
// spelling of a procedural sky, --prev with a wind, --model procedural on another sky, and a
// --dt that would make more than SkyTimeline::kMaxSteps steps of `duration`. Throws dynsky::Error
// naming the options.
void check_sky_source(const SkySourceSpec& sky, const StepModelSpec& model, double duration);

// True for the skies made here: 'clear' and 'procedural[:SEED]'.
bool is_generated_sky(const std::string& sky);

// What a rendered image was made from beyond its settings (`render`, `compare`): the build
// (Software), the scene and sky files as found, with their contents' sizes and hashes
// (dynsky:scene_file, dynsky:sky_file and their _contents; a relative scene name is looked up from
// the working folder first, then among the shipped scenes, so one command gave different images on
// two nodes with identical headers), and how the sky file was taken (dynsky:sky_turn_deg,
// dynsky:sky_res). scene_path: the file loaded ("builtin": none).
void record_image_inputs(ImageMetadata* m, const std::string& scene_path, const SkySourceSpec& sky);

// How a sky file of this spec is taken (--sky-res when given, --sky-turn; sky/latlong.h), a
// lat-long at most latlong_limit px unasked (0: its height).
SkyFileOptions sky_file_options(const SkySourceSpec& spec, int latlong_limit = 0);

// The sky made here at t = 0 ('clear' or 'procedural[:SEED]'; the sun of start_time at the spec's
// place): what `render --sky clear` shows and the timeline's input. Throws dynsky::Error naming
// the option at fault.
SkyImage make_generated_sky(const SkySourceSpec& sky);

// render's sky when none is given: a clear afternoon over Paris at the summer solstice (the place,
// time and turbidity of `--sky clear` everywhere), N x N.
SkyImage make_builtin_clear_sky(int resolution);

// Validates everything (files, ranges) before any step is computed.
SkyTimeline make_sky_timeline(const SkySourceSpec& sky, const StepModelSpec& model);

// What a sky timeline depends on, as frame settings (a subset of `animate`'s, the same keys; the
// model and Delta t as asked: "auto", 0 when automatic). A stored timeline records them and is used
// only for the same.
FrameSettings sky_timeline_settings(const SkySourceSpec& sky, const StepModelSpec& model);

// --model as the timeline takes it: auto, advect, paper, procedural, flow or network:FOLDER (a
// folder given bare gets the prefix). Throws dynsky::Error for anything else.
std::string step_model_name(const std::string& model);

// The contents of a cloud model's description and networks (model.json, *.onnx: name, size, hash),
// " [...]", for the settings frames and timelines are kept by: a retrained model, or the shipped
// one of another version, moves the clouds otherwise. "" for a model without a folder.
std::string cloud_model_files(const std::string& name);

// A stored timeline (glossary "stored timeline"): makes the timeline and saves the steps covering
// t in [0, duration] into `folder` (motion/sky_timeline.h SkyTimeline::save). A folder already
// holding one of these settings that covers the duration is kept (a rerun does nothing). Returns
// the last step stored.
int write_sky_timeline(const SkySourceSpec& sky, const StepModelSpec& model, double duration, const std::string& folder,
                       bool quiet);
// Reads a stored timeline for these settings; throws dynsky::Error naming the folder when it was
// made with others (and which differ) or is not a complete timeline. Gamma from `model`.
SkyTimeline load_sky_timeline(const std::string& folder, const SkySourceSpec& sky, const StepModelSpec& model);

// The UTC time of t = 0 (the default when the spec gives none: 2026-06-21T16:00:00Z).
UtcTime start_time(const SkySourceSpec& sky);

// When the sky at t seconds was (or is made to be): the clock's time for a generated sky or a
// given --time, else the time a sky file records being taken at (`sky import`'s), else nullopt.
std::optional<UtcTime> sky_time_at(const SkySourceSpec& sky, const SkyImage& input, double t);

// EXIF's "YYYY:MM:DD hh:mm:ss" of sky_time_at, or "" when it is not known (the frame then carries
// no DateTime: blanks were junk to asset tools).
std::string exif_date_time(const SkySourceSpec& sky, const SkyImage& input, double t);

}  // namespace dynsky
