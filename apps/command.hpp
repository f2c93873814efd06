// Subcommands of the `tomograin` program register themselves: each
// apps/cmd_<name>.cpp defines one static Registrar, so adding a command never
// edits a shared list. A Command is its name, its place in --help and its
// description; main adds the subcommand (CLI::App::add_subcommand(name,
// description)) and hands it to setup(), which adds the options and returns
// the function that runs it (exit code 0 on success; errors are thrown, see
// core/errors.hpp, and mapped to exit codes in main).
//
//   static tg::app::Registrar reg{{"info", 10, "Describe a volume ...",
//       [](CLI::App* sub) -> tg::app::Runner { ...; return [o] { return run(*o); }; }}};
#pragma once
#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

namespace tg::app {

using Runner = std::function<int()>;
struct Command {
  std::string name;
  int order;                // position in --help
  std::string description;  // the subcommand's --help text
  std::function<Runner(CLI::App* sub)> setup;
};

std::vector<Command>& registry();

struct Registrar {
  explicit Registrar(Command c) { registry().push_back(std::move(c)); }
};

// Shared option helpers.
// --voxel-um: overrides (or supplies) the voxel size of an input volume.
void add_voxel_option(CLI::App* sub, double& voxel_um);
// --feret N|exact (measure, compare): `exact`, or N orientations, a whole
// integer (the measurement refuses N < 3); else UsageError.
void parse_feret_option(const std::string& value, bool& exact, int& directions);
// --threads: OpenMP threads of a command whose results do not depend on them.
void add_threads_option(CLI::App* sub, int& threads);

// The default name of a file written beside OUT: OUT's folder, OUT's stem and
// suffix, e.g. beside("run/psd.csv", "_summary.csv") = "run/psd_summary.csv"
// (psd's summary, contacts' fabric, voxelise's truth table).
std::string beside(const std::string& out, const std::string& suffix);

}  // namespace tg::app
