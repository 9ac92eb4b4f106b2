// What `dynsky` exits with (docs/exit-codes.md), and the usage errors' "did you mean".
#pragma once

#include <CLI/CLI.hpp>

#include <string>

#include "util/error.h"

namespace dynsky::cli {

constexpr int kSuccess = 0;       // done (also --help)
constexpr int kRuntimeError = 1;  // an input is missing, unreadable or bad; an output could not be written
constexpr int kUsageError = 2;    // the command line is wrong: unknown command or option, bad option value
constexpr int kInterrupted = 3;   // SIGINT, SIGTERM or SIGHUP: stopped, the output being written removed

// The --help epilog.
std::string exit_codes_help();

// kUsageError for errors about an option (their message starts with the option's name, "--spp ...";
// util/error.h), kRuntimeError for the rest.
int exit_code_of(const Error& e);

// CLI11's wording of a bad value or a repeated option in dynsky's ("--steps: '1e308' is not a value
// of this option ..."); other messages unchanged.
std::string plain_parse_message(const std::string& message);

// -h, --help or --help-all anywhere on the line: prints the help of the command named before it and
// returns true, even where an option before it lacks its value ("render --sky --help", where
// CLI11 would take "--help" for the sky file).
bool print_help_if_asked(CLI::App& app, int argc, char** argv);

// An option that takes a value given an option instead ("--sky --spp 2": values may start with '-',
// so that --lon -105 works, and --sky took "--spp"): "--sky: its value is missing ...", else "".
std::string missing_option_value(CLI::App& app, int argc, char** argv);

// Prints a CLI11 parse error with a "did you mean" for a misspelt command or option, and returns
// kUsageError (kSuccess for --help).
int report_parse_error(CLI::App& app, const CLI::ParseError& e, int argc, char** argv);

}  // namespace dynsky::cli
