#include "dem/calibration/calibrate.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <toml++/toml.h>

#include "core/atomic_file.hpp"
#include "core/config.hpp"
#include "core/errors.hpp"
#include "dem/breakage/crush.hpp"
#include "dem/oedometer.hpp"
#include "dem/packing_io.hpp"

extern char** environ;

namespace tg::dem::calibration {
namespace calibrate_detail {
namespace fs = std::filesystem;

// Starts `argv` as a child process with stdout and stderr to `log` and the
// environment's entries `env` (NAME=value) replacing or added to ours.
pid_t spawn_logged(const std::vector<std::string>& argv, const fs::path& log, const std::vector<std::string>& env) {
  std::vector<std::string> envs;
  for (char** e = environ; *e; ++e) {
    const std::string s = *e;
    bool replaced = false;
    for (const auto& x : env) replaced |= s.compare(0, x.find('=') + 1, x, 0, x.find('=') + 1) == 0;
    if (!replaced) envs.push_back(s);
  }
  envs.insert(envs.end(), env.begin(), env.end());
  std::vector<char*> a, en;
  for (const auto& s : argv) a.push_back(const_cast<char*>(s.c_str()));
  a.push_back(nullptr);
  for (const auto& s : envs) en.push_back(const_cast<char*>(s.c_str()));
  en.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, a[0], &fa, nullptr, a.data(), en.data());
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) throw ResourceError(argv[0] + ": cannot start a process (" + std::strerror(rc) + ")");
  return pid;
}

int wait_for(pid_t pid) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

std::string run_name(size_t i) {
  char b[32];
  std::snprintf(b, sizeof b, "run_%03zu", i);
  return b;
}

struct RunRecord {
  std::vector<double> params;
  RunScore score;
  std::string status;
  double seconds = 0;
};

// Scales a unit-box point to the parameters' ranges.
std::vector<double> scale(const std::vector<Parameter>& p, const Point& u) {
  std::vector<double> v;
  for (size_t k = 0; k < p.size(); ++k) v.push_back(p[k].min + u[k] * (p[k].max - p[k].min));
  return v;
}

void write_runs_csv(const fs::path& out, const std::vector<Parameter>& params, const std::vector<RunRecord>& runs) {
  std::vector<std::string> names{"run"};
  for (const auto& p : params) names.push_back(p.name);
  for (const char* n : {"objective", "curve_misfit", "yield_misfit", "broken_misfit", "broken_stress_misfit", "bonds_misfit", "crush_misfit", "yield_stress_Pa",
                        "peak_stress_Pa", "final_strain", "final_broken_fraction", "crush_bonds_broken", "seconds"})
    names.push_back(n);
  names.push_back("status");
  Table t;
  std::vector<std::vector<double>> cols(names.size() - 1);
  std::vector<std::string> status;
  for (size_t i = 0; i < runs.size(); ++i) {
    const RunRecord& r = runs[i];
    std::vector<double> row{static_cast<double>(i)};
    row.insert(row.end(), r.params.begin(), r.params.end());
    for (double v : {r.score.objective, r.score.curve_misfit, r.score.yield_misfit, r.score.broken_misfit,
                     r.score.broken_stress_misfit, r.score.bonds_misfit, r.score.crush_misfit, r.score.yield_stress_Pa, r.score.peak_stress_Pa, r.score.final_strain,
                     r.score.final_broken_fraction, r.score.crush_bonds_broken, r.seconds})
      row.push_back(v);
    for (size_t c = 0; c < row.size(); ++c) cols[c].push_back(row[c]);
    status.push_back(r.status);
  }
  for (size_t c = 0; c + 1 < names.size(); ++c) t.add(names[c], cols[c]);
  t.add_text("status", status);
  write_file_atomic(out / "runs.csv", to_csv(t));
}

fs::path plot_script(const std::string& given) {
  if (!given.empty()) return given;
  const char* e = std::getenv("TOMOGRAIN_CALIBRATION_SCRIPT");
  return e && *e ? fs::path(e) : fs::path(TOMOGRAIN_CALIBRATION_SCRIPT);
}

}  // namespace calibrate_detail

breakage::CrushOptions crush_options(const OedometerSetup& setup, double diameter_m, double travel_fraction,
                                     uint64_t strength_seed) {
  breakage::CrushOptions c;
  c.diameter_m = diameter_m;
  c.final_travel_fraction = travel_fraction;
  c.engine = setup.engine;
  c.breakage = setup.breakage_options;
  if (c.breakage.strength.d0_m == 0) c.breakage.strength.d0_m = diameter_m;
  c.breakage.strength.seed = strength_seed;
  return c;
}

std::vector<CrushMean> crush_bonds_broken(const Target& t, const std::vector<OedometerSetup>& setups, int threads) {
  const int n = t.crush_grains;
  const int64_t tests = static_cast<int64_t>(setups.size()) * n;
  std::vector<double> bonds(static_cast<size_t>(tests), std::numeric_limits<double>::quiet_NaN());
  std::vector<std::string> why(static_cast<size_t>(tests));
#pragma omp parallel for schedule(dynamic) num_threads(std::max(1, threads))
  for (int64_t k = 0; k < tests; ++k) {
    const breakage::CrushOptions c = crush_options(setups[static_cast<size_t>(k / n)], t.crush_diameter_m, t.crush_travel,
                                                   static_cast<uint64_t>(k % n + 1));
    try {
      bonds[static_cast<size_t>(k)] = static_cast<double>(breakage::run_crush(c).final_record.bonds_broken);
    } catch (const std::exception& e) {  // that setup has no objective; say why
      why[static_cast<size_t>(k)] = "strength seed " + std::to_string(k % n + 1) + ": " + e.what();
    }
  }
  std::vector<CrushMean> mean(setups.size());
  for (size_t i = 0; i < setups.size(); ++i) {
    double sum = 0;  // in seed order: the same sum for any thread count
    for (int j = 0; j < n; ++j) {
      const size_t k = i * static_cast<size_t>(n) + static_cast<size_t>(j);
      sum += bonds[k];
      if (!why[k].empty() && mean[i].failed++ == 0) mean[i].first_failure = why[k];
    }
    mean[i].bonds_broken = sum / n;
  }
  return mean;
}

std::string run_config_text(const std::filesystem::path& config, const std::vector<Parameter>& params,
                            const std::vector<double>& values) {
  namespace fs = std::filesystem;
  Config::from_file(config);  // syntax errors as InputError with file:line:column
  toml::table root = toml::parse_file(config.string());
  for (size_t k = 0; k < params.size(); ++k) {
    const std::string& key = params[k].config_key;
    const size_t dot = key.find('.');
    const std::string table = key.substr(0, dot), leaf = key.substr(dot + 1);
    if (!root.contains(table)) root.insert(table, toml::table{});
    toml::table* t = root[table].as_table();
    if (!t) throw InputError(config.string() + ": " + table + " must be a table");
    t->insert_or_assign(leaf, values[k]);
  }
  // The only path key of an oedometer config: relative to the config's folder.
  if (auto* spec = root["specimen"].as_table())
    if (auto p = (*spec)["packing_csv"].value<std::string>(); p && !p->empty() && fs::path(*p).is_relative())
      spec->insert_or_assign("packing_csv", fs::absolute(config.parent_path() / *p).lexically_normal().string());
  std::ostringstream s;
  s << root << "\n";
  return s.str();
}

CalibrationResult run_calibration(const CalibrateOptions& o) {
  using namespace calibrate_detail;
  namespace fs = std::filesystem;
  const auto& so = o.search;
  if (so.initial < 2 || so.evaluations < so.initial || so.batch < 1 || o.jobs < 1 || o.threads_per_run < 0)
    throw UsageError("dem calibrate: need --initial >= 2, --runs >= --initial, --batch >= 1, --jobs >= 1");
  if (!fs::exists(o.config)) throw InputError(o.config.string() + ": config file not found");
  CalibrationResult res;
  res.target = read_target(o.target);
  const Target& t = res.target;
  const std::vector<Parameter>& params = t.parameters;
  // The crush term has a model of its own in the search (surrogate.hpp, SeparateTerm).
  SearchOptions search = so;
  if (t.crush_bonds_broken > 0) search.separate = {t.crush_bonds_broken, t.w_crush};
  // The config as a run sees it (midpoint parameters): every key checked now.
  std::vector<double> mid;
  for (const auto& p : params) mid.push_back(0.5 * (p.min + p.max));
  {
    Config cfg = Config::from_string(run_config_text(o.config, params, mid), o.config.string());
    const OedometerSetup s = read_oedometer_config(cfg, o.config.parent_path());
    if (!s.breakage) throw InputError(o.config.string() + ": breakage.enabled is false; the calibrated parameters are breakage's");
    // The packing too: a bad one would fail every run, after DIR exists.
    if (!s.packing_csv.empty()) read_packing_csv(s.packing_csv, s.engine.material.density_kg_m3);
    // A run's own history.csv as target ends a step past its target strain: allowed.
    if (t.largest_strain() > s.target_strain * 1.001)
      throw InputError(t.source + ": target strains reach " + std::to_string(t.largest_strain()) +
                       ", beyond the config's oedometer.target_strain " + std::to_string(s.target_strain));
  }
  if (fs::exists(o.out) && !fs::is_empty(o.out))
    throw UsageError(o.out.string() + ": exists and is not empty; calibrate writes a new folder");
  if (o.executable.empty() || !fs::exists(o.executable)) throw UsageError("dem calibrate: tomograin program not found");
  fs::create_directories(o.out / "runs");

  std::vector<RunRecord> runs;
  const EvaluateTerms evaluate = [&](const std::vector<Point>& pts) {
    const size_t first = runs.size();
    std::map<pid_t, size_t> running;
    std::vector<std::chrono::steady_clock::time_point> start(pts.size());
    size_t next = 0;
    for (const Point& u : pts) runs.push_back({scale(params, u), {}, "", 0});
    // The crush tests of the round's candidates, before their oedometer runs.
    std::vector<CrushMean> crush(pts.size(), CrushMean{std::numeric_limits<double>::quiet_NaN(), 0, ""});
    if (t.crush_bonds_broken > 0) {
      std::vector<OedometerSetup> setups;
      for (size_t i = 0; i < pts.size(); ++i) {
        Config cfg = Config::from_string(run_config_text(o.config, params, runs[first + i].params), o.config.string());
        setups.push_back(read_oedometer_config(cfg, o.config.parent_path()));
      }
      crush = crush_bonds_broken(t, setups, o.jobs);
    }
    auto launch = [&](size_t i) {
      const std::string name = run_name(first + i);
      const fs::path cfg = o.out / "runs" / (name + ".toml");
      write_file_atomic(cfg, run_config_text(o.config, params, runs[first + i].params));
      start[i] = std::chrono::steady_clock::now();
      running[spawn_logged({o.executable, "dem", "oedometer", cfg.string(), "-o", (o.out / "runs" / name).string()},
                           o.out / "runs" / (name + ".log"),
                           {"OMP_NUM_THREADS=" + std::to_string(std::max(1, o.threads_per_run)), "TOMOGRAIN_QUIET=1"})] = i;
    };
    while (next < pts.size() || !running.empty()) {
      while (next < pts.size() && static_cast<int>(running.size()) < o.jobs) launch(next++);
      int status = 0;
      const pid_t pid = waitpid(-1, &status, 0);
      if (pid < 0) {
        if (errno == EINTR) continue;
        throw ResourceError("dem calibrate: lost track of the runs (waitpid failed)");
      }
      auto it = running.find(pid);
      if (it == running.end()) continue;
      const size_t i = it->second;
      running.erase(it);
      RunRecord& r = runs[first + i];
      r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start[i]).count();
      const std::string name = run_name(first + i);
      const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
      r.score.objective = std::numeric_limits<double>::quiet_NaN();
      if (code != 0) {
        r.status = "failed (exit " + std::to_string(code) + ", see runs/" + name + ".log)";
      } else {
        try {
          const fs::path dir = o.out / "runs" / name;
          const Table h = read_csv(dir / "history.csv", {"strain", "top_stress_Pa"});
          const double grains = static_cast<double>(read_csv(dir / "packing_initial.csv").rows());
          r.score = score_run(t, h, grains, crush[i].bonds_broken);
          r.status = std::isfinite(r.score.objective)           ? "ok"
                     : t.crush_bonds_broken > 0 && !std::isfinite(crush[i].bonds_broken)
                         ? "crush tests failed (" + std::to_string(crush[i].failed) + " of " + std::to_string(t.crush_grains) +
                               "; " + crush[i].first_failure + ")"
                         : "short of the target strain";
        } catch (const InputError& e) {
          r.status = std::string("unreadable (") + e.what() + ")";
        }
      }
      if (!o.quiet) {
        std::printf("%s:", name.c_str());
        for (size_t k = 0; k < params.size(); ++k) std::printf(" %s %.5g", params[k].name.c_str(), r.params[k]);
        std::printf(" -> objective %.5g (%s, %.0f s)\n", r.score.objective, r.status.c_str(), r.seconds);
        std::fflush(stdout);
      }
    }
    write_runs_csv(o.out, params, runs);
    // Nothing ran at all (the first round is the whole initial design): the
    // setup is at fault, not the parameters; stop instead of guessing on.
    bool any = false;
    for (const RunRecord& r : runs) any |= std::isfinite(r.score.objective);
    if (!any)
      throw ResourceError(o.out.string() + ": every run of the initial design failed (" + runs.front().status +
                          "); see runs.csv and runs/*.log");
    std::vector<Evaluation> v;
    for (size_t i = 0; i < pts.size(); ++i) v.push_back({runs[first + i].score.objective, crush[i].bonds_broken});
    return v;
  };
  res.search = minimise(static_cast<int>(params.size()), search, evaluate);
  const SearchResult& r = res.search;
  if (r.best < 0) throw ResourceError(o.out.string() + ": no run finished; see runs.csv and runs/*.log");
  res.best_parameters = runs[r.best].params;
  res.predicted_parameters = scale(params, r.predicted_optimum);

  // best.toml: the config as the best run ran it.
  write_file_atomic(o.out / "best.toml",
                    "# tomograin dem calibrate: " + run_name(r.best) + ", objective " + std::to_string(r.values[r.best]) +
                        ", target " + t.source + "\n" + run_config_text(o.config, params, res.best_parameters));
  // The surrogate's surface on a grid of the first two parameters.
  if (params.size() == 2) {
    Table s;
    std::vector<double> a, b, m, sd;
    for (int i = 0; i <= 40; ++i)
      for (int j = 0; j <= 40; ++j) {
        const Point u{i / 40.0, j / 40.0};
        double mu, sg;
        r.surrogate.predict(u, mu, sg);
        mu = r.surrogate.guess(u);  // what the optimum minimises (the composite's plug-in)
        const auto v = scale(params, u);
        a.push_back(v[0]);
        b.push_back(v[1]);
        m.push_back(mu);
        sd.push_back(sg);
      }
    s.add(params[0].name, a);
    s.add(params[1].name, b);
    s.add("objective_mean", m);
    s.add("objective_sd", sd);
    write_file_atomic(o.out / "surface.csv", to_csv(s));
  }
  nlohmann::json j;
  j["objective"] = {
      {"definition", "J = w_curve*m_curve + w_yield*m_yield + w_broken*m_broken + w_broken_stress*m_broken_stress + "
                     "w_bonds*m_bonds + w_crush*m_crush over the targets given"},
      {"m_curve", "RMS_i(sigma_run(eps_i) - sigma_i) / RMS_i(sigma_i), top platen stress interpolated in history.csv"},
      {"m_yield", "|yield_run - yield_target| / yield_target (bilinear strain-log10 stress fit above 0.1 MPa; 1 if none)"},
      {"m_broken", "RMS_j(grains_broken/grains at eps_j - target fraction)"},
      {"m_broken_stress", "RMS_k(grains_broken/grains at the first row with top stress >= sigma_k - target fraction); "
                          "1 for a stress never reached"},
      {"m_bonds", "RMS_k min(1, |log10((bonds_broken + 1) / (target + 1))|) at the same rows; 1 for a stress never reached"},
      {"m_crush", "|b_run - b_target| / b_target, b = mean bonds broken by stress over single-grain crush tests "
                  "(strength seeds 1..grains) run with the candidate's config"},
      {"weights", {{"stress_strain", t.curve_strain.empty() ? 0.0 : t.w_curve},
                   {"yield_stress", t.yield_stress_Pa > 0 ? t.w_yield : 0.0},
                   {"broken_fraction", t.broken_strain.empty() ? 0.0 : t.w_broken},
                   {"broken_at_stress", t.broken_fraction_at_stress.empty() ? 0.0 : t.w_broken_stress},
                   {"bonds_at_stress", t.bonds_broken_at_stress.empty() ? 0.0 : t.w_bonds},
                   {"crush", t.crush_bonds_broken > 0 ? t.w_crush : 0.0}}}};
  j["target"] = {{"file", t.source}, {"stress_strain_csv", t.curve_file}, {"curve_points", t.curve_strain.size()},
                 {"yield_stress_Pa", t.yield_stress_Pa}, {"broken_strain", t.broken_strain},
                 {"broken_fraction", t.broken_fraction}, {"broken_at_stress_Pa", t.broken_stress_Pa},
                 {"broken_fraction_at_stress", t.broken_fraction_at_stress},
                 {"bonds_broken_at_stress", t.bonds_broken_at_stress}};
  if (t.crush_bonds_broken > 0)
    j["target"]["crush"] = {{"bonds_broken", t.crush_bonds_broken}, {"grains", t.crush_grains},
                            {"diameter_m", t.crush_diameter_m}, {"travel", t.crush_travel}};
  j["config"] = o.config.string();
  for (size_t k = 0; k < params.size(); ++k)
    j["parameters"].push_back({{"name", params[k].name}, {"config_key", params[k].config_key},
                               {"min", params[k].min}, {"max", params[k].max}});
  j["search"] = {{"method", "Latin hypercube (maximin of 64), then Gaussian-process expected improvement; "
                            "Matern 5/2 ARD kernel, hyperparameters by profile marginal likelihood on a grid; "
                            "batches by kriging believer; failed runs count as the worst objective; with a crush target the "
                            "objective less w_crush*m_crush and log b_run get a GP each, combined (composite objective)"},
                 {"runs", so.evaluations}, {"initial", so.initial}, {"batch", so.batch}, {"seed", so.seed},
                 {"jobs", o.jobs}, {"threads_per_run", o.threads_per_run}};
  j["best"] = {{"run", run_name(r.best)}, {"objective", r.values[r.best]}, {"parameters", res.best_parameters}};
  {
    // The objective's GP (the rest, when the crush term has its own model) and log b's.
    const GaussianProcess& g = r.surrogate.rest();
    j["surrogate"] = {{"length_scales_unit_box", g.length_scales()},
                      {"nugget", g.nugget()},
                      {"signal_sd", g.signal_sd()},
                      {"log_likelihood", g.log_likelihood()},
                      {"crush_term_modelled_apart", r.surrogate.composite()},
                      {"predicted_optimum", res.predicted_parameters},
                      {"predicted_objective", r.predicted_value},
                      {"predicted_objective_sd", r.predicted_sd}};
    if (r.surrogate.composite()) {
      const GaussianProcess& q = r.surrogate.log_q();
      j["surrogate"]["log_crush_bonds"] = {{"length_scales_unit_box", q.length_scales()},
                                           {"nugget", q.nugget()},
                                           {"signal_sd", q.signal_sd()},
                                           {"log_likelihood", q.log_likelihood()}};
    }
  }
  write_file_atomic(o.out / "calibration.json", j.dump(2) + "\n");

  const fs::path script = plot_script(o.plot_script);
  if (o.plot && params.size() == 2) {
    if (!fs::exists(script))
      throw ResourceError(script.string() + ": plotting script not found (set TOMOGRAIN_CALIBRATION_SCRIPT); the data are in " +
                          o.out.string());
    const int code = wait_for(spawn_logged({o.python, script.string(), o.out.string()}, o.out / "plot.log", {}));
    if (code != 0)
      throw ResourceError(o.python + " " + script.string() + " failed (exit " + std::to_string(code) + ", see " +
                          (o.out / "plot.log").string() + "); it needs Debian's python3-matplotlib. The data are in " +
                          o.out.string());
  }
  return res;
}

}  // namespace tg::dem::calibration
