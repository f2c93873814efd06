#include "apps/config_args.hpp"

#include <fmt/core.h>

#include <algorithm>

#include "apps/command.hpp"
#include "core/errors.hpp"

namespace tg::app {

namespace {

std::string value_text(const toml::node& n, const std::string& where, const std::string& key) {
  if (auto v = n.value_exact<std::string>()) return *v;
  if (auto v = n.value_exact<int64_t>()) return std::to_string(*v);
  if (auto v = n.value_exact<double>()) return fmt::format("{}", *v);  // shortest text that reads back exactly
  if (auto v = n.value_exact<bool>()) return *v ? "true" : "false";
  throw InputError(where + ": " + key + " must be a string, a number, true/false or an array of those");
}

// Does `given` set option `o` (any of its names)?
bool given_on_line(const CLI::Option& o, const std::vector<std::string>& given) {
  for (const auto& a : given) {
    for (const auto& l : o.get_lnames())
      if (a == "--" + l || a.rfind("--" + l + "=", 0) == 0) return true;
    for (const auto& s : o.get_snames())
      if (a == "-" + s) return true;
  }
  return false;
}

}  // namespace

std::vector<std::string> options_from_toml(const toml::table& table, const CLI::App& command,
                                           const std::string& where, const std::vector<std::string>& given,
                                           const std::set<std::string>& reserved) {
  std::vector<std::string> out;
  for (const auto& [k, node] : table) {
    std::string key(k.str());
    std::string name = key;
    std::replace(name.begin(), name.end(), '_', '-');
    const CLI::Option* o = command.get_option_no_throw("--" + name);
    if (!o || o->get_lnames().empty() || name == "config" || name == "help")
      throw InputError(where + ": unknown key '" + key + "' (`tomograin " + command.get_name() +
                       " --help` lists the options; a key is an option's long name)");
    if (reserved.count(o->get_lnames().front()))
      throw InputError(where + ": " + key + " is set by the study itself and cannot be given here");
    if (node.is_table()) throw InputError(where + ": " + key + " must be a value, not a table");
    if (given_on_line(*o, given)) continue;
    const std::string flag = "--" + o->get_lnames().front();
    if (o->get_expected_max() == 0) {  // a flag (takes no value): true adds it, false leaves it out
      const auto b = node.value_exact<bool>();
      if (!b) throw InputError(where + ": " + key + " is a switch: true or false");
      if (*b) out.push_back(flag);
      continue;
    }
    out.push_back(flag);
    if (const toml::array* arr = node.as_array()) {
      if (arr->empty()) throw InputError(where + ": " + key + " is an empty array");
      for (const auto& el : *arr) out.push_back(value_text(el, where, key));
    } else {
      out.push_back(value_text(node, where, key));
    }
  }
  return out;
}

std::vector<std::string> expand_config(std::vector<std::string> args, const CLI::App& app) {
  if (args.empty()) return args;
  auto command = [&](const std::string& name) -> const CLI::App* {
    const auto found = app.get_subcommands([&](const CLI::App* s) { return s->get_name() == name; });
    return found.empty() ? nullptr : found.front();
  };
  const CLI::App* sub = command(args[0]);
  if (!sub) return args;
  std::string file;
  for (size_t i = 1; i < args.size(); ++i) {
    if (args[i] == "--config" && i + 1 < args.size()) file = args[i + 1];
    else if (args[i].rfind("--config=", 0) == 0) file = args[i].substr(9);
  }
  if (file.empty()) return args;
  toml::table root;
  try {
    root = toml::parse_file(file);
  } catch (const toml::parse_error& e) {
    const auto& b = e.source().begin;
    if (b.line == 0) throw InputError(file + ": cannot read the config file");
    throw InputError(file + ":" + std::to_string(b.line) + ":" + std::to_string(b.column) + ": " +
                     std::string(e.description()));
  }
  // Top-level keys are this command's options; a table named after this
  // command holds more of them; tables named after other commands are theirs.
  toml::table mine;
  for (const auto& [k, node] : root) {
    const std::string key(k.str());
    if (node.is_table()) {
      if (key == sub->get_name()) {
        for (const auto& [k2, n2] : *node.as_table()) mine.insert_or_assign(k2, n2);
      } else if (!command(key)) {
        throw InputError(file + ": unknown table [" + key + "] (tables are named after commands)");
      }
      continue;
    }
    mine.insert_or_assign(k, node);
  }
  const std::vector<std::string> given(args.begin() + 1, args.end());
  for (auto& a : options_from_toml(mine, *sub, file, given)) args.push_back(std::move(a));
  return args;
}

CommandApp::CommandApp(const std::string& name) {
  for (const auto& c : registry())
    if (c.name == name) {
      sub = app.add_subcommand(c.name, c.description);
      runner = c.setup(sub);
      return;
    }
  throw std::logic_error("no command " + name);
}

int run_command(const std::string& name, const std::vector<std::string>& args, bool dry_run) {
  CommandApp c(name);
  std::vector<std::string> tokens{name};
  tokens.insert(tokens.end(), args.begin(), args.end());
  std::reverse(tokens.begin(), tokens.end());  // CLI11 takes a vector in reverse order
  try {
    c.app.parse(tokens);
  } catch (const CLI::ParseError& e) {
    throw UsageError("tomograin " + name + ": " + e.what());
  }
  return dry_run ? 0 : c.runner();
}

}  // namespace tg::app
