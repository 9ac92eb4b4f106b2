// The environment-map importance-sampling study (`dynsky bench sampling`, docs/sampling/): small
// scenes rendered under several skies with every sky sampler, error against cached converged
// references, per-frame rebuild cost beside the streaming floor, and the failure cases; a markdown
// report with tables, CSV files and charts (bench/sampling_charts.py).
#pragma once

#include <string>
#include <vector>

#ifndef DYNSKY_SHARED_DIR_DEFAULT
#define DYNSKY_SHARED_DIR_DEFAULT "../shared"
#endif

namespace dynsky {

// Parameters (defaults): quick false (CI size), out "sampling-report", cache "" (OUT/cache), the
// shared data folder, seeds 0 (2 quick, else 4), and selections (empty: all).
struct SamplingStudyOptions {
    bool quick = false;
    std::string out = "sampling-report";
    std::string cache;  // "" : OUT/cache
    std::string shared = DYNSKY_SHARED_DIR_DEFAULT;
    int seeds = 0;                                            // 0: 2 in quick mode, 4 otherwise
    std::vector<std::string> skies, scenes, samplers, parts;  // empty: all
};

// Returns 0; throws dynsky::Error for bad selections before writing anything.
int run_sampling_study(const SamplingStudyOptions& o);

}  // namespace dynsky
