// tomograin: one program, one subcommand per job. Exit codes:
//   0 success; 2 bad input or usage (one line naming the file and problem);
//   1 internal error.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <stdexcept>

#include "apps/command.hpp"
#include "apps/config_args.hpp"
#include "core/errors.hpp"

namespace tg::app {
std::vector<Command>& registry() {
  static std::vector<Command> r;
  return r;
}
void add_voxel_option(CLI::App* sub, double& voxel_um) {
  // Own check: CLI::PositiveNumber prints the largest double in full.
  sub->add_option("--voxel-um", voxel_um, "Voxel size in micrometres (overrides the file's own)")
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            try {
              const double x = std::stod(v);
              if (x > 0 && std::isfinite(x)) return {};
            } catch (...) {
            }
            return "must be a positive number of micrometres, got " + v;
          },
          "POSITIVE"));
}
void parse_feret_option(const std::string& value, bool& exact, int& directions) {
  if (value == "exact") {
    exact = true;
    return;
  }
  try {
    size_t used = 0;
    directions = std::stoi(value, &used);
    if (used != value.size()) throw std::invalid_argument(value);
  } catch (const std::exception&) {
    throw tg::UsageError("--feret must be a number of orientations (>= 3) or 'exact', got '" + value + "'");
  }
}
void add_threads_option(CLI::App* sub, int& threads) {
  sub->add_option("--threads", threads, "OpenMP threads (0 = all); results do not depend on it")
      ->check(CLI::NonNegativeNumber)
      ->default_str("0");
}
std::string beside(const std::string& out, const std::string& suffix) {
  const std::filesystem::path p(out);
  return (p.parent_path() / (p.stem().string() + suffix)).string();
}
}  // namespace tg::app

int main(int argc, char** argv) {
  using namespace tg::app;
  CLI::App app{
      "tomograin: XCT scans of crushable granular materials -> grains, sizes, shapes;\n"
      "DEM of the oedometer test with particle breakage; both compared with the same metrics.\n\n"
      "Run `tomograin SUBCOMMAND --help` for each job's options and examples."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "tomograin 0.1.0");
  auto cmds = registry();
  std::sort(cmds.begin(), cmds.end(), [](const Command& a, const Command& b) { return a.order < b.order; });
  std::vector<std::pair<CLI::App*, Runner>> runners;
  std::string config_file;  // read by expand_config before parsing; the option is here for --help
  for (const auto& c : cmds) {
    CLI::App* sub = app.add_subcommand(c.name, c.description);
    runners.emplace_back(sub, c.setup(sub));
    if (sub->get_subcommands([](CLI::App*) { return true; }).empty() && c.name != "run")
      sub->add_option("--config", config_file,
                      "TOML file of options: keys are the long option names (with _ or -), e.g.\n"
                      "threshold = \"local\" or no_merge = true; options on the command line win")
          ->check(CLI::ExistingFile);
  }
  app.name(argv[0]);  // as parse(argc, argv) would: --help shows the program as it was called
  std::vector<std::string> args(argv + 1, argv + argc);
  try {
    args = expand_config(std::move(args), app);
  } catch (const tg::InputError& e) {
    std::fprintf(stderr, "tomograin: %s\n", e.what());
    return 2;
  }
  std::reverse(args.begin(), args.end());  // CLI11 takes a vector in reverse order
  try {
    app.parse(args);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "tomograin: %s (see --help)\n", e.what());
    return 2;
  }
  try {
    for (auto& [sub, run] : runners)
      if (sub && sub->parsed()) return run();
    return 2;
  } catch (const tg::InputError& e) {
    std::fprintf(stderr, "tomograin: %s\n", e.what());
    return 2;
  } catch (const tg::UsageError& e) {
    std::fprintf(stderr, "tomograin: %s\n", e.what());
    return 2;
  } catch (const tg::ResourceError& e) {
    std::fprintf(stderr, "tomograin: %s\n", e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "tomograin: out of memory\n");
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tomograin: internal error: %s\n", e.what());
    return 1;
  }
}
