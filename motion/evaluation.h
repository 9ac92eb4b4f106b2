// The evaluation protocol of cloud models (`dynsky sky evaluate`): on real photo sequences, every
// method predicts from the same frames in one run and is scored against the real frames h steps
// later, at several resolutions, in the network form (motion/network_form.h):
//
//   persistence     the frame itself
//   farneback       the frame advected along the Farneback flow of the previous pair applied h times
//                   along its streamlines (motion/advection.h traced_flow: the iterated form of
//                   two-frame extrapolation), in one warp with the rim extended (warp_in_disc), so it
//                   never pulls in black
//   farneback-linear the same flow in one straight warp by h F; verdicts take the better of the two
//   advect+prev     pure advection along the models' motion estimate of the previous pair (that flow
//                   smoothed where the flow measured back does not confirm it: motion/flow.h
//                   consistent_motion), stepped h times, over the clear background of the frame's
//                   sun (only the clouds move; motion/advect_residual.h); no network
//   model+prev      the advect-residual model given the previous frame (that motion, fixed)
//   model+wind      the same model from one frame and the true wind: the uniform wind fitted to the
//                   measured motion of the following pair (an oracle for "the wind is known")
//   advect+wind     that wind with no network (what the oracle wind alone is worth)
//   paper           the paper's FlowNet + CloudNet from one frame (at its own 64 px only)
//
// Frames are imported with the camera preset (sky/preset_import.h) at the import resolution and
// area-averaged to each resolution; scored pixels: seen in both frames (not the arm, band or masts)
// and not saturated in either (the sun, which every model puts back from the input). PSNR and SSIM
// are means of per-frame values (motion/metrics.h). Which frames: the model's held-out part
// (split.json) for a sequence it was trained on, else every frame, or --frames; frames whose next
// 20 minutes of the same camera the model was trained on (another sequence) are not held out.
// model+prev takes the share of the network's correction its previous pair supports
// (AdvectResidualNetwork::correction_gain), as `sky predict --prev` and `animate` do.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace dynsky {

// Parameters (defaults): model "auto" (motion/network_step_model.h resolve_cloud_model); a named
// sequence (motion/photo_sequence.h) or a folder of photos with its preset; shared "" (the default
// shared folder); horizons "1,2,6"; resolutions "64,256"; frames "" (see above; "A-B": start frames
// A..B of the sequence); report "evaluation.md" (with .csv and _RES.png charts beside it);
// import_resolution 256; limit 0 (all start frames; K: only the first K); paper true (also the
// paper's model when installed); quiet false; stop_on_request false (true: an interrupt,
// util/interrupt.h, ends the scoring after the start frame under way, and the report of the frames
// scored is written, saying so; `sky evaluate` sets it).
struct EvaluationOptions {
    std::string model = "auto";
    std::string sequence, photos, preset, shared;
    std::string horizons = "1,2,6", resolutions = "64,256", frames;
    std::string report = "evaluation.md";
    int import_resolution = 256, limit = 0;
    bool paper = true;
    bool quiet = false;
    bool stop_on_request = false;
};

struct MethodScore {
    double mse = 0, psnr = 0, ssim = 0;
    int frames = 0;
};

struct EvaluationResult {
    std::string sequence;
    int first = 0, last = 0;  // start frames scored
    double dt = 0;
    std::vector<std::string> methods;
    // resolution -> horizon -> method -> score
    std::map<int, std::map<int, std::map<std::string, MethodScore>>> scores;
    std::string markdown;
};

// Scores and writes the report (markdown, CSV, charts). Throws dynsky::Error before writing
// anything for bad options, a folder without a regular sequence, or too few frames.
EvaluationResult evaluate_cloud_model(const EvaluationOptions& o);

}  // namespace dynsky
