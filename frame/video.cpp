#include "frame/video.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "util/atomic_file.h"
#include "util/child_process.h"
#include "util/error.h"
#include "util/frame_names.h"
#include "util/image.h"

namespace dynsky {

namespace fs = std::filesystem;

namespace {

// ffmpeg may exit 0 when the disk fills while it writes the MP4's index (the trailer), leaving a
// file that does not play. An MP4 is complete when its top-level boxes tile the file exactly and
// include the header (ftyp), the data (mdat) and the index (moov). Returns "" or what is wrong.
std::string mp4_problem(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    std::error_code ec;
    const uint64_t size = fs::file_size(path, ec);
    if (!f || ec) return "cannot read it back";
    bool ftyp = false, moov = false, mdat = false;
    for (uint64_t at = 0; at < size;) {
        unsigned char h[16];
        f.seekg(std::streamoff(at));
        if (size - at < 8 || !f.read(reinterpret_cast<char*>(h), 8)) return "cut short inside a box header";
        uint64_t box = (uint64_t(h[0]) << 24) | (uint64_t(h[1]) << 16) | (uint64_t(h[2]) << 8) | h[3];
        const std::string type(reinterpret_cast<char*>(h + 4), 4);
        if (box == 1) {
            if (size - at < 16 || !f.read(reinterpret_cast<char*>(h + 8), 8)) return "cut short inside a box header";
            box = 0;
            for (int i = 8; i < 16; ++i) box = (box << 8) | h[i];
        } else if (box == 0) {
            box = size - at;  // to the end of the file
        }
        if (box < 8 || box > size - at) return "cut short inside its '" + type + "' box";
        ftyp |= type == "ftyp", moov |= type == "moov", mdat |= type == "mdat";
        at += box;
    }
    if (!ftyp || !mdat) return "no MP4 header or no video data";
    if (!moov) return "no index (moov box): the trailer was not written";
    return "";
}

}  // namespace

void make_video(const std::string& dir, const std::string& prefix, int frames, double fps, const std::string& out,
                bool quiet) {
    TemporaryFile tmp(out);
    // ffmpeg reads a '%' in the input pattern as its own (only the frame number's may be one) and a
    // path starting with '-' or 'word:' as an option or a protocol ("100% cover/", "-take2/",
    // "shot:2/" lost the videos after the render): both paths absolute, the folder's '%' doubled.
    std::string folder;
    for (char c : fs::absolute(dir).lexically_normal().string())
        folder += c == '%' ? std::string("%%") : std::string(1, c);
    if (!folder.empty() && folder.back() != '/') folder += '/';
    const std::string pattern = folder + numbered_pattern(prefix, ".png", frames);
    const std::string output = fs::absolute(tmp.path()).lexically_normal().string();
    char rate[32];
    std::snprintf(rate, sizeof rate, "%g", fps);
    // Frames 0 .. frames - 1 only: an earlier, longer run's frames after them in the folder are not this
    // animation's (a 5 s animation was encoded as 20 s).
    const ChildResult run = run_program({"ffmpeg",
                                         "-y",
                                         "-loglevel",
                                         "error",
                                         "-framerate",
                                         rate,
                                         "-start_number",
                                         "0",
                                         "-i",
                                         pattern,
                                         "-frames:v",
                                         std::to_string(frames),
                                         "-vf",
                                         "scale=trunc(iw/2)*2:trunc(ih/2)*2",
                                         "-c:v",
                                         "libx264",
                                         "-pix_fmt",
                                         "yuv420p",
                                         "-crf",
                                         "18",
                                         output});
    if (!run.started)
        throw_file_error(out, "could not write the video: ffmpeg " +
                                  (run.spawn_error == ENOENT
                                       ? std::string("is not installed (--no-video skips the videos)")
                                       : "could not be started: " + std::string(std::strerror(run.spawn_error))));
    if (!run.exited || run.exit_code != 0)
        throw_file_error(out, "could not write the video: ffmpeg " +
                                  (run.exited ? "failed (exit " + std::to_string(run.exit_code) + ")"
                                              : std::string("was killed")));
    std::error_code ec;
    if (fs::file_size(tmp.path(), ec) > 0 && !ec)  // a missing or empty file: commit() says so
        if (std::string problem = mp4_problem(tmp.path()); !problem.empty())
            throw_file_error(out, "could not write the video: ffmpeg exited 0 but its file is incomplete: " + problem);
    tmp.commit("ffmpeg");
    if (!quiet) std::fprintf(stderr, "wrote %s\n", out.c_str());
}

void contact_sheet_grid(int total, int* count, int* columns) {
    const int n = std::clamp(total, 1, 12);
    // Up to 5 in one row; more in the rows of 4, 3 or 5 that show the most of them (9 frames: 3 x 3,
    // where rows of 4 dropped one).
    int c = n;
    if (n > 5) {
        c = 4;
        for (int option : {3, 5})
            if (n / option * option > n / c * c) c = option;
    }
    *count = n / c * c, *columns = c;
}

std::string frame_time_label(double seconds) {
    char text[64];
    if (!(std::abs(seconds) < 100)) {
        const bool negative = seconds < 0;
        const long long whole = std::llround(std::abs(seconds));
        const long long h = whole / 3600, m = whole / 60 % 60, s = whole % 60;
        const char* sign = negative ? "-" : "";
        if (h == 0 && s == 0) std::snprintf(text, sizeof text, "%s%lld min", sign, m);
        else if (h == 0) std::snprintf(text, sizeof text, "%s%lld min %02lld s", sign, m, s);
        else if (m == 0 && s == 0) std::snprintf(text, sizeof text, "%s%lld h", sign, h);
        else if (s == 0) std::snprintf(text, sizeof text, "%s%lld h %02lld min", sign, h, m);
        else std::snprintf(text, sizeof text, "%s%lld h %02lld min %02lld s", sign, h, m, s);
        return text;
    }
    std::snprintf(text, sizeof text, "%.4g s", seconds);
    return text;
}

void make_contact_sheet(const FrameStore& store, int total, double fps, const std::string& out) {
    int count, columns;
    contact_sheet_grid(total, &count, &columns);
    const int rows = count / columns;
    std::vector<cv::Mat> tiles;
    int tw = 320, th = 0;
    for (int c = 0; c < count; ++c) {
        int k = count == 1 ? 0 : int(std::lround(double(c) * (total - 1) / (count - 1)));
        Image img = read_image(store.frame_png(k));
        cv::Mat m(img.height, img.width, CV_32FC(img.channels), img.pixels.data()), rgb, small;
        if (img.channels == 4) cv::cvtColor(m, rgb, cv::COLOR_RGBA2RGB);
        else if (img.channels == 1) cv::cvtColor(m, rgb, cv::COLOR_GRAY2RGB);
        else rgb = m.clone();
        th = std::max(1, int(std::lround(double(tw) * img.height / img.width)));
        cv::resize(rgb, small, cv::Size(tw, th), 0, 0, cv::INTER_AREA);
        // The frame's time, white on a dark box in the top-left corner.
        const std::string text = "t = " + frame_time_label(k / fps);
        const char* label = text.c_str();
        int baseline = 0;
        const double scale = 0.5;
        cv::Size size = cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline);
        cv::rectangle(small, cv::Rect(0, 0, std::min(tw, size.width + 8), std::min(th, size.height + baseline + 8)),
                      cv::Scalar(0.0, 0.0, 0.0), cv::FILLED);
        cv::putText(small, label, cv::Point(4, 4 + size.height), cv::FONT_HERSHEY_SIMPLEX, scale,
                    cv::Scalar(1.0, 1.0, 1.0), 1, cv::LINE_AA);
        tiles.push_back(small);
    }
    Image sheet;
    sheet.width = columns * tw, sheet.height = rows * th, sheet.channels = 3;
    sheet.pixels.assign(size_t(sheet.width) * sheet.height * 3, 0.0f);
    for (int c = 0; c < count; ++c) {
        const cv::Mat& t = tiles[size_t(c)];
        int x0 = (c % columns) * tw, y0 = (c / columns) * th;
        for (int y = 0; y < th; ++y)
            for (int x = 0; x < tw; ++x) {
                cv::Vec3f p = t.at<cv::Vec3f>(y, x);
                float* q = &sheet.pixels[(size_t(y0 + y) * sheet.width + x0 + x) * 3];
                q[0] = p[0], q[1] = p[1], q[2] = p[2];
            }
    }
    write_image(out, sheet);
}

}  // namespace dynsky
