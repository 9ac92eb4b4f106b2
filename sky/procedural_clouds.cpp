#include "sky/procedural_clouds.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <iomanip>
#include <sstream>

#include "sky/fisheye.h"
#include "sky/noise.h"
#include "util/error.h"

namespace dynsky {

namespace {

constexpr double kSunHalfAngle = 0.5 * 0.533 * kPiD / 180.0;

// Henyey-Greenstein phase function (per steradian).
inline double henyey_greenstein(double cos_theta, double g) {
    double denom = 1.0 + g * g - 2.0 * g * cos_theta;
    return (1.0 - g * g) / (4.0 * kPiD * denom * std::sqrt(denom));
}

// Water clouds scatter mostly forward (silver linings near the sun) with a weak backward lobe.
inline double cloud_phase(double cos_theta) {
    return 0.8 * henyey_greenstein(cos_theta, 0.75) + 0.2 * henyey_greenstein(cos_theta, -0.25);
}

// Diffuse transmittance of a conservative-scattering slab (two-stream, asymmetry g = 0.85):
// how much light still reaches a cloud's base after crossing optical depth tau.
inline double diffuse_transmittance(double tau) { return 1.0 / (1.0 + 0.75 * (1.0 - 0.85) * tau); }

void require(bool ok, const std::string& what) {
    if (!ok) throw Error("procedural sky: " + what);
}

// Bilinear lookup of a 1-channel image at continuous pixel coordinates; 0 outside.
float sample_mask(const Image& mask, double x, double y) {
    x -= 0.5, y -= 0.5;  // pixel centres at integer + 0.5
    double fx = std::floor(x), fy = std::floor(y);
    int x0 = int(fx), y0 = int(fy);
    float ax = float(x - fx), ay = float(y - fy);
    auto at = [&](int xi, int yi) -> float {
        if (xi < 0 || yi < 0 || xi >= mask.width || yi >= mask.height) return 0.0f;
        return mask.at(xi, yi, 0);
    };
    if (x0 < -1 || y0 < -1 || x0 >= mask.width || y0 >= mask.height) return 0.0f;
    float top = at(x0, y0) * (1 - ax) + at(x0 + 1, y0) * ax;
    float bottom = at(x0, y0 + 1) * (1 - ax) + at(x0 + 1, y0 + 1) * ax;
    return top * (1 - ay) + bottom * ay;
}

// One cloud layer, ready to evaluate: noise, coverage threshold, wind frame.
struct LayerModel {
    CloudLayer spec;
    FractalNoise noise;
    FractalNoise warp;                           // bends cirrus streaks (a domain warp in material coordinates)
    FractalNoise patch;                          // gathers cirrus streaks into patches
    static constexpr double kPatchWeight = 1.2;  // patch field's spread relative to the streaks'
    double field_sigma = 0.0;
    double threshold = 0.0;               // noise value above which there is cloud (+inf: none)
    double ramp = 0.0;                    // width of the density ramp above the threshold, in noise units
    double gradient_bound = 0.0;          // noise units per metre the field hardly ever exceeds
    double finest_frequency = 0.0;        // cells per metre of the finest octave (across the wind)
    double wind_x = 0.0, wind_z = 0.0;    // m/s, world frame
    double along_x = 1.0, along_z = 0.0;  // unit vector the wind blows towards
    double inv_evolution = 0.0;           // noise time units per second
    double mask_half_extent = 0.0;        // metres

    LayerModel(const CloudLayer& layer, uint64_t seed, double coverage)
        : spec(layer),
          noise(seed, layer.octaves, layer.gain, layer.billow_from),
          warp(noise_hash(seed), 2, 0.5),
          patch(noise_hash(seed + 1), 3, 0.5) {
        // The wind blows towards the opposite of where it comes from: azimuth from + 180 deg.
        double from = layer.wind_from_deg * kPiD / 180.0;
        along_x = -std::sin(from), along_z = std::cos(from);
        wind_x = layer.wind_speed_mps * along_x, wind_z = layer.wind_speed_mps * along_z;
        inv_evolution = layer.evolution_time_s > 0 ? 1.0 / layer.evolution_time_s : 0.0;
        field_sigma = layer.type == CloudType::Cirrus ? noise.sigma() * std::hypot(1.0, kPatchWeight) : noise.sigma();
        ramp = layer.edge_softness * field_sigma;
        if (layer.mask) {
            double extent = layer.mask_extent_m > 0 ? layer.mask_extent_m
                                                    : 2.0 * layer.altitude_m * std::tan(60.0 * kPiD / 180.0);
            mask_half_extent = 0.5 * extent;
        }
        threshold = coverage_threshold(coverage);
        gradient_bound = field_gradient_bound();
        finest_frequency = std::ldexp(1.0, layer.octaves - 1) / layer.feature_size_m;
    }

    // A bound on how fast the field changes (noise units per metre): twice the 99th percentile
    // of its gradient (forward differences below the finest octave) over a fixed pseudo-random set
    // of points, as coverage_threshold samples it. Used only to skip pixels far from an edge.
    double field_gradient_bound() const {
        const int n = 2048;
        std::vector<double> g(n);
        const double h = spec.feature_size_m / 4096.0;
        uint64_t state = noise_hash(0x9ad1e47ull);
        for (int k = 0; k < n; ++k) {
            double x = noise_unit(state = noise_hash(state)) * 2048.0 * spec.feature_size_m;
            double z = noise_unit(state = noise_hash(state)) * 2048.0 * spec.feature_size_m;
            double t = noise_unit(state = noise_hash(state)) * 256.0 * spec.evolution_time_s;
            const double v = field(x, z, t, 0.0).value;
            g[k] = std::hypot(field(x + h, z, t, 0.0).value - v, field(x, z + h, t, 0.0).value - v) / h;
        }
        std::nth_element(g.begin(), g.begin() + (n * 99) / 100, g.end());
        return 2.0 * g[size_t((n * 99) / 100)];
    }

    // The noise value exceeded on a fraction `coverage` of the layer: an empirical quantile of the
    // noise over a fixed pseudo-random set of points, so "coverage" is a real cloud fraction.
    double coverage_threshold(double coverage) const {
        if (coverage <= 0.0) return std::numeric_limits<double>::infinity();
        const int n = 8192;
        std::vector<float> values(n);
        uint64_t state = noise_hash(0xc0fe1a6eull);
        for (int k = 0; k < n; ++k) {
            // Points spread over thousands of features and a long time: the field's statistics.
            double x = noise_unit(state = noise_hash(state)) * 2048.0 * spec.feature_size_m;
            double z = noise_unit(state = noise_hash(state)) * 2048.0 * spec.feature_size_m;
            double t = noise_unit(state = noise_hash(state)) * 256.0 * spec.evolution_time_s;
            values[k] = field(x, z, t, 0.0).value;
        }
        std::sort(values.begin(), values.end());
        double index = (1.0 - coverage) * (n - 1);
        int lo = int(std::floor(index));
        int hi = std::min(lo + 1, n - 1);
        double a = index - lo;
        double value = values[lo] * (1 - a) + values[hi] * a;
        // Full coverage: slightly below the minimum so that (almost) every point has cloud.
        return coverage >= 1.0 ? value - 0.05 * noise.sigma() : value;
    }

    // Cloud density in [0, 1] at material coordinates (qx, qz) (metres, world frame, wind removed),
    // time t (s), for a pixel footprint (m) on the layer.
    // The noise field that the coverage threshold cuts, at material coordinates (qx, qz)
    // (metres, world frame, wind removed), time t (s), for a pixel footprint (m) on the layer.
    FractalNoise::Sample field(double qx, double qz, double t, double footprint) const {
        double across = spec.feature_size_m, along = spec.feature_size_m * spec.stretch;
        double a = (qx * along_x + qz * along_z) / along;
        double b = (-qx * along_z + qz * along_x) / across;
        double time = t * inv_evolution;
        if (spec.type != CloudType::Cirrus) return noise.evaluate(a, b, time, footprint / across);
        // Cirrus: fall streaks curve (a smooth shift across the wind, a few features wide) and
        // come in patches (a large, round field added to the streaks before the threshold).
        double w = warp.evaluate(a * spec.stretch / 6.0, b / 6.0, time / 6.0).value;
        FractalNoise::Sample s = noise.evaluate(a, b + 0.6 * w / warp.sigma(), time, footprint / across);
        const double patch_size = 5.0 * along;
        FractalNoise::Sample p = patch.evaluate(qx / patch_size, qz / patch_size, time / 5.0, footprint / patch_size);
        s.value += float(kPatchWeight * noise.sigma() / patch.sigma()) * p.value;
        s.removed_sigma = std::hypot(s.removed_sigma,
                                     float(kPatchWeight * noise.sigma() / patch.sigma()) * p.removed_sigma);
        return s;
    }

    // Cloud density in [0, 1] at material coordinates (qx, qz), time t (s), footprint (m).
    double density(double qx, double qz, double t, double footprint) const {
        if (spec.mask) {
            // Mask pixel: seen from below, north up (-z), east left (+x).
            double mu = -qx / mask_half_extent, mv = qz / mask_half_extent;
            if (std::abs(mu) >= 1.0 || std::abs(mv) >= 1.0) return 0.0;
            const Image& m = *spec.mask;
            double value = sample_mask(m, (mu + 1.0) * 0.5 * m.width, (mv + 1.0) * 0.5 * m.height);
            if (spec.mask_detail <= 0.0) return clamp(value, 0.0, 1.0);
            FractalNoise::Sample s = field(qx, qz, t, footprint);
            // The noise erodes the soft edges and gives the inside lumps of varying thickness
            // (a uniform inside would shade as a flat grey card).
            double erosion = clamp(0.5 + s.value / (4.0 * field_sigma), 0.0, 1.0);
            double eroded = clamp((value - spec.mask_detail * erosion) / (1.0 - spec.mask_detail), 0.0, 1.0);
            double lumps = clamp(0.5 + s.value / (3.0 * field_sigma), 0.0, 1.0);
            return eroded * std::max(0.0, 1.0 - 2.0 * spec.mask_detail * (1.0 - lumps));
        }
        return pixel_density(qx, qz, t, footprint, 0.0);
    }

    // The density a pixel of `footprint` (m) shows where the opacity along the view is
    // 1 - exp(-k density): the one whose opacity is the mean opacity over the footprint (k = 0:
    // the density at the centre). Cut at the threshold, the field turns from clear to opaque
    // within a few metres (opacity 0.95 at 15 % of the ramp at the cumulus' optical depth of 20),
    // and taken at each pixel's centre the clouds of a 1024 px sky had stair-stepped edges (looked
    // at). Near an edge the field's change across the footprint (its gradient, by forward
    // differences) makes a window of field values over which that opacity has a closed-form mean.
    double pixel_density(double qx, double qz, double t, double footprint, double k) const {
        if (!std::isfinite(threshold)) return 0.0;
        FractalNoise::Sample s = field(qx, qz, t, footprint);
        // Octaves dropped for the footprint blur the threshold by their spread: the expected
        // density over the pixel, so distant clouds merge into a band instead of aliasing.
        double widen = 1.25 * s.removed_sigma;
        double lo = threshold - widen, hi = threshold + ramp + widen, width = hi - lo;
        const double x = (s.value - lo) / width;
        // Only for footprints under two cells of the finest octave (the cumulus: within 70 degrees
        // of the zenith at 1024 px, 50 at 512, 20 at 256, none at 128). Coarser, the octaves faded
        // out widen the ramp as much, and the sun-weight rules (motion/sun_patch.h) were
        // calibrated on such skies at 64-128 px: with the window there too, the illuminance error
        // of SunTransmittance's seeds rose from 9.6 to 12.9 %.
        if (!(k > 0.0) || !(footprint > 0.0) || footprint * finest_frequency >= 2.0) return clamp(x, 0.0, 1.0);
        // Beyond the opacity's knee (0.98) or clear by more than the field can change across the
        // pixel: the centre's value stands.
        const double reach = gradient_bound * footprint / width, knee = std::min(1.0, 4.0 / k);
        if (x < -reach || x > knee + reach) return clamp(x, 0.0, 1.0);
        const double h = 0.5 * footprint;
        const double gx = field(qx + h, qz, t, footprint).value - s.value;
        const double gz = field(qx, qz + h, t, footprint).value - s.value;
        // Half the window: 1.5 x the change over h. The finer octaves within the pixel widen
        // what the gradient says: against 4 x 4 pixels at 4 x the resolution, edge opacities were
        // off by 0.12 at 1 x, 0.11 at 1.5 x and 2 x, 0.17 at the centre (test
        // ProceduralClouds.EdgeOpacityIsThePixelsMean, three seeds).
        const double half = 1.5 * std::hypot(gx, gz) / width;
        if (half < 1e-9) return clamp(x, 0.0, 1.0);
        // The opacity's integral over the ramp's x: 0 below it, x - (1 - e^-kx) / k on it, then
        // linear at the full opacity 1 - e^-k.
        const double full = -std::expm1(-k), at_one = 1.0 + std::expm1(-k) / k;
        auto integral = [&](double u) {
            if (u <= 0.0) return 0.0;
            if (u <= 1.0) return u + std::expm1(-k * u) / k;
            return at_one + (u - 1.0) * full;
        };
        const double mean = (integral(x + half) - integral(x - half)) / (2.0 * half);
        if (mean <= 0.0) return 0.0;
        return mean >= full ? 1.0 : clamp(-std::log1p(-mean) / k, 0.0, 1.0);
    }
};

struct LayerHit {
    double alpha = 0.0;              // visible opacity (aerial perspective included)
    Color radiance = Color::Zero();  // premultiplied by alpha
};

}  // namespace

CloudLayer cumulus_layer() { return CloudLayer(); }

CloudLayer cirrus_layer() {
    CloudLayer c;
    c.type = CloudType::Cirrus;
    c.altitude_m = 8000.0;
    c.thickness_m = 500.0;
    c.wind_speed_mps = 25.0;
    c.wind_from_deg = 260.0;
    c.feature_size_m = 600.0;
    c.stretch = 10.0;
    c.optical_depth = 0.8;
    c.edge_softness = 1.0;
    c.evolution_time_s = 1800.0;
    c.octaves = 6;
    c.gain = 0.6;
    c.billow_from = c.octaves;  // plain fBm: fibrous, not lumpy
    return c;
}

std::string describe_procedural_sky(const ProceduralSkyParams& p) {
    std::ostringstream s;
    s << std::setprecision(10) << "procedural (seed " << p.seed << ", coverage " << p.coverage << ", turbidity "
      << p.clear_sky.turbidity << ", visibility " << p.visibility_m << " m";
    for (const CloudLayer& l : p.layers) {
        s << "; " << (l.type == CloudType::Cumulus ? "cumulus" : "cirrus") << " at " << l.altitude_m << " m";
        if (l.coverage) s << ", coverage " << *l.coverage;
        s << ", wind " << l.wind_speed_mps << " m/s from " << l.wind_from_deg << " deg, evolution "
          << l.evolution_time_s << " s";
        if (l.mask) s << ", drawn mask over " << l.mask_extent_m << " m, detail " << l.mask_detail;
    }
    return s.str() + ")";
}

void validate_procedural_params(const ProceduralSkyParams& p) {
    auto finite = [](double x) { return std::isfinite(x); };
    require(finite(p.coverage) && p.coverage >= 0.0 && p.coverage <= 1.0,
            "coverage must be in [0, 1], got " + std::to_string(p.coverage));
    require(p.layers.size() <= 8, "at most 8 cloud layers, got " + std::to_string(p.layers.size()));
    require(finite(p.visibility_m) && p.visibility_m > 0.0, "visibility must be a positive distance in metres");
    const Vec3d& sun = p.clear_sky.sun_direction;
    require(sun.allFinite() && sun.norm() > 0.0, "the sun direction must be a finite, non-zero vector");
    validate_clear_sky_params(p.clear_sky);
    for (size_t k = 0; k < p.layers.size(); ++k) {
        const CloudLayer& l = p.layers[k];
        std::string name = "layer " + std::to_string(k) + ": ";
        if (l.coverage)
            require(finite(*l.coverage) && *l.coverage >= 0.0 && *l.coverage <= 1.0,
                    name + "coverage must be in [0, 1], got " + std::to_string(*l.coverage));
        require(finite(l.altitude_m) && l.altitude_m > 0.0, name + "altitude must be above the viewer (> 0 m)");
        require(finite(l.thickness_m) && l.thickness_m >= 0.0, name + "thickness must be >= 0 m");
        require(finite(l.wind_speed_mps) && l.wind_speed_mps >= 0.0, name + "wind speed must be >= 0 m/s");
        require(finite(l.wind_from_deg), name + "wind direction must be finite");
        require(finite(l.feature_size_m) && l.feature_size_m > 0.0, name + "feature size must be > 0 m");
        require(finite(l.stretch) && l.stretch >= 1.0, name + "stretch must be >= 1");
        require(finite(l.optical_depth) && l.optical_depth >= 0.0, name + "optical depth must be >= 0");
        require(finite(l.edge_softness) && l.edge_softness > 0.0, name + "edge softness must be > 0");
        require(finite(l.evolution_time_s) && l.evolution_time_s >= 0.0,
                name + "evolution time must be >= 0 s (0 freezes the shapes)");
        require(l.octaves >= 1 && l.octaves <= 12, name + "octaves must be in [1, 12]");
        require(finite(l.gain) && l.gain > 0.0 && l.gain < 1.0, name + "gain must be in (0, 1)");
        require(l.billow_from >= 0, name + "billow_from must be >= 0");
        if (l.mask) {
            require(l.mask->channels == 1 && l.mask->width > 0 && l.mask->height > 0,
                    name + "the cloud mask must be a non-empty 1-channel image (use load_cloud_mask)");
            require(finite(l.mask_extent_m) && l.mask_extent_m >= 0.0, name + "mask extent must be >= 0 m");
            require(finite(l.mask_detail) && l.mask_detail >= 0.0 && l.mask_detail < 1.0,
                    name + "mask detail must be in [0, 1)");
        }
    }
}

Image load_cloud_mask(const std::string& path) {
    Image in = read_image(path);  // throws "PATH: no such file" etc.
    Image mask(in.width, in.height, 1);
    bool has_alpha = in.channels == 2 || in.channels >= 4;
    int alpha_channel = in.channels == 2 ? 1 : 3;
    int colours = has_alpha ? in.channels - 1 : in.channels;
    if (has_alpha) {
        // Many tools save grey drawings as RGBA with an opaque alpha: then the grey is the density.
        bool opaque = true;
        for (int y = 0; y < in.height && opaque; ++y)
            for (int x = 0; x < in.width && opaque; ++x) opaque = in.at(x, y, alpha_channel) >= 1.0f;
        has_alpha = !opaque;
    }
    for (int y = 0; y < in.height; ++y)
        for (int x = 0; x < in.width; ++x) {
            float v = 0;
            if (has_alpha) {
                v = in.at(x, y, alpha_channel);
            } else {
                for (int c = 0; c < colours; ++c) v += in.at(x, y, c);
                v /= float(colours);
            }
            if (!std::isfinite(v)) throw_file_error(path, "cloud mask holds a non-finite value");
            mask.at(x, y, 0) = clamp(v, 0.0f, 1.0f);
        }
    return mask;
}

struct ProceduralSky::Impl {
    ProceduralSkyParams params;
    std::vector<LayerModel> layers;    // sorted by altitude, lowest (nearest the viewer) first
    std::vector<size_t> sorted_index;  // params.layers[k] is layers[sorted_index[k]]
    // Lighting from the clear sky, for the current sun.
    Vec3d sun = Vec3d(0, 1, 0);
    Color sun_irradiance = Color::Zero();   // on a surface facing the sun, above the clouds
    Color sky_ambient = Color::Zero();      // cosine-weighted mean radiance of the clear sky
    Color ground_radiance = Color::Zero();  // light reflected by the ground onto cloud bases
    SkyImage clear;                         // cached clear sky (resolution 0: none)
    SkyImage clear_no_disc;                 // the same without the sun disc

    explicit Impl(const ProceduralSkyParams& p) : params(p) {
        validate_procedural_params(p);
        std::vector<size_t> order(p.layers.size());
        for (size_t k = 0; k < order.size(); ++k) order[k] = k;
        std::stable_sort(order.begin(), order.end(),
                         [&](size_t a, size_t b) { return p.layers[a].altitude_m < p.layers[b].altitude_m; });
        sorted_index.resize(order.size());
        for (size_t s = 0; s < order.size(); ++s) sorted_index[order[s]] = s;
        for (size_t k : order) {
            const CloudLayer& l = p.layers[k];
            uint64_t seed = noise_hash(p.seed * 0x100000001b3ull + 0x632be59bd9b4e019ull * (k + 1));
            layers.emplace_back(l, seed, l.coverage.value_or(p.coverage));
        }
        update_lighting();
    }

    void update_lighting() {
        sun = params.clear_sky.sun_direction.normalized();
        clear = clear_no_disc = SkyImage();
        // The sun lights the clouds whether or not the image shows its disc.
        ClearSkyParams lit = params.clear_sky;
        lit.sun_disc = true;
        ClearSkyModel model(lit, /*warn=*/false);
        sun_irradiance = sun.y() > 0.0 ? model.sun_irradiance() : Color::Zero();
        // Irradiance from the clear sky on a horizontal surface, by midpoint quadrature.
        const int nt = 16, np = 32;
        Eigen::Array3d e = Eigen::Array3d::Zero();
        for (int a = 0; a < nt; ++a) {
            double theta = (a + 0.5) * (kPiD / 2) / nt;
            for (int b = 0; b < np; ++b) {
                double phi = (b + 0.5) * 2 * kPiD / np;
                Color l = model.sky_radiance(fisheye::direction_from_angles(theta, phi));
                e += l.cast<double>() * std::cos(theta) * std::sin(theta) * (kPiD / 2 / nt) * (2 * kPiD / np);
            }
        }
        sky_ambient = (e / kPiD).cast<float>();
        double mu = std::max(0.0, sun.y());
        ground_radiance = float(params.clear_sky.ground_albedo / kPiD) * (sun_irradiance * float(mu) + e.cast<float>());
    }

    const SkyImage& clear_sky(int n) {
        if (clear.resolution != n) {
            clear = make_clear_sky(params.clear_sky, n);
            ClearSkyParams no_disc = params.clear_sky;
            no_disc.sun_disc = false;
            clear_no_disc = params.clear_sky.sun_disc ? make_clear_sky(no_disc, n) : clear;
        }
        return clear;
    }

    // Optical depth along the sun's path through layers above `below` (index into layers), from
    // the point (x, altitude of layer `below`, z).
    double sun_depth_above(size_t below, double x, double z, double t, double footprint) const {
        double depth = 0.0, mu = std::max(sun.y(), 0.1);
        double h0 = layers[below].spec.altitude_m;
        for (size_t j = below + 1; j < layers.size(); ++j) {
            const LayerModel& l = layers[j];
            double s = (l.spec.altitude_m - h0) / std::max(sun.y(), 1e-3);
            double px = x + sun.x() * s, pz = z + sun.z() * s;
            double d = l.density(px - l.wind_x * t, pz - l.wind_z * t, t, footprint);
            depth += d * l.spec.optical_depth / mu;
        }
        return depth;
    }

    LayerHit hit(size_t k, const Vec3d& d, double t, double pixel_angle) const {
        LayerHit out;
        const LayerModel& l = layers[k];
        const CloudLayer& spec = l.spec;
        double h = spec.altitude_m;
        double dist = h / d.y();
        double px = d.x() * dist, pz = d.z() * dist;
        // The pixel's footprint on the layer: h * angle / cos^2 radially, / cos tangentially; their
        // geometric mean keeps detail without visible aliasing.
        double footprint = h * pixel_angle / std::pow(d.y(), 1.5);
        double qx = px - l.wind_x * t, qz = pz - l.wind_z * t;
        // Slant paths through a plane-parallel layer grow as 1 / cos; real layers are broken, so
        // cap the growth (otherwise every layer turns into a white wall at the horizon).
        const double view_depth = spec.optical_depth / std::max(d.y(), 0.25);
        double density = spec.mask ? l.density(qx, qz, t, footprint)
                                   : l.pixel_density(qx, qz, t, footprint, view_depth);
        if (density <= 0.0) return out;

        double tau_vertical = density * spec.optical_depth;
        double tau_view = density * view_depth;
        double alpha = -std::expm1(-tau_view);
        double air = std::exp(-dist / params.visibility_m);
        out.alpha = alpha * air;
        if (out.alpha <= 0.0) return out;

        double t_diff = diffuse_transmittance(tau_vertical);
        Eigen::Array3d radiance = (sky_ambient.cast<double>() * (0.35 + 0.65 * t_diff) +
                                   ground_radiance.cast<double>() * 0.6);
        if (sun.y() > 0.0) {
            double mu = sun.y();
            // Shadows of higher layers are soft (the sun is half a degree wide, and they are far):
            // their fine octaves would cost time and change nothing.
            double above = std::exp(-sun_depth_above(k, px, pz, t, std::max(footprint, 100.0)));
            // Density toward the sun inside the layer: cloud edges facing the sun are lit through
            // little cloud and glow; the far sides and thick cores are dark.
            // Offsets grow geometrically so that both small puffs and whole clouds shade.
            double sh = std::sqrt(sun.x() * sun.x() + sun.z() * sun.z());
            double toward = density;
            double light_extinction = std::min(0.1 * spec.optical_depth, 3.0);
            // Thin layers (cirrus) barely shade themselves: skip the samples.
            if (sh > 1e-6 && light_extinction > 0.5) {
                double light_path = std::min(spec.thickness_m * sh / mu, 2.0 * spec.feature_size_m);
                double sx = sun.x() / sh, sz = sun.z() / sh;
                double sum = 0.0;
                const double offsets[3] = {1.0 / 9.0, 1.0 / 3.0, 1.0};
                for (double f : offsets) {
                    double o = light_path * f;
                    sum += l.density(qx + sx * o, qz + sz * o, t, std::max(footprint, 0.5 * o));
                }
                toward = sum / 3.0;
            }
            double t_light = std::exp(-light_extinction * (0.5 * density + 0.5 * toward) / std::max(mu, 0.2));
            double cos_gamma = d.dot(sun);
            // Single scattering towards the viewer survives only where the cloud is thin along
            // the view (tau e^-tau, divided by the alpha it is later multiplied by): bright
            // silver linings at the edges, dark cores, no sun shining through a thick cloud.
            double single = cloud_phase(cos_gamma) * t_light * tau_view * std::exp(-tau_view) / alpha;
            // Seen from below a cloud shows its base, lit by what diffuses through it; towards the
            // horizon more and more of its sides, bright where they face the sun.
            double base = mu / kPiD * (0.1 + 0.9 * t_diff) * (0.3 + 0.7 * t_light);
            double dh = std::sqrt(std::max(0.0, 1.0 - d.y() * d.y()));
            double side_facing = dh > 1e-6 ? std::max(0.0, -(d.x() * sun.x() + d.z() * sun.z()) / dh) : 0.0;
            double side = 0.9 * side_facing / kPiD * (0.4 + 0.6 * t_light);
            double side_weight = spec.type == CloudType::Cumulus ? 0.8 * (1.0 - d.y()) : 0.0;
            double multiple = (1.0 - side_weight) * base + side_weight * side;
            radiance += sun_irradiance.cast<double>() * (above * (single + multiple));
        }
        out.radiance = (radiance * out.alpha).cast<float>();
        return out;
    }

    SkyImage render(double time_s, int n, Image* flow_out, double dt) {
        require(std::isfinite(time_s), "time must be finite");
        require(n >= 2 && n <= 16384, "resolution must be in [2, 16384], got " + std::to_string(n));
        require(std::isfinite(dt) && dt > 0.0, "dt must be a positive number of seconds, got " + std::to_string(dt));
        SkyImage out = clear_sky(n);
        out.time_seconds = time_s;
        out.sun_direction = sun.cast<float>();
        out.source = "procedural";
        out.units = kAbsoluteRadiance;
        if (flow_out) {
            *flow_out = Image(n, n, 3);
            flow_out->metadata.numbers["dynsky:time"] = time_s;
            flow_out->metadata.numbers["dynsky:flow_dt"] = dt;
            flow_out->metadata.strings["dynsky:flow_channels"] =
                "R,G: displacement over dt in pixels of this image (+x right, +y down); B: cloud opacity";
        }
        const double pixel_angle = kPiD / n;  // equidistant: every pixel spans pi/N radians of zenith angle
        const size_t nl = layers.size();
        // The sun's disc is dimmed by the clouds along the sun's own line of sight, in every pixel
        // its light falls in: it is half a degree wide, a 128 px pixel 1.4 degrees, and taken at
        // the pixel's centre the sun went out whenever a wisp crossed a centre up to a degree away
        // (5-10 s early or late at a cloud's edge), and lit the scene whatever lay over the sun itself.
        const float disc_transmittance = float(sun_transmittance(time_s));
        tbb::parallel_for(tbb::blocked_range<int>(0, n), [&](const tbb::blocked_range<int>& rows) {
            std::vector<LayerHit> hits(nl);
            for (int j = rows.begin(); j != rows.end(); ++j) {
                for (int i = 0; i < n; ++i) {
                    if (!out.in_disc(i, j)) continue;
                    double u = 2.0 * (i + 0.5) / n - 1.0, v = 2.0 * (j + 0.5) / n - 1.0;
                    Vec3d d = fisheye::direction_from_uv(u, v);
                    if (d.y() <= 1e-9 || nl == 0) continue;
                    for (size_t k = 0; k < nl; ++k) hits[k] = hit(k, d, time_s, pixel_angle);
                    // Composite from the highest layer down; the lowest is nearest the viewer.
                    // Haze between viewer and cloud (aerial perspective) shows the sky's light,
                    // never the sun's disc, which only the clouds' own transmittance lets through.
                    bool any = false;
                    for (size_t k = 0; k < nl; ++k) any = any || hits[k].alpha > 0.0;
                    Color sky_light = clear_no_disc.pixel(i, j);
                    const Color disc = (out.pixel(i, j) - sky_light).max(0.0f);
                    const bool sun_here = (disc > 0.0f).any();
                    if (any || sun_here) {
                        for (size_t k = nl; k-- > 0;)
                            sky_light = sky_light * float(1.0 - hits[k].alpha) + hits[k].radiance;
                        out.set_pixel(i, j, sky_light + disc * disc_transmittance);
                    }
                    if (!flow_out) continue;
                    // The flow is the most visible layer's: its opacity times what the layers
                    // below it let through.
                    size_t dominant = 0;
                    double best = 0.0, through = 1.0;
                    for (size_t k = 0; k < nl; ++k) {
                        double visible = hits[k].alpha * through;
                        if (visible > best) best = visible, dominant = k;
                        through *= 1.0 - hits[k].alpha;
                    }
                    const LayerModel& l = layers[dominant];
                    double s = l.spec.altitude_m / d.y();
                    Vec3d p = d * s;
                    Vec3d moved(p.x() + l.wind_x * dt, p.y(), p.z() + l.wind_z * dt);
                    double u0, v0, u1, v1;
                    fisheye::uv_from_direction(p.normalized(), &u0, &v0);
                    fisheye::uv_from_direction(moved.normalized(), &u1, &v1);
                    flow_out->at(i, j, 0) = float((u1 - u0) * 0.5 * n);
                    flow_out->at(i, j, 1) = float((v1 - v0) * 0.5 * n);
                    flow_out->at(i, j, 2) = float(1.0 - through);
                }
            }
        });
        return out;
    }

    double sun_transmittance(double time_s) const {
        if (sun.y() <= 0.0) return 1.0;  // clouds are not between the viewer and a set sun
        double depth = 0.0;
        for (size_t k = 0; k < layers.size(); ++k) {
            const LayerModel& l = layers[k];
            double s = l.spec.altitude_m / sun.y();
            double footprint = s * 2.0 * kSunHalfAngle;
            double qx = sun.x() * s - l.wind_x * time_s, qz = sun.z() * s - l.wind_z * time_s;
            depth += l.density(qx, qz, time_s, footprint) * l.spec.optical_depth / std::max(sun.y(), 0.1);
        }
        return std::exp(-depth);
    }
};

ProceduralSky::ProceduralSky(const ProceduralSkyParams& params) : impl_(std::make_unique<Impl>(params)) {}
ProceduralSky::~ProceduralSky() = default;
ProceduralSky::ProceduralSky(ProceduralSky&&) noexcept = default;
ProceduralSky& ProceduralSky::operator=(ProceduralSky&&) noexcept = default;

SkyImage ProceduralSky::render(double time_s, int resolution, Image* flow_out, double dt) {
    return impl_->render(time_s, resolution, flow_out, dt);
}

double ProceduralSky::sun_transmittance(double time_s) const { return impl_->sun_transmittance(time_s); }

double ProceduralSky::layer_density(size_t layer, double x_m, double z_m, double time_s) const {
    require(layer < impl_->layers.size(), "layer " + std::to_string(layer) + " does not exist");
    const LayerModel& l = impl_->layers[impl_->sorted_index[layer]];
    return l.density(x_m - l.wind_x * time_s, z_m - l.wind_z * time_s, time_s, 0.0);
}

void ProceduralSky::set_sun_direction(const Vec3d& sun_direction) {
    require(sun_direction.allFinite() && sun_direction.norm() > 0.0,
            "the sun direction must be a finite, non-zero vector");
    impl_->params.clear_sky.sun_direction = sun_direction.normalized();
    impl_->update_lighting();
}

const ProceduralSkyParams& ProceduralSky::params() const { return impl_->params; }

SkyImage render_procedural_sky(const ProceduralSkyParams& params, double time_s, int resolution, Image* flow_out,
                               double dt) {
    return ProceduralSky(params).render(time_s, resolution, flow_out, dt);
}

double procedural_sun_transmittance(const ProceduralSkyParams& params, double time_s) {
    return ProceduralSky(params).sun_transmittance(time_s);
}

}  // namespace dynsky
