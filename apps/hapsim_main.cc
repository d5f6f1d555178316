// hapsim: multirate haptic rendering of a rigid tool in contact with deformable tissue.
// main() parses arguments and runs one subcommand; errors become one clear line and an exit code:
// 2 for bad input (file, line and key named), 1 for a failed run.

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "apps/commands.h"
#include "core/error.h"

int main(int argc, char** argv) {
  CLI::App app{
      "hapsim: multirate haptic rendering of a rigid tool in contact with deformable tissue.\n"
      "Scenes are YAML files (see scenes/); outputs are CSV, JSON and legacy VTK."};
  app.set_version_flag("--version", std::string("hapsim ") + HAPSIM_VERSION);
  app.require_subcommand(1);
  hapsim::apps::AddFemCommand(&app);
  hapsim::apps::AddSimCommand(&app);
  hapsim::apps::AddRunCommand(&app);
  hapsim::apps::AddHapticCommand(&app);
  hapsim::apps::AddReplayCommand(&app);
  hapsim::apps::AddInspectCommand(&app);
  hapsim::apps::AddViewCommand(&app);
  hapsim::apps::AddTrainCommand(&app);
  hapsim::apps::AddMeshCommand(&app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return app.exit(error);
  } catch (const hapsim::apps::RunExit& exit) {
    return exit.code;
  } catch (const hapsim::InputError& error) {
    std::fprintf(stderr, "hapsim: error: %s\n", error.what());
    return 2;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "hapsim: error: %s\n", error.what());
    return 1;
  }
  return 0;
}
