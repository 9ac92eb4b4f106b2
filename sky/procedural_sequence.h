// A sequence of procedural cloudy skies with their exact flow fields (`dynsky sky procedural`,
// sky/procedural_clouds.h): OUT/frame_NNNN.exr (canonical fisheye radiance), OUT/flow_NNNN.exr
// (channels dx, dy in pixels over dt, +x right, +y down, and the cloud opacity), optional
// previews, and OUT/manifest.json (the schema: docs/procedural-sky.md) listing every frame.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace dynsky {

// Parameters (defaults): seed 0, coverage 0.4, 60 s at dt 10 s, N 512, layers {cumulus}, winds
// (empty: the layers' defaults; else SPEED m/s, FROM degrees), cumulus altitude 1500 m, shapes
// changing over 900 s, an optional density mask for the first layer, the sun fixed at elevation 45,
// azimuth 180 degrees (or following a place and time: write_procedural_sequence's use_location),
// turbidity 3, visibility 40 km.
struct ProceduralSequenceSettings {
    uint64_t seed = 0;
    double coverage = 0.4;
    double duration = 60.0;
    double dt = 10.0;
    int resolution = 512;
    std::string out;
    std::vector<std::string> layers = {"cumulus"};
    std::vector<double> wind;         // SPEED,FROM_DEG of the cumulus layer
    std::vector<double> cirrus_wind;  // SPEED,FROM_DEG of the cirrus layer
    double cumulus_altitude = 1500.0;
    double evolution = 900.0;
    std::string mask_image;
    double mask_extent = 0.0;
    double mask_detail = 0.35;
    double sun_elevation = 45.0, sun_azimuth = 180.0;
    double latitude = 0.0, longitude = 0.0;
    std::string time_iso;
    double turbidity = 3.0;
    double visibility = 40000.0;
    bool preview = false, quiet = false;
};

// Checks everything before the output folder is touched: a bad setting leaves nothing.
void write_procedural_sequence(const ProceduralSequenceSettings& o, bool use_location);

}  // namespace dynsky
