// A sequence of procedural cloudy skies with their exact flow fields (`dynsky sky procedural`,
// sky/procedural_clouds.h): OUT/frame_NNNN.exr (canonical fisheye radiance), OUT/flow_NNNN.exr
// (channels dx, dy in pixels over dt, +x right, +y down, and the cloud opacity), optional
// previews, and OUT/manifest.json (the schema: docs/procedural-sky.md) listing every frame.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sky/default_sky.h"

namespace dynsky {

// Parameters (defaults; those of every subcommand's procedural sky, sky/default_sky.h):
//   cloud_seed      0          the clouds' random seed
//   coverage        0.5        cloud cover of each layer
//   duration, dt    60, 10 s   frames at 0, dt, ... <= duration; each flow spans dt
//   resolution      512        N of the N x N fisheye frames
//   layers          {cumulus}  cumulus (at cloud_height_m) and / or cirrus (at 8 km)
//   wind_from_deg, wind_speed_mps, cloud_height_m  270, 12, 1500  the cumulus wind
//   cirrus_wind     {}         SPEED,FROM_DEG of the cirrus layer (empty: 25 m/s from 260)
//   evolution       900 s      time for the cumulus shapes to change completely (0: frozen)
//   mask_image      ""         a density image shaping the first layer (mask_extent, mask_detail)
//   sun             at latitude, longitude (Paris) from time_iso (2026-06-21T16:00:00Z), following
//                   the clock; or fixed at sun_elevation, sun_azimuth when fixed_sun
//   turbidity 3, visibility 40 km
struct ProceduralSequenceSettings {
    uint64_t cloud_seed = 0;
    double coverage = default_sky::kCoverage;
    double duration = 60.0;
    double dt = 10.0;
    int resolution = 512;
    std::string out;
    std::vector<std::string> layers = {"cumulus"};
    double wind_from_deg = default_sky::kWindFromDeg, wind_speed_mps = default_sky::kWindSpeedMps;
    double cloud_height_m = default_sky::kCloudHeightM;
    std::vector<double> cirrus_wind;  // SPEED,FROM_DEG of the cirrus layer
    double evolution = default_sky::kCloudEvolutionS;
    std::string mask_image;
    double mask_extent = 0.0;
    double mask_detail = 0.35;
    bool fixed_sun = false;
    double sun_elevation = 45.0, sun_azimuth = 180.0;
    double latitude = default_sky::kLatitudeDeg, longitude = default_sky::kLongitudeDeg;
    std::string time_iso = default_sky::kStartTime;
    double turbidity = default_sky::kTurbidity;
    double visibility = 40000.0;
    bool preview = false, quiet = false;
};

// Checks everything before the output folder is touched: a bad setting leaves nothing.
void write_procedural_sequence(const ProceduralSequenceSettings& o);

}  // namespace dynsky
