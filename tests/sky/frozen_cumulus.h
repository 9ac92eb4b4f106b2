// The sky the sun tests share (tests/sky/procedural_clouds_test.cpp, tests/motion/sun_transmittance_test.cpp,
// and bench/sun_seeds.cpp, whose seeds must be theirs): frozen cumulus, coverage 0.45, under a steady 12 m/s wind
// from 250 degrees, the sun 46 degrees from the zenith, so that a cloud's edge crosses it within a
// minute or two on most seeds.
#pragma once

#include <cstdint>

#include "sky/fisheye.h"
#include "sky/procedural_clouds.h"

namespace dynsky::test {

inline ProceduralSkyParams frozen_cumulus(uint64_t seed) {
    ProceduralSkyParams p;
    p.coverage = 0.45;
    p.layers = {cumulus_layer()};
    p.layers[0].wind_from_deg = 250, p.layers[0].wind_speed_mps = 12, p.layers[0].evolution_time_s = 0;
    p.clear_sky.sun_direction = fisheye::direction_from_angles(0.8, 1.2);
    p.seed = seed;
    return p;
}

}  // namespace dynsky::test
