// Clear against cloudy lighting (`dynsky compare`): the same frame under the clear sky and under the
// cloudy sky of the same sun position, side by side with a difference image (log2 cloudy / clear),
// and the illuminance at chosen points over time under both (CSV and chart).
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "frame/scene_spec.h"
#include "frame/sky_source.h"

namespace dynsky {

// Parameters (defaults): frames 640 x 360 at 32 spp; out "compare"; chart points (fractions of
// the image) "0.5,0.3;0.25,0.75;0.75,0.75"; chart over 60 s in 13 frames of 160 x 90 at 8 spp;
// seed 0; threads 0 (all). The clear sky has the cloudy sky's sun at every moment: the clock's for
// skies made here (sky.time, default 2026-06-21T16:00:00Z at the spec's place) or when sky.time is
// given, else the sun of the sky EXR (fixed); an EXR without a sun direction needs sky.time.
struct ComparisonSettings {
    SceneSpec scene;
    SkySourceSpec sky;
    StepModelSpec model;
    int width = 640, height = 360;
    int spp = 32;
    std::string out = "compare";
    std::string points = "0.5,0.3;0.25,0.75;0.75,0.75";
    double duration = 60.0;
    int chart_frames = 13;
    int chart_width = 160, chart_height = 90;
    int chart_spp = 8;
    uint64_t seed = 0;
    int threads = 0;
};

// "X,Y;X,Y;..." with X, Y in [0, 1]. Throws dynsky::Error naming --points.
std::vector<std::pair<double, double>> parse_chart_points(const std::string& text);

// Writes clear.exr, cloudy.exr, side_by_side.png, difference.png, illuminance.csv, illuminance.png.
void render_clear_cloudy_comparison(const ComparisonSettings& settings);

}  // namespace dynsky
