// dynsky: moving HDR skies and the scenes they light. One program, subcommands.
#include <cstdio>
#include <exception>

#include "cli/commands.h"
#include "util/error.h"

int main(int argc, char** argv) {
    CLI::App app{
        "dynsky: time-varying HDR skies (clear, photographed, procedural, with moving clouds) and a\n"
        "CPU path tracer that renders glTF 2.0 scenes under them.\n"
        "Sky images are equidistant fisheye EXRs of the upper hemisphere, north up, east left."};
    app.require_subcommand(1);
    app.set_help_all_flag("--help-all", "Show help for every subcommand");

    dynsky::cli::register_render_command(app);
    CLI::App* sky = app.add_subcommand("sky", "Make, import, convert and inspect sky images");
    sky->require_subcommand(1);
    dynsky::cli::register_sky_clear_commands(*sky);
    dynsky::cli::register_sky_import_commands(*sky);
    dynsky::cli::register_sky_procedural_command(*sky);
    dynsky::cli::register_sky_model_commands(*sky);
    dynsky::cli::register_bench_commands(app);
    dynsky::cli::register_animate_command(app);
    dynsky::cli::register_compare_command(app);

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    } catch (const dynsky::Error& e) {
        std::fprintf(stderr, "dynsky: error: %s\n", e.what());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "dynsky: error: %s\n", e.what());
        return 1;
    }
    return 0;
}
