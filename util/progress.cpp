#include "util/progress.h"

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>

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

namespace {

// The terminal's width in columns (stderr's, else $COLUMNS); 0 when unknown.
int terminal_columns() {
    winsize ws{};
    if (ioctl(STDERR_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 0) return ws.ws_col;
    if (const char* c = std::getenv("COLUMNS")) return std::max(0, std::atoi(c));
    return 0;
}

}  // namespace

std::string format_progress(const std::string& label, double fraction, double elapsed, double time_limit, int columns) {
    double frac = std::clamp(fraction, 0.0, 1.0);
    char left[32] = "?";
    if (frac > 0) {
        double seconds = elapsed * (1 - frac) / frac;
        if (time_limit > 0) seconds = std::min(seconds, std::max(0.0, time_limit - elapsed));
        std::snprintf(left, sizeof left, "%.1fs", seconds);
    } else if (time_limit > 0) {
        std::snprintf(left, sizeof left, "at most %.1fs", std::max(0.0, time_limit - elapsed));
    }
    char tail[128];
    std::snprintf(tail, sizeof tail, "%5.1f%%  %.1fs elapsed, %s left", 100 * frac, elapsed, left);
    const size_t fit = columns > 0 ? size_t(columns - 1) : std::string::npos;
    int width = 30;  // the bar's, shrunk to fit, dropped below 10
    const size_t without_bar = label.size() + 3 + std::string(tail).size() + 1;  // "L [] T"
    if (without_bar + size_t(width) > fit) width = fit > without_bar ? int(fit - without_bar) : 0;
    std::string line;
    if (width >= 10) {
        const int filled = int(frac * width);
        line = label + " [" + std::string(size_t(filled), '#') + std::string(size_t(width - filled), '.') + "] " + tail;
    } else {
        line = label + " " + tail;
    }
    if (line.size() > fit) line.resize(fit);
    return line;
}

void ProgressBar::draw(long long done, bool final) {
    last_drawn_ = done;
    const double fraction = double(done) / double(total_);
    if (tty_) {
        // Fitted to the terminal and padded to its width less one (a shorter line leaves none of
        // the last one behind; a longer one wraps, and every redraw scrolled a new line).
        const int columns = terminal_columns();
        const std::string line = format_progress(label_, fraction, elapsed_seconds(), time_limit_, columns);
        const int pad = columns > 0 ? std::max(0, columns - 1 - int(line.size())) : 3;
        std::fprintf(stderr, "\r%s%*s%s", line.c_str(), pad, "", final ? "\n" : "");
    } else {
        std::fprintf(stderr, "%s\n", format_progress(label_, fraction, elapsed_seconds(), time_limit_).c_str());
    }
    std::fflush(stderr);
}

}  // namespace dynsky
