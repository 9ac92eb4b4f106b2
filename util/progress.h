// A thread-safe progress report for long work (renders, sky sequences, rollouts): a bar redrawn in
// place on a terminal, a line every 10 % in logs (stderr not a terminal), both with the time left.
#pragma once

#include <atomic>
#include <chrono>
#include <mutex>
#include <string>

namespace dynsky {

// One progress line: label, bar, percentage, time elapsed and left (estimated from the rate so
// far; "?" before any progress), at most what a time limit (> 0) leaves. `columns` > 0: the line fits
// in one less than that (a terminal's width; a longer line wrapped and scrolled on every redraw):
// the bar shrinks, then goes, then the line is cut.
std::string format_progress(const std::string& label, double fraction, double elapsed_seconds,
                            double time_limit_seconds = 0, int columns = 0);

// The program-wide -q (cli/main.cpp sets it for every command, with or without a --quiet of its
// own): progress bars and reports on stderr stay silent (warnings and errors are still said).
// Off by default.
void silence_reports(bool silent);
bool reports_silenced();

class ProgressBar {
  public:
    // Prints to stderr; quiet = true (or reports_silenced()) prints nothing (tests, --quiet).
    ProgressBar(long long total, std::string label, bool quiet = false);
    ~ProgressBar();
    void advance(long long n = 1);
    void finish();
    double elapsed_seconds() const;
    // Work that stops at a time limit (render --time-limit): the time left is at most what it leaves.
    void set_time_limit(double seconds) { time_limit_ = seconds; }

  private:
    void draw(long long done, bool final);
    long long total_;
    std::string label_;
    bool quiet_, finished_ = false, tty_;
    double time_limit_ = 0;
    std::atomic<long long> done_{0};
    long long last_drawn_ = -1;
    std::mutex mutex_;
    std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace dynsky
