// A thread-safe terminal progress bar for long work (renders, sky sequences, rollouts).
#pragma once

#include <atomic>
#include <chrono>
#include <mutex>
#include <string>

namespace dynsky {

class ProgressBar {
  public:
    // Prints to stderr; quiet = true prints nothing (tests, --quiet).
    ProgressBar(long long total, std::string label, bool quiet = false);
    ~ProgressBar();
    void advance(long long n = 1);
    void finish();
    double elapsed_seconds() const;

  private:
    void draw(long long done, bool final);
    long long total_;
    std::string label_;
    bool quiet_, finished_ = false, tty_;
    std::atomic<long long> done_{0};
    long long last_drawn_ = -1;
    std::mutex mutex_;
    std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace dynsky
