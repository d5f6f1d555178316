#pragma once
// Subcommands of the `hapsim` executable. Each adds itself to the CLI11 app; its callback runs
// the command and throws on failure (main() turns exceptions into a message and exit code).

#include <CLI/CLI.hpp>

namespace hapsim::apps {

void AddFemCommand(CLI::App* app);
void AddSimCommand(CLI::App* app);

}  // namespace hapsim::apps
