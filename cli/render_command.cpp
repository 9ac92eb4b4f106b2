#include "cli/commands.h"

namespace dynsky::cli {

void register_render_command(CLI::App& app) {
    app.add_subcommand("render", "Render a glTF 2.0 scene under a fisheye sky");
}

}  // namespace dynsky::cli
