#include "frame/clear_cloudy_comparison.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <regex>
#include <sstream>

#include "renderer/accel.h"
#include "renderer/env_light.h"
#include "renderer/integrator.h"
#include "util/progress.h"
#include "util/version.h"
#include "util/image.h"
#include "motion/network_form.h"
#include "motion/radiance_scale.h"
#include "motion/sun_patch.h"
#include "sky/clear_sky.h"
#include "util/atomic_file.h"
#include "util/chart.h"
#include "util/error.h"
#include "util/exposure.h"

namespace dynsky {

namespace fs = std::filesystem;

namespace {

Image render_frame(const Accel& accel, EnvLight& light, const Camera& camera, std::shared_ptr<const SkyImage> sky,
                   int w, int h, int spp, uint64_t seed) {
    light.set_sky(std::move(sky));
    RenderSettings s;
    s.width = w, s.height = h, s.spp = spp, s.seed = seed, s.quiet = true;
    PathIntegrator integrator(accel, light, s);
    return integrator.render(camera).color;
}

// Mean luminance (cd m^-2 = 683 Y) of a (2r+1)^2 window around pixel (x, y).
double window_luminance(const Image& im, int x, int y, int r = 2) {
    double sum = 0;
    int n = 0;
    for (int j = std::max(0, y - r); j <= std::min(im.height - 1, y + r); ++j)
        for (int i = std::max(0, x - r); i <= std::min(im.width - 1, x + r); ++i) {
            const float* p = &im.pixels[(size_t(j) * im.width + i) * im.channels];
            sum += kLumensPerWatt * luminance(Color(p[0], p[1], p[2])), ++n;
        }
    return sum / std::max(n, 1);
}

// A diverging colormap for cv::applyColorMap (256 x 1 BGR): ColorBrewer's RdBu from dark blue (0:
// the cloudy sky darker) through white (128: no change) to dark red (255: brighter). The cyclic
// TWILIGHT_SHIFTED used before ended in the same dark purple at -3 and +3 stops.
cv::Mat diverging_colormap() {
    static const int rgb[11][3] = {{5, 48, 97},     {33, 102, 172},  {67, 147, 195},  {146, 197, 222},
                                   {209, 229, 240}, {247, 247, 247}, {253, 219, 199}, {244, 165, 130},
                                   {214, 96, 77},   {178, 24, 43},   {103, 0, 31}};
    cv::Mat lut(256, 1, CV_8UC3);
    for (int k = 0; k < 256; ++k) {
        const double x = k / 255.0 * 10;
        const int a = std::min(int(x), 9);
        const double f = x - a;
        for (int c = 0; c < 3; ++c)
            lut.at<cv::Vec3b>(k, 0)[2 - c] = uint8_t(std::lround((1 - f) * rgb[a][c] + f * rgb[a + 1][c]));
    }
    return lut;
}

// The side-by-side image (BGR, 8 bit; halves half_width wide, 8 px apart) with "clear" and "cloudy"
// under its halves, enlarged (nearest pixel) as the difference image is when a half is under 240 px,
// so the captions fit (at 64 px it was 136 x 36 pixels without a word).
cv::Mat with_captions(const cv::Mat& side, int half_width) {
    cv::Mat big = side;
    const int k = (240 + half_width - 1) / std::max(1, half_width);
    if (k > 1) cv::resize(side, big, cv::Size(), k, k, cv::INTER_NEAREST);
    cv::Mat out(big.rows + 22, big.cols, CV_8UC3, cv::Scalar(255, 255, 255));
    big.copyTo(out(cv::Rect(0, 0, big.cols, big.rows)));
    const int half = half_width * std::max(k, 1), gap = 8 * std::max(k, 1);
    const char* names[2] = {"clear", "cloudy"};
    for (int i = 0; i < 2; ++i) {
        int baseline = 0;
        const cv::Size size = cv::getTextSize(names[i], cv::FONT_HERSHEY_SIMPLEX, 0.45, 1, &baseline);
        const int centre = i == 0 ? half / 2 : half + gap + half / 2;
        cv::putText(out, names[i], cv::Point(centre - size.width / 2, big.rows + 16), cv::FONT_HERSHEY_SIMPLEX, 0.45,
                    cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    }
    return out;
}

// An 8-bit BGR picture as a display Image (0..1 RGB), for write_image.
Image image_of_bgr(const cv::Mat& bgr) {
    Image out(bgr.cols, bgr.rows, 3);
    for (int y = 0; y < bgr.rows; ++y)
        for (int x = 0; x < bgr.cols; ++x) {
            const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x);
            for (int c = 0; c < 3; ++c) out.pixels[(size_t(y) * bgr.cols + x) * 3 + c] = p[2 - c] / 255.0f;
        }
    return out;
}

// The difference image (BGR, 8 bit) with its colour bar below it: the colormap from -3 to +3 stops
// with labelled ticks. An image under 240 px wide is first enlarged by a whole factor (nearest
// pixel), so the bar's labels and title fit (at 64 px they ran into each other and the title was cut).
cv::Mat with_colour_bar(const cv::Mat& image) {
    cv::Mat coloured = image;
    if (const int k = (240 + image.cols - 1) / std::max(1, image.cols); k > 1)
        cv::resize(image, coloured, cv::Size(), k, k, cv::INTER_NEAREST);
    const int w = coloured.cols, bar_h = 14, margin = std::min(std::max(8, w / 20), w / 4), panel_h = 52;
    cv::Mat ramp(1, w - 2 * margin, CV_8UC1);
    for (int x = 0; x < ramp.cols; ++x)
        ramp.at<uint8_t>(0, x) = uint8_t(std::lround(255.0 * x / std::max(1, ramp.cols - 1)));
    cv::Mat ramp_rgb;
    cv::applyColorMap(ramp, ramp_rgb, diverging_colormap());
    cv::Mat panel(panel_h, w, CV_8UC3, cv::Scalar(255, 255, 255));
    for (int y = 4; y < 4 + bar_h; ++y) ramp_rgb.row(0).copyTo(panel(cv::Rect(margin, y, ramp.cols, 1)));
    const double scale = 0.4;
    for (int stops = -3; stops <= 3; ++stops) {
        int x = margin + int(std::lround((stops + 3) / 6.0 * (ramp.cols - 1)));
        cv::line(panel, cv::Point(x, 4 + bar_h), cv::Point(x, 4 + bar_h + 3), cv::Scalar(0, 0, 0));
        std::string label = (stops > 0 ? "+" : "") + std::to_string(stops);
        int baseline = 0;
        cv::Size size = cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline);
        cv::putText(panel, label, cv::Point(x - size.width / 2, 4 + bar_h + 5 + size.height), cv::FONT_HERSHEY_SIMPLEX,
                    scale, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    }
    const std::string title = "log2(cloudy / clear), stops";
    int baseline = 0;
    cv::Size size = cv::getTextSize(title, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline);
    cv::putText(panel, title, cv::Point((w - size.width) / 2, panel_h - 4), cv::FONT_HERSHEY_SIMPLEX, scale,
                cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    cv::Mat out;
    cv::vconcat(coloured, panel, out);
    return out;
}

}  // namespace

std::vector<std::pair<double, double>> parse_chart_points(const std::string& text) {
    std::vector<std::pair<double, double>> out;
    std::stringstream ss(text);
    std::string item;
    std::regex re("^\\s*([0-9.]+)\\s*,\\s*([0-9.]+)\\s*$");
    while (std::getline(ss, item, ';')) {
        std::smatch m;
        if (!std::regex_match(item, m, re))
            throw Error("--points '" + text + "': expected X,Y;X,Y;... with X, Y in [0, 1]");
        double x = 0, y = 0;
        try {
            size_t used_x = 0, used_y = 0;
            x = std::stod(m[1], &used_x), y = std::stod(m[2], &used_y);
            if (used_x != size_t(m[1].length()) || used_y != size_t(m[2].length())) throw std::invalid_argument("");
        } catch (const std::exception&) {
            throw Error("--points '" + text + "': '" + item + "' is not X,Y with X, Y in [0, 1]");
        }
        if (x > 1 || y > 1) throw Error("--points '" + text + "': coordinates are fractions of the image, in [0, 1]");
        out.emplace_back(x, y);
    }
    if (out.empty()) throw Error("--points: give at least one point");
    return out;
}

void render_clear_cloudy_comparison(const ComparisonSettings& o) {
    const int w = o.width, h = o.height, cw = o.chart_width, ch = o.chart_height;
    if (o.spp < 1 || o.chart_spp < 1) throw Error("--spp and --chart-spp must be at least 1");
    if (o.chart_frames < 2) throw Error("--chart-frames must be at least 2");
    if (!(o.duration > 0)) throw Error("--duration must be positive");
    auto points = parse_chart_points(o.points);
    // Neither the output folder nor a file written in it may be an input (a sky EXR named
    // OUT/clear.exr would be replaced), nor lie in an input folder (a model's).
    std::vector<std::string> outputs = {o.out};
    for (const char* name :
         {"clear.exr", "cloudy.exr", "side_by_side.png", "difference.png", "illuminance.csv", "illuminance.png"})
        outputs.push_back((fs::path(o.out) / name).string());
    {
        const std::string model = o.model.model.rfind("network:", 0) == 0 ? o.model.model.substr(8) : "";
        check_outputs_are_not_inputs(outputs, {o.sky.sky, o.sky.previous, o.scene.scene, model});
    }
    std::unique_ptr<tbb::global_control> threads;
    if (o.threads > 0)
        threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, o.threads);

    const SkySourceSpec& so = o.sky;
    SkyTimeline cloudy = make_sky_timeline(so, o.model);
    cloudy.check_span(o.duration);
    // The clear sky takes the cloudy one's sun at every moment: the clock's (skies made here, or
    // --time), else where the sky EXR has it.
    if (!cloudy.sun_direction_at(0.0))
        throw Error(so.sky +
                    ": the sky has no sun direction (dynsky:sun_* attributes): give --time (and --lat, --lon) "
                    "so the clear sky knows where the sun is");
    LoadedScene scene = load_scene(o.scene, float(w) / h);
    check_outputs_are_not_inputs(outputs, scene.scene.source_files);  // a texture beside the scene
    // Each output writable before any rendering (a folder in the way was found after it all).
    for (size_t k = 1; k < outputs.size(); ++k) check_output_file(outputs[k]);
    const OutputFolder folder(o.out);  // removed again if this run fails before writing anything
    remove_stale_temporaries(o.out);   // of a killed run into the same folder
    const int sky_n = cloudy.step(0)->resolution;
    // A sky in units of its own is compared with the clear sky brought to its scale: its figures
    // are then not lux. Said, as is a sky that does not say what its units are.
    if (!reports_silenced() && cloudy.step(0)->units != kAbsoluteRadiance) {
        if (cloudy.radiance_scale() != 1.0)
            std::fprintf(stderr,
                         "dynsky: note: the clear sky is given the cloudy sky's scale (x %.3g): the illuminance "
                         "figures are 683 x its units, not lux\n",
                         cloudy.radiance_scale());
        else
            std::fprintf(stderr,
                         "dynsky: note: %s does not record its units: its pixels are taken as W m^-2 sr^-1 (they are "
                         "within 1.5 x the clear-sky model's)\n",
                         so.sky.c_str());
    }
    // The clear sky of the cloudy one's haze: a Hosek-Wilkie sky of another turbidity keeps its own
    // (a cloudless turbidity-6 sky came out brighter than "clear" at 3), photographs and cloudy skies
    // 3 (motion/network_form.h clear_sky_turbidity), as the moving sky's own background.
    // A sky made here has the turbidity it was made with (--turbidity; the procedural clouds' haze).
    const double turbidity = is_generated_sky(so.sky)
                                 ? so.turbidity
                                 : clear_sky_turbidity(*cloudy.step(0), *cloudy.sun_direction_at(0.0));
    // The clear sky's sun is the cloudy sky's own when its first sky shows it whole: a downloaded
    // HDRI's sun is rarely the model's (a cloudless one's sun came out 2.7 x weaker than its own
    // in the clear sky, and clouds far from the sun "brightened" the scene 1.5 stops).
    SunPatch own_sun;
    {
        SkyImage first = cloudy.sky_at(0.0);
        first.sun_direction = cloudy.sun_direction_at(0.0)->cast<float>();
        SunPatch cut = remove_sun(&first);
        const double share = sun_patch_share(cut, sky_n, *cloudy.sun_direction_at(0.0), turbidity) /
                             std::max(cloudy.radiance_scale(), 1e-30);
        if (share >= 0.5) own_sun = std::move(cut);
        // In a sky's own units a sun that holds little light may be clipped (an 8-bit photograph
        // imported with --hdr none) rather than covered: the clear sky's sun is the model's, and the
        // cloudy figures came out 23 % darker for the light the clipping lost (a compare audit).
        else if (cloudy.radiance_scale() != 1.0 && cloudy.sun_direction_at(0.0)->y() > 0)  // a warning: even with -q
            std::fprintf(stderr,
                         "dynsky: warning: %s holds %.2f x the clear-sky model's sun light at its sun: covered by "
                         "cloud, or clipped (an 8-bit photograph imported with --hdr none, not recovered to HDR); in a "
                         "sky's own units the two cannot be told apart, and a clipped sun reads as cloud "
                         "shade against the clear sky's whole sun\n",
                         so.sky.c_str(), share);
        if (!own_sun.empty() && !reports_silenced() && std::abs(share - 1) > 0.1)
            std::fprintf(stderr,
                         "dynsky: note: the clear sky takes %s's own sun (%.2f x the clear-sky model's at that "
                         "height)\n",
                         so.sky.c_str(), share);
    }
    // Else the model's own sun, cut from the clear sky at the start and moved the same way: drawn
    // anew at each time it fell on whole pixels, and the clear column stepped by up to 1 % as the
    // sun crossed them (0.8 % apart at the same time from a clear and an overcast start).
    if (own_sun.empty()) {
        ClearSkyParams p0;
        p0.sun_direction = *cloudy.sun_direction_at(0.0);
        p0.turbidity = turbidity;
        SkyImage c0 = make_clear_sky(p0, sky_n, false);
        if (cloudy.radiance_scale() != 1.0) scale_radiance(&c0, cloudy.radiance_scale());
        c0.sun_direction = p0.sun_direction.cast<float>();
        own_sun = remove_sun(&c0);
    }
    auto clear_at = [&](double t) {
        ClearSkyParams p;
        p.sun_direction = *cloudy.sun_direction_at(t);
        p.turbidity = turbidity;
        auto s = std::make_shared<SkyImage>(make_clear_sky(p, sky_n));
        // In the cloudy sky's units (a sky in other units than the models' comes back in its own:
        // motion/radiance_scale.h), so the two are compared like for like.
        if (cloudy.radiance_scale() != 1.0) scale_radiance(s.get(), cloudy.radiance_scale());
        if (!own_sun.empty()) {
            // Dimmed and reddened as the model's sun at t (the cloudy sky's is, in its timeline):
            // put back at its start radiance, the clear sky's sun stayed at the start's strength,
            // and an hour of a Paris evening read 17 % more light than the cloudy sky of the same
            // clear start.
            s->sun_direction = p.sun_direction.cast<float>();
            remove_sun(s.get());
            SunPatch relit = own_sun;
            const Color factor = sun_patch_relight(sky_n, *cloudy.sun_direction_at(0.0), p.sun_direction, turbidity);
            for (Color& e : relit.excess) e *= factor;
            insert_sun(s.get(), relit, p.sun_direction);
        }
        s->time_seconds = t;
        return s;
    };

    Accel accel(scene.scene);
    EnvLight light(o.scene.ground_albedo, path_tracer_sky_sampler());  // as render's default (cdf+mis)
    auto clear0 = clear_at(0.0);
    auto cloudy0 = std::make_shared<const SkyImage>(cloudy.sky_at(0.0));
    // Progress with time left: the two frames, then the chart's pairs.
    ProgressBar frames_progress(2, "compare: the clear and the cloudy frame");
    Image a = render_frame(accel, light, scene.camera, clear0, w, h, o.spp, o.seed);
    frames_progress.advance();
    float ev = exposure_for_irradiance(light.sky_irradiance());
    Color e_clear = light.sky_irradiance();
    Image b = render_frame(accel, light, scene.camera, cloudy0, w, h, o.spp, o.seed);
    frames_progress.finish();
    Color e_cloudy = light.sky_irradiance();
    if (is_black_everywhere(a) && is_black_everywhere(b))
        std::fprintf(stderr, "dynsky: warning: the clear and the cloudy image are black: each %s\n", kBlackRenderHint);
    // What each image is, as render's and animate's say (they were written bare).
    auto describe = [&](Image* image, const SkyImage& sky, const std::string& model) {
        ImageMetadata& m = image->metadata;
        write_sky_metadata(sky, &m);  // its sun and source
        m.numbers["dynsky:time"] = 0.0;
        m.numbers["dynsky:spp"] = o.spp;
        m.numbers["dynsky:seed"] = double(o.seed);
        m.numbers["dynsky:png_exposure_ev"] = ev;
        m.numbers["dynsky:ground_albedo"] = o.scene.ground_albedo;
        m.strings["dynsky:sky"] = sky.source;
        if (!model.empty()) m.strings["dynsky:sky_model"] = model;
        m.strings["dynsky:scene"] = o.scene.scene;
        m.strings["dynsky:camera"] = scene.camera.name;
        record_image_inputs(&m, scene.path, o.sky);  // the build, the files, how the sky file was taken
        if (const std::string when = exif_date_time(o.sky, sky, 0.0); !when.empty()) m.strings["DateTime"] = when;
    };
    describe(&a, *clear0, "");
    describe(&b, *cloudy0, cloudy.model().name());
    // The earlier run's outputs go just before the first of this run's is written (stopped while
    // rendering, the earlier results stay whole): one stopped while writing leaves no mix of two
    // runs' files.
    remove_earlier_outputs(std::vector<std::string>(outputs.begin() + 1, outputs.end()));
    write_image((fs::path(o.out) / "clear.exr").string(), a);
    write_image((fs::path(o.out) / "cloudy.exr").string(), b);
    Image da = tonemap_to_display(a, ev), db = tonemap_to_display(b, ev);
    Image side;
    side.width = 2 * w + 8, side.height = h, side.channels = 3;
    side.pixels.assign(size_t(side.width) * h * 3, 1.0f);
    Image diff = side;
    diff.width = w;
    diff.pixels.assign(size_t(w) * h * 3, 0.0f);
    cv::Mat ratio8(h, w, CV_8UC1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            for (int c = 0; c < 3; ++c) {
                side.pixels[(size_t(y) * side.width + x) * 3 + c] = da.pixels[(size_t(y) * w + x) * da.channels + c];
                side.pixels[(size_t(y) * side.width + x + w + 8) * 3 + c] =
                    db.pixels[(size_t(y) * w + x) * db.channels + c];
            }
            const float* pa = &a.pixels[(size_t(y) * w + x) * a.channels];
            const float* pb = &b.pixels[(size_t(y) * w + x) * b.channels];
            double la = luminance(Color(pa[0], pa[1], pa[2])), lb = luminance(Color(pb[0], pb[1], pb[2]));
            // log2(cloudy / clear) in [-3, 3] stops -> 0..255 (128: no change)
            double stops = std::log2((lb + 1e-6) / (la + 1e-6));
            ratio8.at<uint8_t>(y, x) = uint8_t(std::lround(std::clamp(128.0 + stops / 3.0 * 127.0, 0.0, 255.0)));
        }
    cv::Mat coloured;
    cv::applyColorMap(ratio8, coloured, diverging_colormap());
    diff = image_of_bgr(with_colour_bar(coloured));
    cv::Mat side_bgr(h, side.width, CV_8UC3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < side.width; ++x)
            for (int c = 0; c < 3; ++c)
                side_bgr.at<cv::Vec3b>(y, x)[2 - c] = uint8_t(
                    std::lround(255.0 * std::clamp(side.pixels[(size_t(y) * side.width + x) * 3 + c], 0.0f, 1.0f)));
    // Like every picture the program renders, they say which build made them (a PNG text chunk).
    Image side_by_side = image_of_bgr(with_captions(side_bgr, w));
    side_by_side.metadata.strings["Software"] = diff.metadata.strings["Software"] = dynsky_version();
    side_by_side.metadata.strings["ImageDescription"] = "dynsky compare: the clear sky's frame | the cloudy sky's";
    diff.metadata.strings["ImageDescription"] = "dynsky compare: log2(cloudy / clear) luminance, -3..+3 stops";
    write_image((fs::path(o.out) / "side_by_side.png").string(), side_by_side);
    write_image((fs::path(o.out) / "difference.png").string(), diff);
    const char* lux = cloudy.radiance_scale() != 1.0 ? "(683 x the sky's units)" : "lx";
    if (!reports_silenced())
        std::fprintf(
            stderr,
            "wrote %s/side_by_side.png (clear | cloudy, same exposure %.2f EV) and difference.png (log2 cloudy/clear, "
            "-3..+3 stops: blue darker under the clouds, white no change, red brighter; colour bar below)\n"
            "global horizontal illuminance at t=0: clear %.0f %s, cloudy %.0f %s\n",
            o.out.c_str(), ev, kLumensPerWatt * luminance(e_clear), lux, kLumensPerWatt * luminance(e_cloudy), lux);

    // Illuminance over time at the chosen points, under both skies (the sun follows the clock).
    std::string csv = (fs::path(o.out) / "illuminance.csv").string();
    {
        std::ostringstream f;  // written whole at the end: a stopped run leaves no half table
        // In a sky's own units the figures are 683 x those, not lux and cd/m2 (the note said so,
        // the table and the chart did not).
        const bool absolute = cloudy.radiance_scale() == 1.0;
        const std::string e_unit = absolute ? "lx / 100" : "683 x sky units / 100",
                          l_unit = absolute ? "cd/m2" : "683 x sky units";
        f << "time_s,clear sky horizontal (" << e_unit << "),cloudy sky horizontal (" << e_unit << ")";
        for (size_t p = 0; p < points.size(); ++p)
            f << ",cloudy point " << p + 1 << " (" << l_unit << "),clear point " << p + 1 << " (" << l_unit << ")";
        f << '\n';
        ProgressBar chart_progress(o.chart_frames, "compare: chart frames");
        for (int k = 0; k < o.chart_frames; ++k) {
            double t = o.duration * k / (o.chart_frames - 1);
            Image ic = render_frame(accel, light, scene.camera, clear_at(t), cw, ch, o.chart_spp, o.seed);
            double ec = kLumensPerWatt * luminance(light.sky_irradiance());
            Image iy = render_frame(accel, light, scene.camera, std::make_shared<const SkyImage>(cloudy.sky_at(t)), cw,
                                    ch, o.chart_spp, o.seed);
            double ey = kLumensPerWatt * luminance(light.sky_irradiance());
            f << t << ',' << ec / 100 << ',' << ey / 100;
            for (auto [px, py] : points) {
                int x = std::min(cw - 1, int(px * cw)), y = std::min(ch - 1, int(py * ch));
                f << ',' << window_luminance(iy, x, y) << ',' << window_luminance(ic, x, y);
            }
            f << '\n';
            chart_progress.advance();
        }
        chart_progress.finish();
        write_file_atomic(csv, f.str());
    }
    make_line_chart(csv, (fs::path(o.out) / "illuminance.png").string(),
                    "Clear vs cloudy sky: illuminance and luminance at chosen points", "time (s)",
                    cloudy.radiance_scale() == 1.0 ? "lux / 100, cd/m^2"
                                                   : "683 x the sky's units (/ 100 for illuminance)",
                    true);
    if (!reports_silenced()) std::fprintf(stderr, "wrote %s and illuminance.png\n", csv.c_str());
}

}  // namespace dynsky
