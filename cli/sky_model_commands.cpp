// dynsky sky predict | evaluate | training-data: the cloud models run on skies (motion/prediction.h),
// scored against real sequences and the two baselines (motion/evaluation.h), and the C++ half of
// the training-set builder (motion/training_set.h; networks/dataset.py drives it; docs/networks.md).
#include <memory>

#include "cli/commands.h"
#include "cli/options.h"
#include "motion/evaluation.h"
#include "motion/photo_sequence.h"
#include "motion/prediction.h"
#include "motion/training_set.h"
#include "sky/cloud_mask.h"
#include "sky/photo_import.h"
#include "sky/sky_image.h"
#include "util/atomic_file.h"

namespace dynsky::cli {

void register_sky_model_commands(CLI::App& sky) {
    {
        auto o = std::make_shared<PredictionOptions>();
        CLI::App* cmd = sky.add_subcommand(
            "predict",
            "Move the clouds of a sky forward with a cloud model (docs/networks.md): K recursive medium steps\n"
            "of Delta t (the model's, e.g. 30 s). The default model advects the clouds along a given motion\n"
            "(--prev: measured from a previous frame; --wind-from/--wind-speed; else the default wind) and a\n"
            "small network corrects. Writes DIR/step_0001.exr ... (canonical fisheye radiance; the sun of the\n"
            "input is kept). A sky without its sun direction (imported without time and place, or an HDRI of its\n"
            "own units) is moved at the networks' scale and back, its sun taken where it is brightest.");
        cmd->add_option("--model", o->model,
                        "Model: auto (networks/models/advect_residual), advect (pure advection along the motion),\n"
                        "paper (the paper's FlowNet + CloudNet, networks/models/arm_tsi), or a model folder")
            ->capture_default_str();
        o->model = "auto";
        auto wind = std::make_shared<Wind>();
        // The same ranges as animate, compare and timeline (cli/options.cpp).
        auto from = cmd->add_option("--wind-from", wind->from_deg,
                                    "Where the wind blows from, degrees clockwise from north (default 270)")
                        ->check(finite_in(-360, 360));
        auto speed = cmd->add_option("--wind-speed", wind->speed_mps, "Wind speed at the clouds, m/s (default 12)")
                         ->check(finite_in(0, 300));
        auto height = cmd->add_option("--cloud-height", wind->cloud_height_m,
                                      "Height of the cloud layer the wind moves, metres (default 1500: cumulus)")
                          ->check(finite_in(10, 1e5));
        cmd->add_option("--prev", o->previous,
                        "A previous frame of the same sky (EXR): the motion is measured from it (previous -> --sky), "
                        "and the share of the network's first correction the pair supports");
        cmd->add_option("--prev-dt", o->previous_dt, kPrevDtHelp)->check(finite_in(0, 86400));
        cmd->parse_complete_callback([o, wind, from, speed, height] {
            if (from->count() || speed->count() || height->count()) o->wind = *wind;
        });
        cmd->add_option(
            "--sky", o->in,
            "Input sky (canonical fisheye EXR, any resolution; or a 2:1 lat-long HDRI, whose upper half is\n"
            "taken, at most 2048 px unless --sky-res says; or a folder of skies, a captured sequence: on from\n"
            "its last, the one before it the previous frame, as animate takes one)");
        add_hidden_alias(cmd, "--in", &o->in);
        cmd->add_option("--sky-turn", o->turn_deg, kSkyTurnHelp)->check(finite_in(-360, 360));
        cmd->add_option("--sky-res", o->resolution,
                        "Take the input sky (and --prev) at N x N (resampled; a 2:1 lat-long converted at N). "
                        "Default: a fisheye's own size, a lat-long's height, at most 2048")
            ->check(CLI::Range(kMinSkyResolution, kMaxSkyResolution));
        cmd->add_option("--out,-o", o->out, "Output folder (created if missing)")->required();
        cmd->add_option("--steps", o->steps, "Number of medium steps K (1..100000)")->capture_default_str();
        cmd->add_option("--every", o->every, "Write only every M-th step (and the last)")->capture_default_str();
        cmd->add_option("--stats", o->stats,
                        "CSV of per-step statistics (mean luminance, mean/min/max of the [0,1] form, cloud\n"
                        "coverage, high-frequency energy, mean luminance without the start's sun pixels,\n"
                        "non-finite pixel count), step 0 = the input");
        cmd->add_flag("--previews", o->preview,
                      "Also write tone-mapped PNGs beside the EXRs (the input's auto exposure)");
        cmd->add_flag("--quiet,-q", o->quiet, "No progress bar or summary");
        cmd->callback([o]() {
            check_outputs_are_not_inputs({o->out, o->stats}, {o->in, o->previous});
            check_numbered_outputs_spare(o->out, {"step"}, {o->stats});
            if (!o->stats.empty()) check_output_file(o->stats);  // a folder there was removed, an empty one
            remove_stale_temporaries(o->out);                    // of a killed run into the same folder
            write_prediction(*o);
        });
    }
    {
        auto o = std::make_shared<EvaluationOptions>();
        CLI::App* cmd = sky.add_subcommand(
            "evaluate",
            "Score a cloud model on real photographs against persistence and iterated Farneback extrapolation, in\n"
            "the same run (docs/networks.md): a named sequence or any folder of one camera's photographs, at\n"
            "several resolutions and horizons; the model given the previous frame, and from one frame with the\n"
            "true (fitted) wind; pure advection and the paper's model beside them. Writes a markdown report with\n"
            "PSNR tables, the paper's one-step table (MSE, PSNR, SSIM), verdicts, a CSV and charts. A first\n"
            "Ctrl-C or SIGTERM while scoring ends it after the start frame under way and writes the report of\n"
            "the frames scored, saying so (exit 3); a second stops at once.");
        cmd->add_option("--model", o->model, "Model: auto, advect or a model folder (as for 'sky predict')")
            ->capture_default_str();
        cmd->add_option("--sequence", o->sequence,
                        "A named sequence in the shared data: arm-tsi, arm-clear, arm-dusk, mobotix");
        cmd->add_option("--photos", o->photos,
                        "A folder of photographs of one of the preset cameras (with --preset; or its images/ "
                        "sub-folder), times in the file names; or of skies already imported from any camera ('dynsky "
                        "sky import', .exr: another camera's photographs are imported first; a STEM.filled.png beside "
                        "each, from --filled-mask, leaves its filled pixels out)");
        cmd->add_option("--preset", o->preset,
                        "Camera preset of --photos when they are photographs: arm-tsi or mobotix")
            ->check(CLI::IsMember(camera_preset_names()));
        cmd->add_option(
            "--frames", o->frames,
            "Start frames A-B to score (default: the model's held-out part of a sequence it was trained on,\n"
            "else every frame)");
        cmd->add_option("--horizons", o->horizons, "Steps ahead to score, comma-separated")->capture_default_str();
        cmd->add_option("--resolutions", o->resolutions,
                        "Resolutions N to score at, comma-separated (each divides --import-res)")
            ->capture_default_str();
        cmd->add_option(
            "--shared", o->shared,
            "The shared data folder (default: ../shared beside the source tree dynsky was built from, else beside the working folder)");
        cmd->add_option("--out,-o", o->report, "Markdown file to write (a .csv and charts beside it)")
            ->capture_default_str();
        add_hidden_alias(cmd, "--report", &o->report);
        cmd->add_option("--import-res", o->import_resolution, "Resolution the photographs are imported at")
            ->check(CLI::Range(kImportResolutionMin, kImportResolutionMax))
            ->capture_default_str();
        cmd->add_option("--limit", o->limit, "Score only the first K start frames (0: all; for quick checks)")
            ->capture_default_str();
        cmd->add_flag("!--no-paper", o->paper, "Do not score the paper's model beside it");
        cmd->add_flag("--quiet,-q", o->quiet, "No progress bars; the report is still written");
        cmd->callback([o]() {
            o->stop_on_request = true;
            evaluate_cloud_model(*o);
        });
    }
    {
        auto o = std::make_shared<TrainingSetOptions>();
        CLI::App* cmd = sky.add_subcommand(
            "training-data",
            "Build one sequence of a cloud-model training set (networks/dataset.py runs this): frames in the\n"
            "networks' [0, 1] form at --sky-res, seen-sky and cloud masks, Farneback flow frame k -> k+1 and, for\n"
            "procedural sequences, the exact flow, as .npy files plus meta.json in --out.");
        cmd->add_option("--sequence", o->sequence, "Real sequence to import: arm-tsi or mobotix");
        cmd->add_option("--procedural", o->procedural,
                        "Folder written by `dynsky sky procedural` (with manifest.json)");
        cmd->add_option(
            "--shared", o->shared,
            "The shared data folder (default: ../shared beside the source tree dynsky was built from, else beside the working folder)");
        cmd->add_option("--sky-res", o->resolution, "Resolution N of the training images")->capture_default_str();
        cmd->add_option("--import-res", o->import_resolution,
                        "Resolution frames are imported (and Farneback flow computed) at; a multiple of --sky-res")
            ->check(CLI::Range(kImportResolutionMin, kImportResolutionMax))
            ->capture_default_str();
        cmd->add_option("--unit-scale", o->form.unit_map.scale,
                        "HDR -> [0, 1] log map (sky/hdr_recovery.h): radiance scale, W m^-2 sr^-1")
            ->check(finite_above(0, 1e9))
            ->capture_default_str();
        cmd->add_option(
               "--unit-max", o->form.unit_map.max_radiance,
               "HDR -> [0, 1] log map: radiance that maps to 1 (brighter clips; the sun is re-inserted on output)")
            ->check(finite_above(0, 1e9))
            ->capture_default_str();
        cmd->add_option("--cloud-rule", o->cloud_rule,
                        "Cloud mask rule: rb (red / blue > t) or nbr ((b - r) / (b + r) < t)")
            ->check(parsed_by([](const std::string& s) { parse_cloud_rule(s); }, "RULE"))
            ->capture_default_str();
        cmd->add_option("--cloud-threshold", o->form.cloud_rule.threshold, "Cloud mask threshold t")
            ->check(finite_in(-1000, 1000))
            ->capture_default_str();
        cmd->add_option("--out,-o", o->out, "Output folder")->required();
        cmd->add_flag("--quiet,-q", o->quiet, "No progress bars or summary");
        cmd->callback([o]() { build_training_sequence(*o); });
    }
}

}  // namespace dynsky::cli
