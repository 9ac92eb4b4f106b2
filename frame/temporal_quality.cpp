#include "frame/temporal_quality.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <regex>
#include <sstream>
#include <vector>

#include "util/atomic_file.h"
#include "util/chart.h"
#include "util/error.h"
#include "util/image.h"
#include "util/math.h"
#include "util/parse.h"

namespace dynsky {

namespace fs = std::filesystem;

namespace {

// The folder's frame_NNNN.exr in frame order (four digits or more: frame 10000 is frame_10000.exr),
// those of the first frame's settings only (frames of other settings are another run's: said, left
// out).
std::vector<std::string> frame_files(const std::string& dir) {
    std::vector<std::pair<long, std::string>> found;
    std::regex re("^frame_([0-9]{4,9})\\.exr$");
    std::smatch m;
    for (const auto& e : fs::directory_iterator(dir)) {
        const std::string name = e.path().filename().string();
        if (std::regex_match(name, m, re)) found.emplace_back(std::stol(m[1].str()), e.path().string());
    }
    std::sort(found.begin(), found.end());
    std::vector<std::string> out;
    if (found.empty()) return out;
    const std::string hash = image_header_strings(found.front().second, {"dynsky:settings_hash"}).front();
    std::vector<std::string> other;
    for (const auto& [k, path] : found) {
        if (!hash.empty() && image_header_strings(path, {"dynsky:settings_hash"}).front() != hash)
            other.push_back(fs::path(path).filename().string());
        else out.push_back(path);
    }
    if (!other.empty())
        std::fprintf(stderr,
                     "dynsky: note: %s: %zu frame(s) made with other settings than the first left out (%s%s: "
                     "another run's)\n",
                     dir.c_str(), other.size(), other.front().c_str(), other.size() > 1 ? ", ..." : "");
    return out;
}

}  // namespace

void analyse_temporal_quality(const std::string& folder) {
    struct {
        const std::string& folder;
    } o{folder};
    if (!fs::is_directory(o.folder))
        throw_file_error(o.folder, "not a folder (give the --out folder of 'dynsky animate')");
    auto files = frame_files(o.folder);
    if (files.size() < 3) throw_file_error(o.folder, "needs at least 3 frame_NNNN.exr files");
    // Pairs of neighbouring frames only: a gap would be scored as one frame's change.
    auto number = [](const std::string& file) { return std::stoi(fs::path(file).stem().string().substr(6)); };
    for (size_t k = 1; k < files.size(); ++k)
        if (number(files[k]) != number(files[k - 1]) + 1) {
            const int a = number(files[k - 1]) + 1, b = number(files[k]) - 1;
            throw_file_error(o.folder, (a == b ? "frame " + std::to_string(a) + " is"
                                               : "frames " + std::to_string(a) + "-" + std::to_string(b) + " are") +
                                           " missing: render them first (dynsky animate resumes)");
        }
    std::string csv = (fs::path(o.folder) / "temporal.csv").string();
    std::ostringstream f;  // written whole once every frame is read: a bad frame leaves no table
    f << "time_s,relative change (%),boundary\n";
    // A rendered frame is finite everywhere; one that is not was damaged since (its NaN would
    // make the whole table NaN).
    auto read_frame = [](const std::string& file) {
        Image image = read_image(file);
        for (const char* key : {"dynsky:time", "dynsky:medium_step_seconds"})
            if (!image.metadata.numbers.count(key))
                throw_file_error(file, std::string("has no ") + key + ": not a frame of 'dynsky animate'");
        if (const long i = first_non_finite(image); i >= 0)
            throw_file_error(file, non_finite_pixel_text(image, i) +
                                       ": a damaged frame; render it again (dynsky animate resumes)");
        return image;
    };
    Image prev = read_frame(files[0]);
    double sum_b = 0, sum_w = 0;
    int nb = 0, nw = 0;
    for (size_t k = 1; k < files.size(); ++k) {
        Image cur = read_frame(files[k]);
        if (cur.width != prev.width || cur.height != prev.height)
            throw_file_error(files[k], "size differs from the previous frame");
        double t0 = prev.metadata.numbers["dynsky:time"], t1 = cur.metadata.numbers["dynsky:time"];
        double dt = cur.metadata.numbers["dynsky:medium_step_seconds"];
        if (!(t1 > t0))
            throw_file_error(files[k], "its time (" + number_text(t1) + " s) does not follow the previous frame's (" +
                                           number_text(t0) + " s): a copied or foreign frame");
        double num = 0, den = 0;
        for (size_t p = 0; p < cur.pixels.size(); p += size_t(cur.channels)) {
            double la = luminance(Color(prev.pixels[p], prev.pixels[p + 1], prev.pixels[p + 2]));
            double lb = luminance(Color(cur.pixels[p], cur.pixels[p + 1], cur.pixels[p + 2]));
            num += std::abs(lb - la), den += 0.5 * (la + lb);
        }
        if (!(den > 0))
            throw_file_error(files[k], "it and the frame before it are black everywhere: no change to measure");
        double change = 100.0 * num / den;
        // The pair straddles (or ends on) a medium-step boundary i * Delta t.
        bool boundary = dt > 0 && std::floor(t1 / dt + 1e-9) > std::floor(t0 / dt + 1e-9);
        (boundary ? sum_b : sum_w) += change;
        (boundary ? nb : nw) += 1;
        f << t1 << ',' << change << ',' << (boundary ? 1 : 0) << '\n';
        prev = std::move(cur);
    }
    write_file_atomic(csv, f.str());
    make_line_chart(csv, (fs::path(o.folder) / "temporal.png").string(),
                    "Frame-to-frame change (shaded: pairs across a medium-step boundary)",
                    "time of the later frame (s)", "mean |dL| / L (%)", false);
    // A mean of no pairs, or a ratio without both kinds, is not a figure: said in words.
    auto mean_text = [](double sum, int n) {
        return n ? number_text(sum / n, 4) + "% (" + std::to_string(n) + " pairs)" : std::string("none (0 pairs)");
    };
    const std::string ratio = (nb && nw && sum_w > 0)
                                  ? number_text((sum_b / nb) / (sum_w / nw), 3)
                                  : std::string(nb ? "none (no pair within an interval)"
                                                   : "none (no pair across a medium-step boundary: the frames lie "
                                                     "within one step, or the frames carry no step length)");
    std::printf(
        "frames: %zu; mean frame-to-frame luminance change: across medium-step boundaries %s, within intervals %s; "
        "ratio %s\n",
        files.size(), mean_text(sum_b, nb).c_str(), mean_text(sum_w, nw).c_str(), ratio.c_str());
    std::printf("wrote %s and temporal.png\n", csv.c_str());
}

}  // namespace dynsky
