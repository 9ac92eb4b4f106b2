// What the libFuzzer targets share (scripts/fuzz.sh, docs/testing.md). dynsky's loaders read files,
// as the program does, so each input is written to a file of a private temporary folder first; a
// bad input may only end in dynsky::Error (the clean refusal the program reports), anything else
// (another exception, a crash, a leak, undefined behaviour) is a finding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace dynsky::fuzz {

// One thread for TBB and OpenImageIO: a finding then reproduces from its input alone, and the
// fuzzer's executions per second are not spent on thread start-up.
void init_single_threaded();

// Writes the input to `name` in this process's temporary folder (removed at exit); returns its path.
std::string write_input(const uint8_t* data, size_t size, const std::string& name);

// Width x height x channels from the image header, or -1 when dynsky refuses the file before
// decoding (util/image.h image_file_problem) or OpenImageIO cannot open it. The
// image targets skip images over kMaxFuzzImageValues: they are within dynsky's limits
// (docs/input-limits.md) but decoding hundreds of megabytes per input would only measure memory.
long long header_values(const std::string& path);
constexpr long long kMaxFuzzImageValues = 4LL << 20;

// Runs f: returns normally or after a dynsky::Error; any other exception aborts with its message.
template <typename F>
void expect_clean_refusal(F&& f);

[[noreturn]] void unexpected_exception(const char* what);

}  // namespace dynsky::fuzz

#include "util/error.h"

template <typename F>
void dynsky::fuzz::expect_clean_refusal(F&& f) {
    try {
        f();
    } catch (const dynsky::Error&) {
        // A refusal naming the file: what a bad input should get.
    } catch (const std::exception& e) {
        unexpected_exception(e.what());
    }
}
