// TOML configuration with strict keys: every key a program reads is declared
// with its default at the point of use; finish() then rejects any key in the
// file that nobody read ("unknown key 'dem.stifness'"), so a typo is an
// error, never a silently ignored setting. Errors name the file and key.
//
//   Config cfg = Config::from_file("run.toml");
//   double G = cfg.get("material.shear_modulus_Pa", 2.2e9);
//   cfg.require(G > 0, "material.shear_modulus_Pa", "must be positive");
//   cfg.finish();
#pragma once
#include <filesystem>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace tg {

class Config {
 public:
  Config();  // empty: every get() returns its default
  ~Config();
  Config(Config&&) noexcept;
  Config& operator=(Config&&) noexcept;
  static Config from_file(const std::filesystem::path& path);
  static Config from_string(const std::string& toml, const std::string& source);

  // Dotted key ("dem.time_step_s"). Wrong type -> InputError naming the key.
  double get(const std::string& key, double def);
  int64_t get(const std::string& key, int64_t def);
  int get(const std::string& key, int def) { return static_cast<int>(get(key, static_cast<int64_t>(def))); }
  bool get(const std::string& key, bool def);
  std::string get(const std::string& key, const std::string& def);
  std::string get(const std::string& key, const char* def) { return get(key, std::string(def)); }
  std::vector<double> get(const std::string& key, const std::vector<double>& def);
  bool has(const std::string& key) const;

  // Throws InputError("<file>: <key> <message>") unless ok.
  void require(bool ok, const std::string& key, const std::string& message) const;

  // A key that names one of a fixed set of choices: `names` pairs each word
  // with its value, the first pair is the default. Any other word is an
  // InputError listing them. The same table gives the word back for a
  // record of the run (Config::name_of), so each choice is spelled once.
  template <class E>
  using Choices = std::vector<std::pair<std::string, E>>;
  template <class E>
  E choice(const std::string& key, const Choices<E>& names) {
    const std::string word = get(key, names.front().first);
    std::string all;
    for (const auto& [name, value] : names) {
      if (name == word) return value;
      all += (all.empty() ? "\"" : ", \"") + name + "\"";
    }
    require(false, key, "must be one of " + all + " (got \"" + word + "\")");
    return names.front().second;
  }
  template <class E>
  static const std::string& name_of(const Choices<E>& names, E value) {
    for (const auto& n : names)
      if (n.second == value) return n.first;
    return names.front().first;
  }
  // Throws InputError for the first key present in the file but never read.
  void finish() const;
  const std::string& source() const { return source_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string source_ = "config";
  std::set<std::string> read_;
};

}  // namespace tg
