// Each subcommand family registers itself on the `dynsky` CLI::App; main.cpp wires them up.
#pragma once

#include <CLI/CLI.hpp>

namespace dynsky::cli {

void register_render_command(CLI::App& app);          // dynsky render
void register_sky_clear_commands(CLI::App& sky);      // dynsky sky clear | latlong | sun
void register_sky_import_commands(CLI::App& sky);     // dynsky sky import | mask
void register_sky_procedural_command(CLI::App& sky);  // dynsky sky procedural
void register_sky_model_commands(CLI::App& sky);      // dynsky sky predict | evaluate | training-data
void register_sky_timeline_command(CLI::App& sky);    // dynsky sky timeline
void register_bench_commands(CLI::App& app);          // dynsky bench ...
void register_animate_command(CLI::App& app);         // dynsky animate
void register_compare_command(CLI::App& app);         // dynsky compare, dynsky temporal

}  // namespace dynsky::cli
