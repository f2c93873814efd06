#include "core/config.hpp"

#include <cmath>
#include <fstream>
#include <sstream>
#include <toml++/toml.h>

#include "core/errors.hpp"

namespace tg {

struct Config::Impl {
  toml::table root;
};

Config::Config() : impl_(std::make_unique<Impl>()) {}
Config::~Config() = default;
Config::Config(Config&&) noexcept = default;
Config& Config::operator=(Config&&) noexcept = default;

Config Config::from_string(const std::string& text, const std::string& source) {
  Config c;
  c.source_ = source;
  try {
    c.impl_->root = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    const auto& b = e.source().begin;
    throw InputError(source + ":" + std::to_string(b.line) + ":" + std::to_string(b.column) + ": " +
                     std::string(e.description()));
  }
  return c;
}

Config Config::from_file(const std::filesystem::path& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw InputError(path.string() + ": cannot open config file");
  std::ostringstream ss;
  ss << f.rdbuf();
  return from_string(ss.str(), path.string());
}

bool Config::has(const std::string& key) const {
  return static_cast<bool>(impl_->root.at_path(key));
}

void Config::require(bool ok, const std::string& key, const std::string& message) const {
  if (!ok) throw InputError(source_ + ": " + key + " " + message);
}

double Config::get(const std::string& key, double def) {
  read_.insert(key);
  auto node = impl_->root.at_path(key);
  if (!node) return def;
  if (auto v = node.value_exact<double>()) {
    require(std::isfinite(*v), key, "must be a finite number");
    return *v;
  }
  if (auto v = node.value_exact<int64_t>()) return static_cast<double>(*v);
  throw InputError(source_ + ": " + key + " must be a number");
}

int64_t Config::get(const std::string& key, int64_t def) {
  read_.insert(key);
  auto node = impl_->root.at_path(key);
  if (!node) return def;
  if (auto v = node.value_exact<int64_t>()) return *v;
  throw InputError(source_ + ": " + key + " must be an integer");
}

bool Config::get(const std::string& key, bool def) {
  read_.insert(key);
  auto node = impl_->root.at_path(key);
  if (!node) return def;
  if (auto v = node.value_exact<bool>()) return *v;
  throw InputError(source_ + ": " + key + " must be true or false");
}

std::string Config::get(const std::string& key, const std::string& def) {
  read_.insert(key);
  auto node = impl_->root.at_path(key);
  if (!node) return def;
  if (auto v = node.value_exact<std::string>()) return *v;
  throw InputError(source_ + ": " + key + " must be a string");
}

std::vector<double> Config::get(const std::string& key, const std::vector<double>& def) {
  read_.insert(key);
  auto node = impl_->root.at_path(key);
  if (!node) return def;
  const auto* arr = node.as_array();
  if (!arr) throw InputError(source_ + ": " + key + " must be an array of numbers");
  std::vector<double> out;
  for (const auto& el : *arr) {
    if (auto d = el.value_exact<double>()) out.push_back(*d);
    else if (auto i = el.value_exact<int64_t>()) out.push_back(static_cast<double>(*i));
    else throw InputError(source_ + ": " + key + " must be an array of numbers");
  }
  return out;
}

void Config::finish() const {
  // Walk every leaf; a leaf (or array) whose dotted path was never read is unknown.
  std::string unknown;
  auto walk = [&](auto&& self, const toml::table& t, const std::string& prefix) -> void {
    for (const auto& [k, node] : t) {
      const std::string path = prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str());
      if (const auto* sub = node.as_table()) {
        self(self, *sub, path);
      } else if (!read_.count(path) && unknown.empty()) {
        unknown = path;
      }
    }
  };
  walk(walk, impl_->root, "");
  if (!unknown.empty()) throw InputError(source_ + ": unknown key '" + unknown + "'");
}

}  // namespace tg
