// Subcommands of the `tomograin` program register themselves: each
// apps/cmd_<name>.cpp defines one static Registrar, so adding a command never
// edits a shared list. setup() adds the subcommand and its options to the
// CLI11 app and returns the function that runs it (exit code 0 on success;
// errors are thrown, see core/errors.hpp, and mapped to exit codes in main).
#pragma once
#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

namespace tg::app {

using Runner = std::function<int()>;
struct Command {
  std::string name;
  int order;  // position in --help
  std::function<Runner(CLI::App& parent, CLI::App*& sub)> setup;
};

std::vector<Command>& registry();

struct Registrar {
  explicit Registrar(Command c) { registry().push_back(std::move(c)); }
};

// Shared option helpers.
// --voxel-um: overrides (or supplies) the voxel size of an input volume.
void add_voxel_option(CLI::App* sub, double& voxel_um);

}  // namespace tg::app
