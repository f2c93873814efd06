// tomograin run STUDY.toml -o DIR: the whole chain of a study on this machine
// (analyse every stage, track, DEM, compare, summary), each step through the
// same command a user would type, skipping steps that are up to date.
// study/study.hpp reads the file and plans the steps; study/records.hpp says
// when a step is done. workflow/Snakefile runs the same steps one job each
// (`--plan` tells it the steps, `--only STEP` runs one).
#include <fmt/core.h>
#include <omp.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>

#include "apps/command.hpp"
#include "apps/config_args.hpp"
#include "core/atomic_file.hpp"
#include "core/config.hpp"
#include "core/errors.hpp"
#include "core/io/hdf5.hpp"
#include "core/io/volume_io.hpp"
#include "dem/oedometer.hpp"
#include "study/records.hpp"
#include "study/study.hpp"
#include "study/summary.hpp"

namespace cmd_run {
namespace fs = std::filesystem;
using namespace tg::study;

constexpr const char* kVersion = "tomograin 0.1.0";  // part of every step's key

struct Opts {
  std::string study, out, only;
  bool plan = false;
  int threads = 0;
};

// A step as commands: (command, arguments) in order; the DEM step runs the
// engine directly (its config text is the variant's, with the study's folder
// for relative paths) and has none.
struct Prepared {
  std::vector<std::pair<std::string, std::vector<std::string>>> commands;
  std::string dem_text;
  tg::dem::OedometerSetup dem_setup;
  std::vector<fs::path> inputs;  // files the step reads beyond the plan's (the DEM's packing)
};

std::vector<std::string> with(std::vector<std::string> fixed, const std::vector<std::string>& more) {
  fixed.insert(fixed.end(), more.begin(), more.end());
  return fixed;
}

std::string num(double x) { return fmt::format("{}", x); }

// The arguments of a command: the study's fixed ones, then the section's options.
std::vector<std::string> command_args(const Study& s, const std::string& cmd, const toml::table& section,
                                      std::vector<std::string> fixed, const std::set<std::string>& reserved) {
  tg::app::CommandApp c(cmd);
  const auto extra = tg::app::options_from_toml(section, *c.sub, s.source + ": [" + cmd + "]", fixed, reserved);
  return with(std::move(fixed), extra);
}

Prepared prepare(const Study& s, const Plan& p, const Step& st) {
  Prepared r;
  switch (st.kind) {
    case StepKind::analyse: {
      const Stage& g = s.stages[static_cast<size_t>(st.stage)];
      const std::string labels = (st.output / "labels.h5").string(), parts = (st.output / "particles.csv").string();
      std::vector<std::string> seg{g.scan, "-o", labels, "--grain-diameter-um", num(s.grain_diameter_um)};
      if (s.voxel_um > 0) seg.insert(seg.end(), {"--voxel-um", num(s.voxel_um)});
      r.commands.emplace_back("segment", command_args(s, "segment", s.segment, seg,
                                                      {"input", "output", "summary", "voxel-um", "grain-diameter-um"}));
      r.commands.emplace_back("measure", command_args(s, "measure", s.measure, {labels, "-o", parts},
                                                      {"labels", "output", "voxel-um"}));
      r.commands.emplace_back("psd", command_args(s, "psd", s.psd, {parts, "-o", (st.output / "psd.csv").string()},
                                                  {"tables", "output", "summary"}));
      break;
    }
    case StepKind::track: {
      std::vector<std::string> a;
      for (const auto& g : s.stages) a.push_back((p.dir / "stages" / g.name / "labels.h5").string());
      a.insert(a.end(), {"-o", st.output.string()});
      if (s.track_scans) {
        a.push_back("--scans");
        for (const auto& g : s.stages) a.push_back(g.scan);
      }
      r.commands.emplace_back("track", command_args(s, "track", s.track, a, {"labels", "output", "scans"}));
      break;
    }
    case StepKind::dem: {
      const DemVariant& v = s.variants[static_cast<size_t>(st.variant)];
      r.dem_text = dem_config_text(s, v);
      const std::string where = s.dem_config.string() + (v.name.empty() ? "" : " (variant '" + v.name + "')");
      tg::Config cfg = tg::Config::from_string(r.dem_text, where);
      r.dem_setup = tg::dem::read_oedometer_config(cfg, s.dem_config.parent_path());
      if (!r.dem_setup.packing_csv.empty()) r.inputs.emplace_back(r.dem_setup.packing_csv);  // its content matters too
      break;
    }
    case StepKind::compare: {
      const DemVariant& v = s.variants[static_cast<size_t>(st.variant)];
      const std::string suffix = v.name.empty() ? "" : "-" + v.name;
      std::vector<std::string> a{"--xct"};
      for (const auto& g : s.stages) a.push_back(g.scan);
      a.push_back("--xct-strains");
      for (const auto& g : s.stages) a.push_back(num(g.strain));
      a.push_back("--names");
      for (const auto& g : s.stages) a.push_back(g.name);
      a.insert(a.end(), {"--dem", (p.dir / ("dem" + suffix)).string(), "-o", st.output.string()});
      if (s.voxel_um > 0 && !s.compare.contains("voxel_um") && !s.compare.contains("voxel-um"))
        a.insert(a.end(), {"--voxel-um", num(s.voxel_um)});
      if (!s.compare.contains("title"))
        a.insert(a.end(), {"--title", s.name + ": experiment vs DEM" + (v.name.empty() ? "" : " (" + v.name + ")")});
      r.commands.emplace_back("compare", command_args(s, "compare", s.compare, a,
                                                      {"xct", "xct-strains", "names", "dem", "dem-snapshots",
                                                       "dem-strains", "output"}));
      break;
    }
    case StepKind::summary:
      break;
  }
  for (const auto& [cmd, args] : r.commands) tg::app::run_command(cmd, args, /*dry_run=*/true);
  return r;
}

// Everything a step's outputs depend on.
std::string step_key(const Step& st, const Prepared& pr, HashCache& hashes, const std::map<std::string, std::string>& keys) {
  std::vector<std::string> parts{kVersion, st.id};
  for (const auto& [cmd, args] : pr.commands) {
    parts.push_back(cmd);
    parts.insert(parts.end(), args.begin(), args.end());
  }
  parts.push_back(pr.dem_text);
  for (const auto& in : st.inputs) parts.push_back(hashes.hash(in));
  for (const auto& n : st.needs) parts.push_back(n + "=" + keys.at(n));
  return hash_strings(parts);
}

std::string read_small(const fs::path& p) {
  std::ifstream f(p);
  std::string s;
  std::getline(f, s);
  return s;
}

void run_dem(const Step& st, const Prepared& pr, const Plan& p, const std::string& key) {
  // A killed run resumes from its checkpoint (bit for bit, tests/apps/crash_restart_test.py)
  // when it was started for the same key; anything else starts afresh.
  const fs::path pending = p.dir / ".run" / (st.id + ".pending");
  const bool resume = fs::exists(st.output / "checkpoint.bin") && read_small(pending) == key;
  if (!resume) {
    fs::remove_all(st.output);
    tg::write_file_atomic(pending, key + "\n");
    fs::create_directories(st.output);
    tg::write_file_atomic(st.output / "config.toml", pr.dem_text);
  }
  tg::dem::RunControl c;
  c.restart = resume;
  fmt::print("  dem oedometer{}: {}\n", resume ? " (resumed from its checkpoint)" : "", st.output.string());
  const auto r = tg::dem::run_oedometer(pr.dem_setup, st.output, c);
  fmt::print("  {} spheres, strain {:.2f} %, top stress {:.4g} MPa, {} grains broken\n",
             static_cast<long long>(r.spheres), 100 * r.strain, r.top_stress_Pa / 1e6,
             static_cast<long long>(r.breakage.grains_broken));
  fs::remove(pending);
}

int64_t scan_voxels(const Study& s) {
  const std::string& scan = s.stages.front().scan;
  if (!tg::is_hdf5(scan)) return 0;
  const auto [file, ds] = tg::split_dataset_spec(scan);
  return tg::H5Reader(file).shape(ds.empty() ? "/volume" : ds).voxels();
}

int run_study(const Opts& o) {
  const Study s = read_study(o.study);
  Plan p = make_plan(s, o.out, scan_voxels(s));
  if (!o.only.empty()) (void)p.step(o.only);  // an unknown id fails before anything runs

  // Every step's commands first: a bad option anywhere stops the run before
  // any step starts, and before DIR is created (and --plan with it).
  std::map<std::string, Prepared> prepared;
  for (Step& st : p.steps) {
    prepared[st.id] = prepare(s, p, st);
    st.inputs.insert(st.inputs.end(), prepared[st.id].inputs.begin(), prepared[st.id].inputs.end());
  }
  if (o.plan) {
    fmt::print("{}", plan_json(s, p));
    return 0;
  }
  if (o.threads > 0) omp_set_num_threads(o.threads);
  HashCache hashes(p.dir / ".run");
  std::map<std::string, std::string> keys;
  for (const Step& st : p.steps) keys[st.id] = step_key(st, prepared[st.id], hashes, keys);
  fs::create_directories(p.dir / ".run");
  hashes.save();

  const auto t0 = std::chrono::steady_clock::now();
  int ran = 0, k = 0;
  for (const Step& st : p.steps) {
    ++k;
    if (!o.only.empty() && st.id != o.only) continue;
    const fs::path record = p.record(st);
    if (recorded_key(record) == keys[st.id] && fs::exists(st.output)) {
      fmt::print("[{}/{}] {}: up to date\n", k, p.steps.size(), st.id);
      if (!o.only.empty()) fs::last_write_time(record, fs::file_time_type::clock::now());  // for make-like schedulers
      continue;
    }
    for (const auto& n : st.needs)
      if (recorded_key(p.record(p.step(n))) != keys[n])
        throw tg::InputError(p.dir.string() + ": step " + st.id + " needs " + n + ", which has not run (or is out of date)");
    tg::study::StepLock lock(p.dir / ".run" / (st.id + ".lock"));
    fmt::print("[{}/{}] {}: running\n", k, p.steps.size(), st.id);
    std::fflush(stdout);
    const auto ts = std::chrono::steady_clock::now();
    fs::remove(record);
    const Prepared& pr = prepared[st.id];
    if (st.kind == StepKind::dem) {
      run_dem(st, pr, p, keys[st.id]);
    } else {
      fs::remove_all(st.output);
      fs::create_directories(st.output);
      for (const auto& [cmd, args] : pr.commands) tg::app::run_command(cmd, args);
      if (st.kind == StepKind::summary) write_summary(s, p, st.output / "summary.csv");
    }
    const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - ts).count();
    write_record(record, st.id, keys[st.id], sec);
    fmt::print("[{}/{}] {}: done in {:.1f} s\n", k, p.steps.size(), st.id, sec);
    ++ran;
  }
  const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  fmt::print("study {}: {} step(s) run, {} up to date, {:.1f} s; results in {}\n", s.name, ran,
             (o.only.empty() ? p.steps.size() : 1) - static_cast<size_t>(ran), sec, p.dir.string());
  if (o.only.empty() || o.only == "summary")
    if (fs::exists(p.dir / "summary" / "summary.csv")) fmt::print("summary: {}\n", (p.dir / "summary" / "summary.csv").string());
  return 0;
}

}  // namespace cmd_run

namespace cmd_run {
static tg::app::Registrar reg{{"run", 90,
      "Run a whole study on this machine: analyse every stage (segment, measure, psd), track the grains\n"
      "through the stages, run the DEM twin (one run, or one per [[dem.variant]] of a sweep), compare,\n"
      "and write the key figures to DIR/summary/summary.csv. Every step calls the same command a user\n"
      "would, with the study file's sections as its options ([segment] threshold = \"local\" is\n"
      "`segment --threshold local`). docs/studies.md lists every key; examples/study.toml is an example.\n\n"
      "A step runs only when its outputs are missing or out of date: its key (in DIR/.run/STEP.json) hashes\n"
      "the content of its inputs, its options and the keys of the steps it reads. Killed at any moment,\n"
      "`run` again picks up where it stopped (a DEM run from its checkpoint); a half-written output is never\n"
      "taken for a finished one. Bad study files (unknown key, missing scan, stages of different shapes,\n"
      "strains not increasing, an option a command does not have) stop the run before any step starts.\n\n"
      "Outputs: DIR/stages/NAME/ (labels.h5, particles.csv, psd.csv, psd_summary.csv), DIR/track/,\n"
      "DIR/dem[-VARIANT]/ (the DEM run folder), DIR/report[-VARIANT]/ (index.html), DIR/summary/summary.csv.\n\n"
      "Examples:\n"
      "  tomograin run study.toml -o results/specimen_a\n"
      "  tomograin run study.toml -o results/specimen_a --plan          # the steps as JSON (for schedulers)\n"
      "  tomograin run study.toml -o results/specimen_a --only track    # one step (as workflow/Snakefile does)",
      [](CLI::App* sub) -> tg::app::Runner {
  auto o = std::make_shared<Opts>();
  sub->add_option("study", o->study, "Study file (TOML)")->required()->check(CLI::ExistingFile);
  sub->add_option("-o,--output", o->out, "Output folder of the study (created)")->required();
  sub->add_flag("--plan", o->plan, "Print the steps (id, needs, record, outputs, threads, mem_mb, runtime_min) as JSON");
  sub->add_option("--only", o->only, "Run only this step (the steps it needs must be done)");
  tg::app::add_threads_option(sub, o->threads);
  return [o] { return run_study(*o); };
}}};
}  // namespace cmd_run
