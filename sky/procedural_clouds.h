// Procedural cloudy skies with known motion: cloud layers on horizontal planes above the viewer,
// advected by wind, slowly changing shape, lit by the sun and composited over the clear sky,
// each frame with its exact image-space flow field (docs/procedural-sky.md).
//
// Geometry: a view direction d (unit, d.y > 0) meets a layer at altitude h at the point
// p = d h / d.y, so clouds shrink and slow towards the horizon by themselves. The cloud field is
// fixed in "material" coordinates q = p_xz - wind t; its shape also evolves in a separate noise
// time axis. The flow of a pixel over dt is the fisheye projection of p + wind dt minus the pixel's
// own position: exact for the model, no optical-flow estimate involved.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sky/clear_sky.h"
#include "sky/sky_image.h"
#include "util/image.h"
#include "util/math.h"

namespace dynsky {

enum class CloudType { Cumulus, Cirrus };

struct CloudLayer {
    CloudType type = CloudType::Cumulus;
    double altitude_m = 1500.0;      // height of the layer above the viewer
    double thickness_m = 1000.0;     // vertical extent, used for the sunlight's path through it
    std::optional<double> coverage;  // fraction of the layer (seen from below) holding any cloud,
                                     // [0, 1]; unset: ProceduralSkyParams::coverage
    double wind_speed_mps = 8.0;
    double wind_from_deg = 270.0;     // where the wind blows FROM, clockwise from north (weather
                                      // reports' convention: 270 = westerly, clouds drift east)
    double feature_size_m = 800.0;    // size of the largest cloud features (across the wind)
    double stretch = 1.0;             // elongation along the wind (cirrus streaks: > 1)
    double optical_depth = 20.0;      // vertical optical depth where the density is 1
    double edge_softness = 1.0;       // width of the density ramp at cloud edges, in noise sigmas
    double evolution_time_s = 900.0;  // time for the largest features to change shape; 0 freezes
                                      // the shapes (pure advection)
    int octaves = 7;
    double gain = 0.5;    // amplitude ratio between successive noise octaves
    int billow_from = 1;  // octaves from this one on are billowy (rounded lobes); a
                          // value >= octaves keeps plain fBm (wispy)

    // Artist-drawn clouds: a 1-channel density image in [0, 1] (load_cloud_mask) replacing the
    // noise on this layer. It is seen from below like the sky image (north up, east left), covers
    // a square of mask_extent_m centred above the viewer at t = 0, and drifts with the wind.
    std::shared_ptr<const Image> mask;
    double mask_extent_m = 0.0;  // 0: 2 * altitude * tan(60 deg), i.e. out to 60 deg zenith angle
    double mask_detail = 0.35;   // how much noise erodes the mask's soft edges (0: mask as is)
};

// Presets: fair-weather cumulus at 1.5 km, cirrus streaks at 8 km.
CloudLayer cumulus_layer();
CloudLayer cirrus_layer();

struct ProceduralSkyParams {
    uint64_t seed = 0;
    double coverage = 0.4;  // default coverage of layers that set none
    std::vector<CloudLayer> layers = {cumulus_layer()};
    ClearSkyParams clear_sky;       // sun direction, turbidity, ground albedo, sun disc
    double visibility_m = 40000.0;  // aerial perspective: clouds this far fade to 1/e
};

// Throws dynsky::Error naming the bad parameter.
void validate_procedural_params(const ProceduralSkyParams& params);

// What made a procedural sky, for its file's dynsky:source: "procedural (seed 5, coverage 0.5,
// turbidity 3, visibility 40000 m; cumulus at 1500 m, wind 12 m/s from 270 deg, evolution 900 s)"
// (a layer's coverage when its own, "drawn mask" for a mask). Two skies of other settings had
// the same header ("procedural").
std::string describe_procedural_sky(const ProceduralSkyParams& params);

// Reads a grey or grey+alpha image as a cloud density mask (1 channel, [0, 1]): the alpha channel
// when there is one (2 or 4 channels) that is not opaque everywhere, else the mean of the colour
// channels, as encoded (8-bit files are not sRGB-decoded: the drawing's grey is the density). Throws
// dynsky::Error "PATH: problem" for a missing or unreadable file.
Image load_cloud_mask(const std::string& path);

// Renders the sky at time_s (seconds on the sequence's clock) as an N x N canonical fisheye.
// If flow_out is given it receives an N x N x 3 image: channels 0 and 1 hold the displacement,
// in pixels of this image (+x right, +y down), that the cloud seen at each pixel undergoes from
// time_s to time_s + dt; channel 2 holds the total cloud opacity of the pixel. Where layers
// overlap the flow is the most visible layer's. Deterministic: the same parameters give
// bitwise identical images on any number of threads.
SkyImage render_procedural_sky(const ProceduralSkyParams& params, double time_s, int resolution,
                               Image* flow_out = nullptr, double dt = 1.0);

// Fraction of the direct sun that gets through the clouds at time_s (1: clear line of sight).
double procedural_sun_transmittance(const ProceduralSkyParams& params, double time_s);

// The renderer behind the functions above, keeping per-sequence work (noise tables, coverage
// thresholds, the clear sky of the last sun direction) between frames. Not thread-safe itself:
// use one per thread; each render parallelises its rows internally.
class ProceduralSky {
  public:
    explicit ProceduralSky(const ProceduralSkyParams& params);
    ~ProceduralSky();
    ProceduralSky(ProceduralSky&&) noexcept;
    ProceduralSky& operator=(ProceduralSky&&) noexcept;

    SkyImage render(double time_s, int resolution, Image* flow_out = nullptr, double dt = 1.0);
    double sun_transmittance(double time_s) const;
    // Cloud density in [0, 1] of layer `layer` (index into params().layers) at the world point
    // (x_m, its altitude, z_m) at time_s, unfiltered (a point, not a pixel). For cloud shadows on
    // the ground, or to check coverage: the fraction of points with density > 0 is the coverage.
    double layer_density(size_t layer, double x_m, double z_m, double time_s) const;
    // Changes the sun (e.g. following the sun's path over a long sequence); clouds are unchanged.
    void set_sun_direction(const Vec3d& sun_direction);
    const ProceduralSkyParams& params() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace dynsky
