#include "sky/hdr_recovery.h"

#include <algorithm>
#include <map>
#include <cmath>
#include <Eigen/SVD>
#include <opencv2/imgproc.hpp>
#include <iomanip>
#include <sstream>

#include "sky/clear_sky.h"
#include "sky/fisheye.h"
#include "util/color.h"
#include "util/error.h"
#include "util/math.h"

namespace dynsky {

namespace {

constexpr double kDeg = kPiD / 180.0;

double angle_between(const Vec3d& a, const Vec3d& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

double median_of(std::vector<double> v) { return v.empty() ? 0.0 : median(std::move(v)); }

}  // namespace

double trust_ramp(double clear_fraction, double none_below, double full_from) {
    return smoothstep01((clear_fraction - none_below) / std::max(1e-9, full_from - none_below));
}

std::string HdrCalibrationReport::summary() const {
    std::ostringstream s;
    s.precision(4);
    s << "HDR calibration: " << method;
    if (clear_weight > 0 && clear_weight < 1)
        s << " (clear pixels' weight " << std::setprecision(2) << clear_weight << ")";
    s << std::setprecision(4) << ", scale " << scale << " W m^-2 sr^-1 per unit";
    s.precision(3);
    s << ", clear pixels " << clear_fraction * 100 << "% of the disc (ratio spread " << ratio_spread * 100 << "%)";
    if (trusted_clear_fraction != clear_fraction)
        s << ", trusted as " << trusted_clear_fraction * 100 << "% (the sequence's around it)";
    s << ", colour: " << white_balance_method;
    if (white_balance_method.rfind("none", 0) != 0)
        s << " (grey R/G " << std::exp(grey_rg) << " B/G " << std::exp(grey_bg) << ", chroma stretch " << chroma_rg
          << " " << chroma_bg << ")";
    s << ", sun elevation " << sun_elevation_deg << " deg";
    if (sun_elevation_deg < 0) s << " (below the horizon: the model is a sunset sky, the scale is unreliable)";
    if (sun_joined) s << ", clipped sun seen joined to other clipped sky (put at the computed sun)";
    else if (sun_in_wide_glare)
        s << ", clipped sun seen in a wide clipped glare on a clear sky (put at the computed sun)";
    else if (sun_offset_deg >= 0) s << ", clipped sun seen " << sun_offset_deg << " deg from the computed one";
    s << (sun_restored ? ", sun disc restored" : (sun_visible ? ", sun seen" : ", sun not seen (not restored)"));
    return s.str();
}

std::string HdrCalibrationReport::sun_offset_warning() const {
    if (sun_elsewhere) {
        std::ostringstream s;
        s.precision(3);
        s << "no clipped sun near the sun computed for the photo's time and place, but one at its height "
          << sun_elsewhere->moved_deg << " deg away (zenith " << sun_elsewhere->seen_zenith_deg << " deg, computed "
          << sun_elsewhere->sun_zenith_deg << "): the sun disc was not restored and the sky's sun direction is the "
          << "computed one; if the camera's north is not where --north says, --north " << sun_elsewhere->north_deg
          << " (or --find-north) puts the computed sun on it (a camera whose east is on the right needs --mirror "
             "as well, and its own --north, since one sun cannot tell a mirrored view from a turned one)";
        return s.str();
    }
    if (!(sun_offset_deg > kSunOffsetWarningDeg)) return "";
    const bool at_seen = angle_between(used_sun, computed_sun) > 1e-6;
    std::ostringstream s;
    s.precision(3);
    s << "the clipped sun was found " << sun_offset_deg << " deg from the sun computed for the photo's time and place"
      << " (more than " << kSunOffsetWarningDeg << " deg: a wrong time, place or camera orientation, or glare or a"
      << " sunlit cloud edge taken for the sun); ";
    if (sun_restored)
        s << "the sun disc was restored " << (at_seen ? "where the photo shows it" : "at the computed position");
    else s << "the sun disc was not restored";
    s << ", and the sky's sun direction is " << (at_seen ? "the one seen" : "the computed one")
      << "; check --time, --lat/--lon and the camera's orientation (--north, or its preset's)";
    return s.str();
}

namespace {

// Clouds needed, as a share of the calibration's sky pixels, to white-balance on them, and the sun's
// lowest elevation for it (below it the light is coloured: dusk).
constexpr double kMinCloudFractionForGrey = 0.5;
constexpr double kMinSunElevationForGreyDeg = 10;
// Below it, a green excess of the clouds' colour over both red and blue (log ratio) is taken out.
constexpr double kGreenCastLog = 0.03;

}  // namespace

namespace {

// A clipped sun and its aureole stay well inside a 20 degree cone; a larger blob is a saturated
// overcast or cloud field, not a sun to place.
const double kMaxSunBlobSr = 2 * kPiD * (1 - std::cos(20 * kDeg));

// The photo's clipped pixels in 8-connected blobs (label 0: none; filled pixels left out when
// seen_only): per blob its solid angle, the sum of its pixels' directions (plain and weighted by
// solid angle) and its pixels' smallest angle to `towards`.
struct ClippedBlobs {
    int count = 0;  // labels, 0 included
    cv::Mat labels;
    std::vector<double> solid_angle, nearest;
    std::vector<Vec3d> direction_sum, weighted_sum;
};
ClippedBlobs clipped_blobs(const ImportedPhoto& photo, bool seen_only, const Vec3d& towards) {
    const int n = photo.sky.resolution;
    cv::Mat clipped(n, n, CV_8U);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const size_t p = size_t(j) * n + i;
            clipped.at<unsigned char>(j, i) = photo.clipped[p] && !(seen_only && photo.not_sky[p]) ? 255 : 0;
        }
    ClippedBlobs out;
    out.count = cv::connectedComponents(clipped, out.labels, 8, CV_32S);
    const size_t m = size_t(std::max(out.count, 1));
    out.solid_angle.assign(m, 0.0), out.nearest.assign(m, 1e9);
    out.direction_sum.assign(m, Vec3d::Zero()), out.weighted_sum.assign(m, Vec3d::Zero());
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const int l = out.labels.at<int>(j, i);
            if (l <= 0) continue;
            const Vec2 uv = fisheye::pixel_center_uv(i, j, n);
            const Vec3d w = fisheye::direction_from_uv(double(uv.x()), double(uv.y()));
            const double a = fisheye::pixel_solid_angle(i, j, n);
            out.nearest[size_t(l)] = std::min(out.nearest[size_t(l)], angle_between(w, towards));
            out.direction_sum[size_t(l)] += w;
            out.weighted_sum[size_t(l)] += a * w;
            out.solid_angle[size_t(l)] += a;
        }
    return out;
}

// A clipped blob's round core near the sun: the centre and radius of the largest disc inside it
// (distance transform of the blob) among centres within kSunCoreSearchDeg of `sun`.
constexpr double kSunCoreSearchDeg = 10, kMaxSunCoreDeg = 10, kSunCoreAgreeDeg = 3, kSunCoreOnSunDeg = 6;
struct SunCore {
    bool found = false;
    Vec3d direction = Vec3d::Zero();
    double radius_deg = 0;
};
SunCore round_core(const cv::Mat& labels, int blob, const Vec3d& sun) {
    const int n = labels.rows;
    cv::Mat mask = (labels == blob), distance;
    cv::distanceTransform(mask, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    SunCore core;
    float best = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const float d = distance.at<float>(j, i);
            if (d <= best) continue;
            const Vec2 uv = fisheye::pixel_center_uv(i, j, n);
            const Vec3d w = fisheye::direction_from_uv(double(uv.x()), double(uv.y()));
            if (angle_between(w, sun) > kSunCoreSearchDeg * kDeg) continue;
            best = d, core.found = true, core.direction = w;
        }
    core.radius_deg = best * 180.0 / n;  // equidistant: pi / n radians of zenith angle per pixel
    return core;
}

}  // namespace

std::optional<NorthFromSun> north_from_seen_sun(const ImportedPhoto& photo, const UtcTime& time,
                                                const GeoLocation& where, double max_zenith_error_deg) {
    if (photo.geometry.tilt_deg != 0) return std::nullopt;
    const SunPosition sp = compute_sun_position(time, where);
    if (sp.elevation_deg() < 3) return std::nullopt;
    const Vec3d sun = sp.direction();
    const ClippedBlobs blobs = clipped_blobs(photo, true, sun);
    const std::vector<double>& solid_angle = blobs.solid_angle;
    const std::vector<Vec3d>& centroid = blobs.weighted_sum;
    // At least the sun's disc and a pixel and a half: a low-resolution camera's clipped sun covers a
    // few pixels, under the 1.5 degree cone once asked for, and a clipped cloud edge beside it was
    // taken instead (north 8.6 degrees off on a 400 x 300 camera).
    const int n = photo.sky.resolution;
    const double max_sr = kMaxSunBlobSr, min_sr = std::max(2 * kPiD * (1 - std::cos(0.5 * kDeg)),
                                                           1.5 * fisheye::pixel_solid_angle(n / 2, n / 2, n));
    const double sun_zenith = std::acos(std::clamp(sun.y(), -1.0, 1.0));
    // The blob nearest the computed sun's zenith angle, larger ones preferred: each doubling of the
    // solid angle is worth 1.5 degrees of zenith error (a sun's wide glare, its centroid pulled a
    // degree or two off by the clouds beside it, still beats a pixel of cloud edge at the height).
    int best = -1;
    double best_score = 0;
    for (int l = 1; l < blobs.count; ++l) {
        if (solid_angle[size_t(l)] < min_sr || solid_angle[size_t(l)] > max_sr) continue;
        const Vec3d c = centroid[size_t(l)].normalized();
        const double error = std::abs(std::acos(std::clamp(c.y(), -1.0, 1.0)) - sun_zenith);
        if (error > max_zenith_error_deg * kDeg) continue;
        const double score = error / kDeg - 1.5 * std::log2(solid_angle[size_t(l)] / min_sr);
        if (best < 0 || score < best_score) best = l, best_score = score;
    }
    if (best < 0) return std::nullopt;
    const Vec3d seen = centroid[size_t(best)].normalized();
    NorthFromSun out;
    out.seen_zenith_deg = std::acos(std::clamp(seen.y(), -1.0, 1.0)) / kDeg;
    out.sun_zenith_deg = sun_zenith / kDeg;
    out.moved_deg = angle_between(seen, sun) / kDeg;
    // The photo shows a direction of azimuth A at angle north - A clockwise from its top (north + A
    // mirrored): the blob imported at azimuth A_seen under north_0 lies where north puts A_sun.
    const double turn = (fisheye::azimuth(sun) - fisheye::azimuth(seen)) / kDeg;
    const double north = photo.geometry.north_deg + (photo.geometry.mirrored ? -turn : turn);
    out.north_deg = std::fmod(std::fmod(north, 360.0) + 360.0, 360.0);
    return out;
}

ConsensusNorth consensus_north(const std::vector<double>& norths_deg, int tries) {
    if (norths_deg.empty()) throw Error("no north found to agree on");
    auto apart = [](double a, double b) { return std::abs(std::remainder(a - b, 360.0)); };
    ConsensusNorth out;
    double best_sum = 1e300;
    for (double a : norths_deg) {
        double sum = 0;
        for (double b : norths_deg) sum += apart(a, b);
        if (sum < best_sum) best_sum = sum, out.north_deg = a;
    }
    for (double a : norths_deg)
        if (apart(a, out.north_deg) <= 10)
            ++out.near, out.spread_deg = std::max(out.spread_deg, apart(a, out.north_deg));
    out.agreed = 2 * out.near > int(norths_deg.size()) && (out.near >= 2 || tries <= 1);
    return out;
}

SkyImage recover_hdr(const ImportedPhoto& photo, const HdrCalibrationParams& params, HdrCalibrationReport* report_out) {
    if (!photo.display_referred)
        throw_file_error(photo.photo_path,
                         "HDR recovery is for 8-bit (display-referred) photographs; this one is already linear HDR");
    validate_location(params.location);
    const SkyImage& in = photo.sky;
    const int n = in.resolution;
    HdrCalibrationReport rep;

    SunPosition sp = compute_sun_position(params.time, params.location);
    rep.clock_sun = sp.direction();
    rep.computed_sun = params.sun_in_photo ? params.sun_in_photo->normalized() : rep.clock_sun;
    rep.sun_elevation_deg = sp.elevation_deg();
    rep.used_sun = rep.computed_sun;
    const double sun_search_deg = params.sun_in_photo ? std::min(params.sun_search_deg, 5.0) : params.sun_search_deg;

    auto dir = [n](size_t p) {
        Vec2 uv = fisheye::pixel_center_uv(int(p % n), int(p / n), n);
        return fisheye::direction_from_uv(double(uv.x()), double(uv.y()));
    };

    // The sun as the photo shows it: the clipped blob nearest the computed sun, within the search cone.
    const ClippedBlobs clipped = clipped_blobs(photo, false, rep.computed_sun);
    const int blobs = clipped.count;
    const cv::Mat& labels = clipped.labels;
    const std::vector<double>&nearest = clipped.nearest, &solid_angle = clipped.solid_angle;
    const std::vector<Vec3d>& centroid = clipped.direction_sum;
    const double max_sun_sr = kMaxSunBlobSr;
    // Where the computed sun falls on a filled obstruction (the TSI's shadow band exists to hide
    // it), clipped clouds beside the obstruction are not the sun: see the band rule below instead.
    // The pixel the computed sun falls in (none below the horizon's circle).
    std::optional<size_t> sun_pixel;
    {
        double sx, sy;
        if (fisheye::uv_from_direction(rep.computed_sun, &sx, &sy)) {
            int si = std::clamp(int((sx + 1) / 2 * n), 0, n - 1), sj = std::clamp(int((sy + 1) / 2 * n), 0, n - 1);
            sun_pixel = size_t(sj) * n + si;
        }
    }
    const bool sun_hidden = sun_pixel && photo.not_sky[*sun_pixel] != 0;
    // Encoded values for the cloud rule (the photo's own, up to resampling).
    auto encoded = [&](size_t p) {
        const float* c = &in.rgb[p * 3];
        return Color(photo.encoded(c[0]), photo.encoded(c[1]), photo.encoded(c[2]));
    };
    int sun_blob = -1;
    for (int l = 1; l < blobs && !sun_hidden; ++l)
        if (nearest[size_t(l)] <= sun_search_deg * kDeg &&
            (sun_blob < 0 || nearest[size_t(l)] < nearest[size_t(sun_blob)]))
            sun_blob = l;
    // Where the photo shows the sun. A compact blob: its centroid, as always. But the sun's round
    // glare is often joined to other clipped sky (the bright horizon under a low sun, sunlit cloud
    // beside it): the blob's centroid then lay 18 degrees from the sun, or the blob was too large
    // and the sun not seen at all (73 % of the sky's irradiance lost). Such a blob is the sun when
    // it has a round core (the largest disc inside it near the computed sun, at most kMaxSunCoreDeg
    // across, a glare's size) on the computed sun; a joined blob's shape cannot say where the sun is
    // more closely than the clock does (its core leans into the neck by 2-4 degrees), so the sun is
    // put where the clock puts it.
    // An over-exposed clear sky clips wide around the sun (at 1/20 of the exposure that keeps the
    // sky, 20-30 degrees): the blob holds the computed sun, and most of the unclipped sky within 45
    // degrees of it is clear. Dropped as too large, the sun was not restored and 78 % of the sky's
    // irradiance was lost. Clipped cloud over the sun (overcast, a bright cumulus) has cloud around.
    auto wide_glare_on_clear_sky = [&](int blob) {
        if (!sun_pixel || labels.at<int>(int(*sun_pixel / n), int(*sun_pixel % n)) != blob) return false;
        long long around = 0, clear = 0;
        for (size_t p = 0; p < size_t(n) * n; ++p) {
            if (photo.not_sky[p] || photo.clipped[p] || !in.in_disc(int(p % n), int(p / n))) continue;
            if (angle_between(dir(p), rep.computed_sun) > 45 * kDeg) continue;
            ++around;
            const Color e = encoded(p);
            clear += !is_cloud(e[0], e[1], e[2], params.clear_rule);
        }
        return around > 0 && clear >= 0.6 * double(around);
    };
    Vec3d seen = Vec3d::Zero();
    if (sun_blob > 0) {
        const SunCore core = round_core(labels, sun_blob, rep.computed_sun);
        const Vec3d blob_centre = centroid[size_t(sun_blob)].normalized();
        const bool compact = solid_angle[size_t(sun_blob)] <= max_sun_sr;
        const bool joined_glare = core.found && core.radius_deg <= kMaxSunCoreDeg &&
                                  angle_between(core.direction, rep.computed_sun) <= kSunCoreOnSunDeg * kDeg;
        if (compact && (!core.found || angle_between(blob_centre, core.direction) <= kSunCoreAgreeDeg * kDeg))
            seen = blob_centre, rep.seen_sun = blob_centre;
        else if (joined_glare) seen = rep.computed_sun, rep.sun_joined = true;
        else if (compact) seen = blob_centre, rep.seen_sun = blob_centre;
        else if (wide_glare_on_clear_sky(sun_blob)) seen = rep.computed_sun, rep.sun_in_wide_glare = true;
        else sun_blob = -1;
    }
    if (sun_blob < 0 && !sun_hidden && !params.sun_in_photo) {
        std::optional<NorthFromSun> elsewhere = north_from_seen_sun(photo, params.time, params.location);
        if (elsewhere && elsewhere->moved_deg > sun_search_deg) rep.sun_elsewhere = elsewhere;
    }
    if (sun_blob > 0 && rep.computed_sun.y() > -0.02) {
        rep.sun_visible = true;
        rep.sun_offset_deg = angle_between(seen, rep.computed_sun) / kDeg;
        if (params.use_observed_sun) rep.used_sun = seen;
    }

    // A sun behind the shadow band (or another filled obstruction): seen if the sky next to the
    // obstruction near the sun, 4-15 degrees out, is mostly clear or clipped.
    if (sun_hidden && rep.computed_sun.y() > 0) {
        long long around = 0, bright_or_clear = 0;
        for (size_t p = 0; p < size_t(n) * n; ++p) {
            if (photo.not_sky[p]) continue;
            if (!in.in_disc(int(p % n), int(p / n))) continue;
            double a = angle_between(dir(p), rep.computed_sun);
            if (a < 4 * kDeg || a > 15 * kDeg) continue;
            ++around;
            Color e = encoded(p);
            if (photo.clipped[p] || !is_cloud(e[0], e[1], e[2], params.clear_rule)) ++bright_or_clear;
        }
        rep.sun_visible = around > 0 && bright_or_clear * 2 >= around;
    }

    ClearSkyParams model_params;
    model_params.sun_direction = rep.used_sun;
    model_params.turbidity = params.turbidity;
    model_params.ground_albedo = params.ground_albedo;
    model_params.sun_disc = true;
    ClearSkyModel model(model_params);

    // Calibration on clear pixels; subsampled so a 2048^2 import evaluates ~40k model pixels.
    long long disc = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) disc += in.in_disc(i, j) ? 1 : 0;
    int stride = std::max(1, int(std::sqrt(double(disc) / 40000.0)));
    struct Sample {
        Color photo, model;
        bool clear;
    };
    std::vector<Sample> samples;  // clear and cloudy, for the scale's fallback too
    long long clear = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            size_t p = size_t(j) * n + i;
            if ((i % stride) || (j % stride) || !in.in_disc(i, j) || photo.not_sky[p]) continue;
            const Vec3d w = dir(p);
            if (angle_between(w, rep.used_sun) < params.exclude_sun_deg * kDeg) continue;
            if (std::acos(std::clamp(w.y(), -1.0, 1.0)) > params.max_zenith_deg * kDeg) continue;
            Color e = encoded(p);
            // Clipped pixels are only lower bounds: never calibrate on them.
            bool is_clear = !photo.clipped[p] && !is_cloud(e[0], e[1], e[2], params.clear_rule);
            if (is_clear) ++clear;
            samples.push_back({in.pixel(i, j), model.sky_radiance(w), is_clear});
        }
    rep.clear_pixels = clear * stride * stride;  // counted on the subsample
    rep.clear_fraction = disc ? std::min(1.0, double(rep.clear_pixels) / double(disc)) : 0;
    rep.trusted_clear_fraction = params.trusted_clear_fraction.value_or(rep.clear_fraction);

    // Colour: log chromaticities (log R/G, log B/G) of the clear pixels against the model's.
    const float floor = 1e-4f;  // darker channels say nothing about colour
    auto add_chroma = [](const Color& c, std::vector<double>* rg, std::vector<double>* bg) {
        rg->push_back(std::log(c[0] / c[1]));
        bg->push_back(std::log(c[2] / c[1]));
    };
    std::vector<double> photo_rg, photo_bg, model_rg, model_bg;
    for (const Sample& s : samples)
        if (s.clear && s.photo.minCoeff() > floor && s.model.minCoeff() > 0) {
            add_chroma(s.photo, &photo_rg, &photo_bg);
            add_chroma(s.model, &model_rg, &model_bg);
        }
    // The fit is trusted fully from full_white_balance_fraction of the disc clear, and blended with
    // what stands in for it (the camera's typical colour, grey clouds, or nothing) from
    // min_white_balance_fraction up, so that a sky clouding over does not change colour at once
    // (the Mobotix 12:34 -> 12:35 CEST: R/G x1.15, B/G x0.78 between frames a minute apart).
    const bool fit = rep.trusted_clear_fraction >= params.min_white_balance_fraction && photo_rg.size() >= 20;
    const double fit_weight = fit ? trust_ramp(rep.trusted_clear_fraction, params.min_white_balance_fraction,
                                               params.full_white_balance_fraction)
                                  : 0.0;
    auto weight_text = [](double w) {
        std::ostringstream t;
        t << std::setprecision(2) << w;
        return t.str();
    };
    const auto& cam = params.camera_colour;
    if (!params.white_balance) {
        rep.white_balance_method = "none (the camera's colours kept)";
    } else if (cam) {
        rep.grey_rg = std::log(cam->grey[0] / cam->grey[1]);
        rep.grey_bg = std::log(cam->grey[2] / cam->grey[1]);
        rep.chroma_rg = cam->chroma_rg, rep.chroma_bg = cam->chroma_bg;
        // The stretch that takes the clear pixels' colour, seen from the camera's grey, to the model's.
        // Only where the model's sky is clearly coloured on that axis, and within a plausible range
        // (an overcast taken for clear sky gives a stretch near 0).
        auto stretch = [](double photo, double grey, double model, double* k) {
            if (std::abs(model) < 0.15) return false;
            const double v = (photo - grey) / model;
            if (!(v >= 0.5 && v <= 4)) return false;
            *k = v;
            return true;
        };
        double krg = 0, kbg = 0;
        if (fit_weight > 0 && stretch(median_of(photo_rg), rep.grey_rg, median_of(model_rg), &krg) &&
            stretch(median_of(photo_bg), rep.grey_bg, median_of(model_bg), &kbg)) {
            rep.chroma_rg = fit_weight * krg + (1 - fit_weight) * cam->chroma_rg;
            rep.chroma_bg = fit_weight * kbg + (1 - fit_weight) * cam->chroma_bg;
            rep.white_balance_method = "clear-sky pixels, from the camera's grey";
            if (fit_weight < 1)
                rep.white_balance_method += ", blended with its typical colour (fit's weight " +
                                            weight_text(fit_weight) + ")";
        } else {
            rep.white_balance_method = fit_weight > 0
                                           ? "the camera's typical colour (the clear pixels' colour is implausible)"
                                           : "the camera's typical colour (too few clear pixels to fit it)";
        }
    } else {
        double grey_rg = 0, grey_bg = 0;
        std::string stand_in;
        if (fit_weight < 1) {
            // An overcast photo from a camera of unknown colour, the sun well up: its clouds are made
            // grey by per-channel gains (their median colour), as clouds come out where the clear sky
            // sets the colour (the TSI's, R/G and B/G within 3 % of grey; the Mobotix's 12:00Z frame
            // within 10 %). The camera's white balance drifts from frame to frame (the Mobotix's clouds
            // run green in dark frames, pink at midday), so no fixed colour fits it. At dusk the light
            // itself is coloured: the camera's colours are kept.
            std::vector<double> cloud_rg, cloud_bg;
            for (const Sample& s : samples)
                if (!s.clear && s.photo.minCoeff() > floor) add_chroma(s.photo, &cloud_rg, &cloud_bg);
            const double cloud_fraction = double(cloud_rg.size()) / double(std::max<size_t>(1, samples.size()));
            const bool clouds = cloud_rg.size() >= 20 && cloud_fraction >= kMinCloudFractionForGrey;
            const double cloud_median_rg = median_of(cloud_rg), cloud_median_bg = median_of(cloud_bg);
            if (clouds && rep.sun_elevation_deg >= kMinSunElevationForGreyDeg) {
                grey_rg = cloud_median_rg;
                grey_bg = cloud_median_bg;
                stand_in = "cloud pixels made grey (per-channel gains; too few clear pixels)";
            } else if (clouds && std::max(cloud_median_rg, cloud_median_bg) < -kGreenCastLog) {
                // At dawn and dusk the light is coloured, but never green: clouds greener than both
                // their red and their blue are the camera's (the Mobotix's dark dawn frames came out
                // green, R/G and B/G 0.64-0.74). Only that excess is taken out: green brought down to the
                // larger of red and blue, so the light stays as warm or as cool as it was.
                grey_rg = grey_bg = std::max(cloud_median_rg, cloud_median_bg);
                stand_in =
                    "green cast of the clouds taken out (per-channel gains; the sun low, too few clear "
                    "pixels)";
            } else {
                stand_in = "none (too few clear pixels to fit it, and the camera's colour is unknown)";
            }
        }
        if (fit_weight > 0) {
            rep.grey_rg = fit_weight * (median_of(photo_rg) - median_of(model_rg)) + (1 - fit_weight) * grey_rg;
            rep.grey_bg = fit_weight * (median_of(photo_bg) - median_of(model_bg)) + (1 - fit_weight) * grey_bg;
            rep.white_balance_method = "clear-sky pixels (per-channel gains)";
            if (fit_weight < 1)
                rep.white_balance_method += ", blended with " + stand_in.substr(0, stand_in.find(" (")) +
                                            " (fit's weight " + weight_text(fit_weight) + ")";
        } else {
            rep.grey_rg = grey_rg, rep.grey_bg = grey_bg;
            rep.white_balance_method = stand_in;
        }
    }
    const bool recolour = params.white_balance && rep.white_balance_method.rfind("none", 0) != 0;
    // One pixel's colour corrected, its luminance kept. Near saturation in every channel (the sun's
    // clipped aureole and what the fill spreads from it) the camera's colour is lost, not tinted:
    // such pixels go to grey instead, smoothly from 85 % to 97 % of the clip level.
    const double clip = photo.clip_level;
    auto corrected = [&](Color c) -> Color {
        if (!recolour || !(c.minCoeff() > 0)) return c;
        const double rg = (std::log(c[0] / c[1]) - rep.grey_rg) / rep.chroma_rg;
        const double bg = (std::log(c[2] / c[1]) - rep.grey_bg) / rep.chroma_bg;
        Color out(float(std::exp(rg)), 1.0f, float(std::exp(bg)));
        const double y = luminance(c);
        const double w = smoothstep01((photo.encoded(c.minCoeff()) / clip - 0.85) / 0.12);
        return (1 - w) * out * float(y / luminance(out)) + w * Color(float(y), float(y), float(y));
    };
    for (Sample& s : samples) s.photo = corrected(s.photo);

    std::vector<double> ratios;
    double sum_model = 0, sum_photo = 0;
    for (const Sample& s : samples) {
        const double y_photo = luminance(s.photo), y_model = luminance(s.model);
        sum_model += y_model;
        sum_photo += y_photo;
        if (s.clear && y_photo > 1e-4) ratios.push_back(y_model / y_photo);
    }
    // The clear pixels' scale is trusted fully from full_clear_fraction of the disc, not at all
    // under min_clear_fraction, and blended (in log) with the fallback's between: a sky clouding
    // over frame by frame then changes its scale smoothly. The hard switch made a frame a minute
    // after the last one 1.9x darker (Mobotix 12:38 -> 12:39 CEST, the photographs within 3 %).
    const double clear_weight = ratios.size() >= 20 ? trust_ramp(rep.trusted_clear_fraction, params.min_clear_fraction,
                                                                 params.full_clear_fraction)
                                                    : 0.0;
    rep.clear_weight = clear_weight;
    double clear_scale = 0, fallback_scale = 0;
    if (clear_weight > 0) {
        clear_scale = median_of(ratios);
        std::vector<double> dev;
        for (double r : ratios) dev.push_back(std::abs(r - clear_scale));
        rep.ratio_spread = median_of(dev) / clear_scale;
    }
    if (clear_weight < 1) {
        if (!(sum_photo > 0)) throw_file_error(photo.photo_path, "the photograph's sky is black: nothing to calibrate");
        fallback_scale = sum_model / sum_photo;
    }
    if (clear_weight >= 1) {
        rep.method = "clear-sky pixels";
        rep.scale = clear_scale;
    } else if (clear_weight <= 0) {
        rep.method = "mean-luminance fallback";
        rep.scale = fallback_scale;
    } else {
        rep.method = "clear-sky pixels and mean-luminance fallback blended";
        rep.scale = std::exp(clear_weight * std::log(clear_scale) + (1 - clear_weight) * std::log(fallback_scale));
    }

    SkyImage out = in;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            if (in.in_disc(i, j)) out.set_pixel(i, j, corrected(in.pixel(i, j)) * float(rep.scale));

    if (params.restore_sun && rep.sun_visible && rep.used_sun.y() > 0) {
        // The disc, splatted conserving its energy exactly as make_clear_sky does, but only onto
        // the few pixels it touches: a full make_clear_sky costs seconds at 2048^2.
        std::map<size_t, Color> disc;
        model.splat_sun_disc(n, [&](int i, int j, const Color& c) {
            disc.emplace(size_t(j) * n + i, Color::Zero()).first->second += c;
        });
        // Clipped pixels of the sun's blob and the disc's pixels: the model's sky + disc where it
        // exceeds what the photo could record.
        auto restore = [&](size_t p, const Color& sun) {
            Color m = model.sky_radiance(dir(p)) + sun;
            int i = int(p % n), j = int(p / n);
            out.set_pixel(i, j, out.pixel(i, j).max(m));
        };
        for (const auto& [p, sun] : disc) restore(p, sun);
        if (sun_blob > 0)
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i) {
                    size_t p = size_t(j) * n + i;
                    if (labels.at<int>(j, i) == sun_blob && !disc.count(p)) restore(p, Color::Zero());
                }
        rep.sun_restored = true;
    }
    out.sun_direction = rep.used_sun.cast<float>();
    out.source = in.source + " (hdr: " + rep.method + ")";
    out.units = kAbsoluteRadiance;
    if (report_out) *report_out = rep;
    return out;
}

std::optional<SunTrack> fit_sun_track(const std::vector<Vec3d>& clock, const std::vector<Vec3d>& seen) {
    if (clock.size() != seen.size()) throw Error("fit_sun_track: as many clock suns as seen ones are needed");
    SunTrack track;
    track.seen = int(seen.size());
    std::vector<bool> use(seen.size(), true);
    std::vector<double> residual(seen.size());
    for (int pass = 0; pass < 5; ++pass) {  // until the photographs taken stop changing
        Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
        int used = 0;
        for (size_t k = 0; k < seen.size(); ++k)
            if (use[k]) h += seen[k].normalized() * clock[k].normalized().transpose(), ++used;
        if (used < 5) return std::nullopt;
        const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
        Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
        d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
        track.turn = svd.matrixU() * d * svd.matrixV().transpose();
        track.used = used;
        std::vector<double> kept;
        for (size_t k = 0; k < seen.size(); ++k) {
            residual[k] = angle_between(track.turn * clock[k].normalized(), seen[k].normalized()) / kDeg;
            if (use[k]) kept.push_back(residual[k]);
        }
        track.median_residual_deg = median(kept);
        const double limit = std::max(3 * track.median_residual_deg, 2.0);
        bool changed = false;
        for (size_t k = 0; k < seen.size(); ++k) {
            changed |= use[k] != (residual[k] <= limit);
            use[k] = residual[k] <= limit;
        }
        if (!changed) break;
    }
    double longest = 0;
    std::vector<double> offsets;
    for (size_t a = 0; a < seen.size(); ++a) {
        if (!use[a]) continue;
        offsets.push_back(angle_between(clock[a].normalized(), seen[a].normalized()) / kDeg);
        for (size_t b = a + 1; b < seen.size(); ++b)
            if (use[b]) longest = std::max(longest, angle_between(clock[a], clock[b]) / kDeg);
    }
    if (offsets.size() < 5 || longest < 10 || track.median_residual_deg > 2) return std::nullopt;
    track.taken = use;
    track.median_offset_deg = median(offsets);
    track.turn_deg = std::acos(std::clamp((track.turn.trace() - 1) / 2, -1.0, 1.0)) / kDeg;
    return track;
}

void validate_unit_map(const UnitMapParams& p) {
    if (!(p.scale > 0) || !std::isfinite(p.scale)) throw Error("unit map: scale must be positive and finite");
    if (!(p.max_radiance > p.scale) || !std::isfinite(p.max_radiance))
        throw Error("unit map: max_radiance must be finite and larger than scale");
}

namespace {

// log(1 + max / scale): the map's range in log units, computed once per image, not per channel.
double unit_log_range(const UnitMapParams& p) { return std::log1p(p.max_radiance / p.scale); }

float to_unit(float radiance, const UnitMapParams& p, double log_range) {
    double x = std::clamp(double(radiance), 0.0, p.max_radiance);
    return float(std::log1p(x / p.scale) / log_range);
}

float from_unit(float unit, const UnitMapParams& p, double log_range) {
    double y = std::clamp(double(unit), 0.0, 1.0);
    return float(p.scale * std::expm1(y * log_range));
}

}  // namespace

float radiance_to_unit(float radiance, const UnitMapParams& p) { return to_unit(radiance, p, unit_log_range(p)); }

float unit_to_radiance(float unit, const UnitMapParams& p) { return from_unit(unit, p, unit_log_range(p)); }

Image hdr_to_unit(const SkyImage& sky, const UnitMapParams& params) {
    validate_unit_map(params);
    const double log_range = unit_log_range(params);
    int n = sky.resolution;
    Image out(n, n, 3);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            if (!sky.in_disc(i, j)) continue;
            Color c = sky.pixel(i, j);
            for (int k = 0; k < 3; ++k) out.at(i, j, k) = to_unit(c[k], params, log_range);
        }
    out.metadata.numbers["dynsky:unit_scale"] = params.scale;
    out.metadata.numbers["dynsky:unit_max"] = params.max_radiance;
    // The sky's own metadata, less its source (a unit map is not that sky).
    write_sky_metadata(sky, &out.metadata);
    out.metadata.strings.erase("dynsky:source");
    return out;
}

SkyImage unit_to_hdr(const Image& unit, const UnitMapParams& params) {
    validate_unit_map(params);
    const auto& num = unit.metadata.numbers;
    auto differs = [](double a, double b) { return std::abs(a - b) > 1e-6 * std::max(std::abs(a), std::abs(b)); };
    if (auto it = num.find("dynsky:unit_scale"); it != num.end() && differs(it->second, params.scale))
        throw Error("unit image was encoded with scale " + std::to_string(it->second) + ", decoding with " +
                    std::to_string(params.scale));
    if (auto it = num.find("dynsky:unit_max"); it != num.end() && differs(it->second, params.max_radiance))
        throw Error("unit image was encoded with max " + std::to_string(it->second) + ", decoding with " +
                    std::to_string(params.max_radiance));
    SkyImage sky = sky_from_image(unit, "unit image");
    const double log_range = unit_log_range(params);
    for (int j = 0; j < sky.resolution; ++j)
        for (int i = 0; i < sky.resolution; ++i) {
            if (!sky.in_disc(i, j)) {
                sky.set_pixel(i, j, Color::Zero());
                continue;
            }
            Color c = sky.pixel(i, j);
            for (int k = 0; k < 3; ++k) c[k] = from_unit(c[k], params, log_range);
            sky.set_pixel(i, j, c);
        }
    return sky;
}

}  // namespace dynsky
