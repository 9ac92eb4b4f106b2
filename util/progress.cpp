#include "util/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace dynsky {

namespace {
std::atomic<bool> g_reports_silenced{false};
}

void silence_reports(bool silent) { g_reports_silenced = silent; }
bool reports_silenced() { return g_reports_silenced; }

ProgressBar::ProgressBar(long long total, std::string label, bool quiet)
    : total_(total > 0 ? total : 1),
      label_(std::move(label)),
      quiet_(quiet || reports_silenced()),
      tty_(isatty(STDERR_FILENO)) {
    start_ = last_draw_ = std::chrono::steady_clock::now();
    if (!quiet_) draw(0, false);
}

ProgressBar::~ProgressBar() { finish(); }

double ProgressBar::elapsed_seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void ProgressBar::advance(long long n) {
    long long done = done_.fetch_add(n) + n;
    if (quiet_) return;
    auto now = std::chrono::steady_clock::now();
    // Redraw at most 10 times a second on a terminal, every 10% otherwise (logs stay short).
    std::lock_guard<std::mutex> lock(mutex_);
    if (tty_) {
        if (now - last_draw_ < std::chrono::milliseconds(100)) return;
    } else {
        long long step = std::max(1LL, total_ / 10);
        if ((done - n) / step == done / step) return;
    }
    last_draw_ = now;
    draw(done, false);
}

void ProgressBar::finish() {
    if (finished_) return;
    finished_ = true;
    if (quiet_) return;
    std::lock_guard<std::mutex> lock(mutex_);
    if (!tty_ && last_drawn_ == done_.load()) return;  // a log already has this line
    draw(done_.load(), true);
}

std::string format_progress(const std::string& label, double fraction, double elapsed, double time_limit) {
    double frac = std::clamp(fraction, 0.0, 1.0);
    const int width = 30;
    int filled = int(frac * width);
    std::string bar(size_t(filled), '#');
    bar += std::string(size_t(width - filled), '.');
    char left[32] = "?";
    if (frac > 0) {
        double seconds = elapsed * (1 - frac) / frac;
        if (time_limit > 0) seconds = std::min(seconds, std::max(0.0, time_limit - elapsed));
        std::snprintf(left, sizeof left, "%.1fs", seconds);
    } else if (time_limit > 0) {
        std::snprintf(left, sizeof left, "at most %.1fs", std::max(0.0, time_limit - elapsed));
    }
    char line[256];
    std::snprintf(line, sizeof line, "%s [%s] %5.1f%%  %.1fs elapsed, %s left", label.c_str(), bar.c_str(), 100 * frac,
                  elapsed, left);
    return line;
}

void ProgressBar::draw(long long done, bool final) {
    last_drawn_ = done;
    std::string line = format_progress(label_, double(done) / double(total_), elapsed_seconds(), time_limit_);
    if (tty_) std::fprintf(stderr, "\r%s%s", line.c_str(), final ? "\n" : "   ");
    else std::fprintf(stderr, "%s\n", line.c_str());
    std::fflush(stderr);
}

}  // namespace dynsky
