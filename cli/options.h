// Options that mean the same in every rendering command (`render`, `animate`, `compare`): the
// scene (frame/scene_spec.h) and the moving sky (frame/sky_source.h). The commands bind them to
// the frame stage's specs; logic lives there.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

#include "frame/scene_spec.h"
#include "frame/sky_source.h"

namespace dynsky::cli {

void add_scene_options(CLI::App* cmd, SceneSpec* o);

// Range checks on numeric options, run by CLI11 before any work: the message names the option and
// the range (docs/input-limits.md). CLI11's own Range lets NaN through, hence these. Whole-number
// options use CLI::Range, which also refuses a fraction or a value beyond the type.
// A finite number in [min, max].
CLI::Validator finite_in(double min, double max);
// A time parse_utc_time reads (ISO 8601 with a zone): a bad one is a usage error naming the option.
CLI::Validator utc_time();
// A value the library's own parser takes (it throws dynsky::Error naming the valid ones): a bad
// name is a usage error naming the option (exit 2), not a failure after the work began.
CLI::Validator parsed_by(std::function<void(const std::string&)> parse, const std::string& what);
// A finite number in (min, max] (a strictly positive one for min = 0).
CLI::Validator finite_above(double min, double max);
// A finite number in [min, max) (a share that must leave something: --mask-detail 1 erodes all).
CLI::Validator finite_below(double min, double max);
// A whole number >= 0 written as digits (a seed): "-1" is refused, not wrapped to 2^64 - 1.
CLI::Validator non_negative_whole();
// Limits shared by the commands.
constexpr int kMaxThreads = 4096;
constexpr int kMaxSpp = 1 << 20;
constexpr int kMaxDepth = 1024;
// --prev-dt's help, the same wherever --prev is taken (`sky predict`, `animate`, `compare`).
inline constexpr const char* kPrevDtHelp =
    "Seconds between --prev and the input sky (default 0: the frames' dynsky:time difference, else the photograph "
    "times their imports recorded, else one medium step)";
// --sky-res's help, the same wherever a sky is taken (`render`, `animate`, `compare`, `sky timeline`,
// `sky predict`).
inline constexpr const char* kSkyResHelp =
    "Resolution N of the sky (N x N fisheye): skies made here (procedural, clear) are made at N (default 1024);\n"
    "given with a sky file, the file is taken at N (resampled; a 2:1 lat-long converted at N). Without it a\n"
    "fisheye keeps its own size and a lat-long its height, at most 2048 where the sky moves";

inline constexpr const char* kSkyTurnHelp =
    "Turn a sky file about the zenith: every azimuth (from north towards east) plus DEG, its sun too, e.g.\n"
    "to put a downloaded HDRI's sun where the scene needs it (a lat-long turns exactly, a fisheye exactly by\n"
    "90, 180 or 270, by other angles through a lat-long: the sun's energy kept, the clouds a little blurred)";

// An old spelling of an option, kept working but left out of --help (glossary: one name per thing).
template <typename T>
CLI::Option* add_hidden_alias(CLI::App* cmd, const std::string& old_name, T* variable) {
    return cmd->add_option(old_name, *variable)->group("");
}

// -q,--quiet for commands whose report goes to stdout: silences stdout (warnings and errors still
// reach stderr).
void add_quiet_flag(CLI::App* cmd);
void add_sky_source_options(CLI::App* cmd, SkySourceSpec* o, StepModelSpec* m);
// The options of a sky made here ('clear', 'procedural'): --sky-res, --time, --lat, --lon (part of
// add_sky_source_options; `render` takes them alone).
void add_generated_sky_options(CLI::App* cmd, SkySourceSpec* o);

// Warns (stderr, even with -q) for each of the options given that only shape a sky made here
// (--sky-res, --coverage) when `sky` is a file: they were ignored without a word.
void warn_options_of_generated_skies(const CLI::App* cmd, const std::string& sky);

}  // namespace dynsky::cli
