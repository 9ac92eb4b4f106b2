#include "cli/commands.h"

namespace dynsky::cli {

// Filled in by its subsystem; registers nothing yet.
void register_sky_clear_commands(CLI::App&) {}

}  // namespace dynsky::cli
