#pragma once
// Subcommands of the `hapsim` executable. Each adds itself to the CLI11 app; its callback runs
// the command and throws on failure (main() turns exceptions into a message and exit code).

#include <CLI/CLI.hpp>

namespace hapsim::apps {

void AddFemCommand(CLI::App* app);
void AddSimCommand(CLI::App* app);
void AddRunCommand(CLI::App* app);
void AddHapticCommand(CLI::App* app);
void AddReplayCommand(CLI::App* app);
void AddInspectCommand(CLI::App* app);
void AddViewCommand(CLI::App* app);
void AddTrainCommand(CLI::App* app);
void AddMeshCommand(CLI::App* app);

// Thrown by a command that ends without an error message of its own but with a non-zero exit
// code (e.g. 130 after SIGINT); main() returns the code.
struct RunExit {
  int code;
};

}  // namespace hapsim::apps
