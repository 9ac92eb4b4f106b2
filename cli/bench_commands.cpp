#include "cli/commands.h"

namespace dynsky::cli {

// Filled in by its subsystem; registers nothing yet.
void register_bench_commands(CLI::App&) {}

}  // namespace dynsky::cli
