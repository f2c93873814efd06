// Options from TOML: `tomograin CMD --config FILE` and the command sections
// of a study file ([segment], [measure], ...) use the commands' own option
// names as keys (the long name, with '_' or '-'), so there is one list of
// options, one set of checks and one --help for both. The keys become
// arguments appended to the command line and parsed by the command's own
// CLI11 definition:
//   threshold = "local"          -> --threshold local
//   no_merge = true              -> --no-merge          (false: the flag is left out)
//   fov_centre_vox = [120, 130]  -> --fov-centre-vox 120 130
// A key that is not an option of the command is an error naming the file and
// the key; an option already on the command line wins over the file.
#pragma once
#include <CLI/CLI.hpp>
#include <set>
#include <string>
#include <toml++/toml.h>
#include <vector>

namespace tg::app {

// The arguments for `table`'s keys. `where` names the source in errors
// ("study.toml: [segment]"); keys naming an option in `given` are skipped;
// keys in `reserved` (long names) are errors ("set by ...": the caller owns them).
std::vector<std::string> options_from_toml(const toml::table& table, const CLI::App& command,
                                           const std::string& where, const std::vector<std::string>& given,
                                           const std::set<std::string>& reserved = {});

// Handles `--config FILE` of a command line (args after the program name):
// appends the file's options for the subcommand named by args[0] (its
// top-level keys, or its table [CMD]; tables of other commands are ignored, so
// one file can serve several). No --config: args unchanged.
std::vector<std::string> expand_config(std::vector<std::string> args, const CLI::App& app);

// Runs a registered command in this process, as `tomograin NAME ARGS...`
// would, e.g. run_command("segment", {"scan.h5", "-o", "labels.h5"}).
// Usage errors become UsageError. With dry_run it only parses (checks the
// arguments) and returns 0.
int run_command(const std::string& name, const std::vector<std::string>& args, bool dry_run = false);

// A fresh CLI::App holding only the command NAME (for its option list).
struct CommandApp {
  CLI::App app;
  CLI::App* sub = nullptr;
  std::function<int()> runner;
  explicit CommandApp(const std::string& name);
};

}  // namespace tg::app
