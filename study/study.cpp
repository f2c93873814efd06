#include "study/study.hpp"

#include <fmt/core.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "core/errors.hpp"
#include "core/io/hdf5.hpp"
#include "core/io/volume_io.hpp"

namespace tg::study {
namespace fs = std::filesystem;

namespace {

std::string read_text(const fs::path& p, const std::string& what) {
  std::ifstream f(p, std::ios::binary);
  if (!f) throw InputError(what + ": cannot open " + p.string());
  std::ostringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// Reads one table of the study file, refusing keys outside `known`.
struct Section {
  const toml::table* t = nullptr;
  std::string where;  // "FILE: [name]" for messages
  std::string file;
  std::string prefix;  // "study." etc.

  void only(const std::set<std::string>& known) const {
    if (!t) return;
    for (const auto& [k, v] : *t)
      if (!known.count(std::string(k.str())))
        throw InputError(file + ": unknown key '" + prefix + std::string(k.str()) + "'");
  }
  [[noreturn]] void bad(const std::string& key, const std::string& msg) const {
    throw InputError(file + ": " + prefix + key + " " + msg);
  }
  std::string str(const std::string& key, const std::string& def) const {
    if (!t || !t->contains(key)) return def;
    if (auto v = (*t)[key].value_exact<std::string>()) return *v;
    bad(key, "must be a string");
  }
  double num(const std::string& key, double def) const {
    if (!t || !t->contains(key)) return def;
    const auto n = (*t)[key];
    if (auto v = n.value_exact<double>()) {
      if (!std::isfinite(*v)) bad(key, "must be a finite number");
      return *v;
    }
    if (auto v = n.value_exact<int64_t>()) return static_cast<double>(*v);
    bad(key, "must be a number");
  }
  bool boolean(const std::string& key, bool def) const {
    if (!t || !t->contains(key)) return def;
    if (auto v = (*t)[key].value_exact<bool>()) return *v;
    bad(key, "must be true or false");
  }
};

fs::path resolve(const fs::path& base, const std::string& p) {
  const fs::path q(p);
  return (q.is_absolute() ? q : base / q).lexically_normal();
}

bool plain_name(const std::string& n) {
  if (n.empty() || n.size() > 64) return false;
  for (char c : n)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '+')) return false;
  return n[0] != '.';
}

// Shape of a scan without reading its voxels, where the format allows it
// (HDF5); empty otherwise (the stages are then checked by track and compare).
Shape scan_shape(const std::string& scan) {
  if (!is_hdf5(scan)) return {};
  const auto [file, ds] = split_dataset_spec(scan);
  H5Reader r(file);
  return r.shape(ds.empty() ? "/volume" : ds);
}

}  // namespace

Study read_study(const fs::path& file_in) {
  Study s;
  s.file = fs::absolute(file_in).lexically_normal();
  const std::string f = file_in.string();
  s.source = f;
  const std::string text = read_text(s.file, f);
  toml::table root;
  try {
    root = toml::parse(text, f);
  } catch (const toml::parse_error& e) {
    const auto& b = e.source().begin;
    throw InputError(f + ":" + std::to_string(b.line) + ":" + std::to_string(b.column) + ": " +
                     std::string(e.description()));
  }
  const fs::path base = s.file.parent_path();
  const std::set<std::string> top = {"study", "stage", "segment", "measure", "psd", "track", "dem", "compare"};
  for (const auto& [k, v] : root)
    if (!top.count(std::string(k.str()))) throw InputError(f + ": unknown key '" + std::string(k.str()) + "'");
  auto section = [&](const char* name) -> Section {
    const toml::node* n = root.get(name);
    if (n && !n->is_table()) throw InputError(f + ": " + name + " must be a table ([" + name + "])");
    return Section{n ? n->as_table() : nullptr, "", f, std::string(name) + "."};
  };

  const Section st = section("study");
  st.only({"name", "grain_diameter_um", "voxel_um"});
  s.name = st.str("name", s.file.stem().string());
  if (!plain_name(s.name)) st.bad("name", "must be 1-64 letters, digits, '_', '.' or '+' (it names folders), got '" + s.name + "'");
  s.grain_diameter_um = st.num("grain_diameter_um", s.grain_diameter_um);
  if (!(s.grain_diameter_um > 0)) st.bad("grain_diameter_um", "must be positive (micrometres)");
  s.voxel_um = st.num("voxel_um", 0.0);
  if (s.voxel_um < 0) st.bad("voxel_um", "must be positive (micrometres), or absent for the scans' own");

  // [[stage]]: scans in loading order.
  const toml::node* sn = root.get("stage");
  if (!sn) throw InputError(f + ": stage: no [[stage]] given (one per scan, in loading order)");
  const toml::array* arr = sn->as_array();
  if (!arr || !arr->is_array_of_tables()) throw InputError(f + ": stage must be an array of tables ([[stage]])");
  std::set<std::string> names;
  Shape first_shape{};
  for (size_t i = 0; i < arr->size(); ++i) {
    const Section g{arr->get(i)->as_table(), "", f, fmt::format("stage[{}].", i)};
    g.only({"scan", "strain", "name"});
    Stage x;
    x.name = g.str("name", "stage" + std::to_string(i));
    if (!plain_name(x.name)) g.bad("name", "must be 1-64 letters, digits, '_', '.' or '+', got '" + x.name + "'");
    if (!names.insert(x.name).second) g.bad("name", "'" + x.name + "' is used twice");
    const std::string scan = g.str("scan", "");
    if (scan.empty()) g.bad("scan", "is missing (the stage's grey scan)");
    const auto [sfile, sds] = split_dataset_spec(scan);
    x.scan = resolve(base, sfile).string() + (sds.empty() ? "" : ":" + sds);
    if (!fs::exists(resolve(base, sfile))) g.bad("scan", "'" + scan + "': no such file or folder");
    if (!g.t->contains("strain")) g.bad("strain", "is missing (axial strain of the stage, a fraction)");
    x.strain = g.num("strain", 0.0);
    if (!(x.strain >= 0 && x.strain < 1)) g.bad("strain", "must be a fraction in [0, 1)");
    if (!s.stages.empty() && !(x.strain > s.stages.back().strain))
      g.bad("strain", fmt::format("must increase from stage to stage ({} after {})", x.strain, s.stages.back().strain));
    Shape sh;
    try {
      sh = scan_shape(x.scan);
    } catch (const InputError& e) {
      g.bad("scan", std::string("unreadable: ") + e.what());
    }
    if (!sh.empty()) {
      if (first_shape.empty()) first_shape = sh;
      else if (!(sh == first_shape))
        g.bad("scan", "has shape " + sh.str() + " but the first stage has " + first_shape.str() +
                          " (stages of one specimen share a field of view)");
    }
    s.stages.push_back(x);
  }

  // Command sections: their keys are checked against the commands' options
  // when the steps' arguments are built (apps/config_args.hpp), before any runs.
  auto take = [&](const char* name, toml::table& into) {
    const Section x = section(name);
    if (x.t) into = *x.t;
  };
  take("segment", s.segment);
  take("measure", s.measure);
  take("psd", s.psd);
  take("compare", s.compare);
  take("track", s.track);
  s.track_enabled = s.stages.size() >= 2;
  if (auto* e = s.track.get("enabled")) {
    const auto v = e->value_exact<bool>();
    if (!v) throw InputError(f + ": track.enabled must be true or false");
    if (*v && s.stages.size() < 2) throw InputError(f + ": track.enabled needs two or more stages");
    s.track_enabled = *v;
    s.track.erase("enabled");
  }
  // [track] scans = true: the stages' scans go to track --scans (each particle's rotation).
  if (auto* e = s.track.get("scans")) {
    const auto v = e->value_exact<bool>();
    if (!v) throw InputError(f + ": track.scans must be true or false (the stages' own scans are given)");
    s.track_scans = *v;
    s.track.erase("scans");
  }

  const Section dem = section("dem");
  dem.only({"config", "variant"});
  if (dem.t) {
    const std::string cfg = dem.str("config", "");
    if (cfg.empty()) dem.bad("config", "is missing (the DEM oedometer config, see dem/examples/oedometer.toml)");
    s.dem_config = resolve(base, cfg);
    if (!fs::is_regular_file(s.dem_config)) dem.bad("config", "'" + cfg + "': no such file");
    s.dem_text = read_text(s.dem_config, f + ": dem.config");
    std::set<std::string> vnames;
    if (const toml::node* vn = dem.t->get("variant")) {
      const toml::array* va = vn->as_array();
      if (!va || !va->is_array_of_tables()) dem.bad("variant", "must be an array of tables ([[dem.variant]])");
      for (size_t i = 0; i < va->size(); ++i) {
        const Section g{va->get(i)->as_table(), "", f, fmt::format("dem.variant[{}].", i)};
        g.only({"name", "set"});
        DemVariant v;
        v.name = g.str("name", "");
        if (!plain_name(v.name)) g.bad("name", "must be 1-64 letters, digits, '_', '.' or '+', got '" + v.name + "'");
        if (!vnames.insert(v.name).second) g.bad("name", "'" + v.name + "' is used twice");
        if (const toml::node* set = g.t->get("set")) {
          if (!set->is_table()) g.bad("set", "must be a table of DEM config keys, e.g. { \"breakage.weibull_modulus\" = 3.0 }");
          v.overrides = *set->as_table();
        }
        s.variants.push_back(std::move(v));
      }
    }
    if (s.variants.empty()) s.variants.push_back(DemVariant{});
    for (const auto& v : s.variants) {
      try {
        (void)dem_config_text(s, v);
      } catch (const InputError& e) {
        throw InputError(f + ": dem.variant '" + v.name + "': " + e.what());
      }
    }
  }
  if (!s.compare.empty() && s.dem_config.empty())
    throw InputError(f + ": compare needs a DEM ([dem] config = ...)");
  return s;
}

std::string dem_config_text(const Study& s, const DemVariant& v) {
  if (v.overrides.empty()) return s.dem_text;
  toml::table cfg = toml::parse(s.dem_text, s.dem_config.string());
  for (const auto& [k, val] : v.overrides) {
    // "a.b.c" = value: walk (and create) the tables a, a.b, then set c.
    const std::string key(k.str());
    toml::table* t = &cfg;
    size_t p = 0;
    for (size_t q; (q = key.find('.', p)) != std::string::npos; p = q + 1) {
      const std::string part = key.substr(p, q - p);
      if (!t->contains(part)) t->insert(part, toml::table{});
      t = t->get(part)->as_table();
      if (!t) throw InputError("set: '" + key + "': " + part + " is not a table in the DEM config");
    }
    if (val.is_table()) throw InputError("set: '" + key + "' must be a value, not a table");
    t->insert_or_assign(key.substr(p), val);
  }
  std::ostringstream os;
  os << "# " << s.dem_config.string() << " with the study's variant '" << v.name << "' set\n" << cfg << "\n";
  return os.str();
}

// ---------------------------------------------------------------- plan

const Step& Plan::step(const std::string& id) const {
  for (const auto& s : steps)
    if (s.id == id) return s;
  std::string ids;
  for (const auto& s : steps) ids += (ids.empty() ? "" : ", ") + s.id;
  throw InputError("no step '" + id + "' in this study (steps: " + ids + ")");
}

Plan make_plan(const Study& s, const fs::path& dir, int64_t voxels) {
  Plan p;
  p.dir = fs::absolute(dir).lexically_normal();
  // Memory: segmentation holds ~10 bytes per voxel (docs/segmentation.md), the
  // comparison a scan and a voxelised DEM stage at once (~25). Time: ~1 min
  // per 10^7 voxels on one core, generous for a scheduler's limit.
  const double mvox = static_cast<double>(voxels) / 1e6;
  auto mb = [&](double bytes_per_voxel) { return static_cast<int64_t>(500 + bytes_per_voxel * mvox); };
  auto minutes = [&](double per_10mvox) { return static_cast<int>(5 + per_10mvox * mvox / 10); };
  std::vector<std::string> analysed;
  for (size_t i = 0; i < s.stages.size(); ++i) {
    Step a{"analyse-" + s.stages[i].name, StepKind::analyse, static_cast<int>(i), -1, {},
           p.dir / "stages" / s.stages[i].name, {fs::path(s.stages[i].scan)}, 2, mb(12), minutes(2)};
    analysed.push_back(a.id);
    p.steps.push_back(a);
  }
  if (s.track_enabled) {
    std::vector<fs::path> scans;  // inputs of the step when it reads them
    if (s.track_scans)
      for (const auto& st : s.stages) scans.emplace_back(st.scan);
    p.steps.push_back({"track", StepKind::track, -1, -1, analysed, p.dir / "track", scans, 2,
                       mb(s.track_scans ? 14 : 10), minutes(s.track_scans ? 3 : 1)});
  }
  std::vector<std::string> compared = analysed;
  if (s.track_enabled) compared.push_back("track");
  for (size_t v = 0; v < s.variants.size() && !s.dem_config.empty(); ++v) {
    const std::string suffix = s.variants[v].name.empty() ? "" : "-" + s.variants[v].name;
    p.steps.push_back({"dem" + suffix, StepKind::dem, -1, static_cast<int>(v), {}, p.dir / ("dem" + suffix),
                       {s.dem_config}, 1, 2000, 60});
    std::vector<fs::path> scans;
    for (const auto& st : s.stages) scans.emplace_back(st.scan);
    p.steps.push_back({"compare" + suffix, StepKind::compare, -1, static_cast<int>(v), {"dem" + suffix},
                       p.dir / ("report" + suffix), scans, 2, mb(25), minutes(6)});
    compared.push_back("compare" + suffix);
  }
  p.steps.push_back({"summary", StepKind::summary, -1, -1, compared, p.dir / "summary", {}, 1, 500, 5});
  return p;
}

std::string plan_json(const Study& s, const Plan& p) {
  nlohmann::json j;
  j["study"] = s.name;
  j["study_file"] = s.file.string();
  j["dir"] = p.dir.string();
  j["steps"] = nlohmann::json::array();
  for (const auto& st : p.steps) {
    std::vector<std::string> inputs;
    for (const auto& i : st.inputs) inputs.push_back(i.string());
    j["steps"].push_back({{"id", st.id},
                          {"needs", st.needs},
                          {"record", p.record(st).string()},
                          {"outputs", {st.output.string()}},
                          {"inputs", inputs},
                          {"threads", st.threads},
                          {"mem_mb", st.mem_mb},
                          {"runtime_min", st.runtime_min}});
  }
  return j.dump(2) + "\n";
}

}  // namespace tg::study
