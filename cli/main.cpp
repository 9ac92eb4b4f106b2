// dynsky: moving HDR skies and the scenes they light. One program, subcommands.
#include <cstdio>
#include <exception>
#include <functional>

#include "cli/commands.h"
#include "cli/options.h"
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
    // The same -q,--quiet on every command (those without their own silence stdout).
    std::function<void(CLI::App*)> add_quiet = [&](CLI::App* cmd) {
        auto subs = cmd->get_subcommands({});
        for (CLI::App* sub : subs) add_quiet(sub);
        if (subs.empty() && cmd->get_option_no_throw("--quiet") == nullptr) dynsky::cli::add_quiet_flag(cmd);
    };
    add_quiet(&app);

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
