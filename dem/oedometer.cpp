#include "dem/oedometer.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <optional>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>

#include "core/atomic_file.hpp"
#include "core/errors.hpp"
#include "core/progress.hpp"
#include "core/table.hpp"
#include "dem/checkpoint.hpp"
#include "dem/neighbor_grid.hpp"
#include "dem/packing_io.hpp"
#include "dem/run_folder.hpp"
#include "dem/snapshot.hpp"
#include "dem/time_step.hpp"

namespace tg::dem {

namespace {

// The words of each choice-valued key, the default first (Config::choice):
// read from the config and written back to run.json from one table.
using breakage::BirthOverlap;
using breakage::BondRadiusRule;
using breakage::SublimitPolicy;
const Config::Choices<bool> kDampingScope{{"contacts", false}, {"total", true}};
const Config::Choices<BondRadiusRule> kBondRadiusRule{{"mean", BondRadiusRule::kMean}, {"min", BondRadiusRule::kMin}};
const Config::Choices<SublimitPolicy> kSublimitPolicy{{"remove", SublimitPolicy::kRemove},
                                                      {"keep", SublimitPolicy::kKeep},
                                                      {"keep_unbreakable", SublimitPolicy::kKeepUnbreakable}};
const Config::Choices<BirthOverlap> kBirthOverlap{{"inherit", BirthOverlap::kInherit},
                                                  {"mother", BirthOverlap::kMotherRatio},
                                                  {"none", BirthOverlap::kNone}};

}  // namespace

using json = nlohmann::json;

OedometerSetup read_oedometer_config(Config& cfg, const std::filesystem::path& base_dir) {
  OedometerSetup s;
  s.source = cfg.source();
  EngineOptions& e = s.engine;
  e.material.shear_modulus_Pa = cfg.get("material.shear_modulus_Pa", e.material.shear_modulus_Pa);
  e.material.poisson_ratio = cfg.get("material.poisson_ratio", e.material.poisson_ratio);
  e.material.density_kg_m3 = cfg.get("material.density_kg_m3", e.material.density_kg_m3);
  e.friction = cfg.get("contact.friction", e.friction);
  e.restitution = cfg.get("contact.restitution", e.restitution);
  e.local_damping = cfg.get("contact.local_damping", e.local_damping);
  e.local_damping_total = cfg.choice("contact.local_damping_scope", kDampingScope);
  e.walls.cylinder_radius = cfg.get("walls.cylinder_radius_m", e.walls.cylinder_radius);
  e.walls.platen_friction = cfg.get("walls.platen_friction", e.walls.platen_friction);
  e.walls.cylinder_friction = cfg.get("walls.cylinder_friction", e.walls.cylinder_friction);
  e.gravity_z = -cfg.get("run.gravity_m_s2", -e.gravity_z);
  e.time_step = cfg.get("run.time_step_s", e.time_step);
  s.time_step_safety = cfg.get("run.time_step_safety", s.time_step_safety);
  s.reference_overlap = cfg.get("run.reference_overlap", s.reference_overlap);
  s.mass_scaling = cfg.get("run.mass_scaling", s.mass_scaling);
  e.skin = cfg.get("run.neighbour_skin_m", e.skin);
  e.overlap_limit = cfg.get("run.overlap_limit", e.overlap_limit);
  e.parallel_min_items = cfg.get("run.parallel_min_items", e.parallel_min_items);
  s.threads = cfg.get("run.threads", s.threads);
  s.packing_csv = cfg.get("specimen.packing_csv", std::string());
  if (!s.packing_csv.empty() && std::filesystem::path(s.packing_csv).is_relative())
    s.packing_csv = (base_dir / s.packing_csv).string();
  PluviationOptions& p = s.pluviation;
  p.d50_m = cfg.get("pluviation.d50_m", p.d50_m);
  p.cu = cfg.get("pluviation.cu", p.cu);
  p.generation_height_m = cfg.get("pluviation.generation_height_m", p.generation_height_m);
  p.target_height_m = cfg.get("pluviation.target_height_m", p.target_height_m);
  p.target_porosity = cfg.get("pluviation.target_porosity", p.target_porosity);
  p.seed = static_cast<uint64_t>(cfg.get("pluviation.seed", static_cast<int64_t>(p.seed)));
  p.time_step_safety = cfg.get("pluviation.time_step_safety", p.time_step_safety);
  p.deposition_friction = cfg.get("pluviation.deposition_friction", p.deposition_friction);
  p.press_to_target_height = cfg.get("pluviation.press_to_target_height", p.press_to_target_height);
  p.press_speed_m_s = cfg.get("pluviation.press_speed_m_s", p.press_speed_m_s);
  p.press_max_stress_Pa = cfg.get("pluviation.press_max_stress_Pa", p.press_max_stress_Pa);
  p.kinetic_energy_tol_J = cfg.get("pluviation.kinetic_energy_tol_J", p.kinetic_energy_tol_J);
  p.rest_window_s = cfg.get("pluviation.rest_window_s", p.rest_window_s);
  p.max_time_s = cfg.get("pluviation.max_time_s", p.max_time_s);
  p.cylinder_radius_m = e.walls.cylinder_radius;
  s.platen_speed = cfg.get("oedometer.platen_speed_m_s", s.platen_speed);
  s.target_strain = cfg.get("oedometer.target_strain", s.target_strain);
  s.snapshot_strains = cfg.get("oedometer.snapshot_strains", s.snapshot_strains);
  s.history_every = cfg.get("oedometer.history_every_steps", s.history_every);
  s.checkpoint_every = cfg.get("oedometer.checkpoint_every_steps", s.checkpoint_every);
  breakage::BreakageOptions& b = s.breakage_options;
  s.breakage = cfg.get("breakage.enabled", s.breakage);
  b.check_interval = cfg.get("breakage.check_every_steps", b.check_interval);
  b.min_split_diameter_m = cfg.get("breakage.min_split_diameter_m", b.min_split_diameter_m);
  b.strength.sigma_t0_Pa = cfg.get("breakage.sigma_t0_Pa", b.strength.sigma_t0_Pa);
  b.strength.weibull_modulus = cfg.get("breakage.weibull_modulus", b.strength.weibull_modulus);
  b.strength.d0_m = cfg.get("breakage.d0_m", b.strength.d0_m);
  b.strength.seed = static_cast<uint64_t>(cfg.get("breakage.seed", static_cast<int64_t>(b.strength.seed)));
  b.bond.radius_multiplier = cfg.get("breakage.bond_radius_multiplier", b.bond.radius_multiplier);
  b.bond.tensile_strength_Pa = cfg.get("breakage.bond_normal_strength_Pa", b.bond.tensile_strength_Pa);
  b.bond.shear_strength_Pa = cfg.get("breakage.bond_shear_strength_Pa", b.bond.shear_strength_Pa);
  b.bond.radius_rule = cfg.choice("breakage.bond_radius_rule", kBondRadiusRule);
  b.bond.damping_ratio = cfg.get("breakage.bond_damping", b.bond.damping_ratio);
  cfg.require(b.bond.damping_ratio >= 0 && b.bond.damping_ratio <= 1, "breakage.bond_damping", "must be in [0, 1]");
  b.split_bonded = cfg.get("breakage.split_bonded", b.split_bonded);
  b.time_step_safety = cfg.get("breakage.time_step_safety", b.time_step_safety);
  b.min_time_step_s = cfg.get("breakage.min_time_step_s", b.min_time_step_s);
  b.sublimit = cfg.choice("breakage.sublimit_policy", kSublimitPolicy);
  b.fines_overlap = cfg.get("breakage.fines_overlap", b.fines_overlap);
  b.birth_overlap = cfg.choice("breakage.birth_overlap", kBirthOverlap);
  s.log_bond_breaks = cfg.get("breakage.log_bond_breaks", s.log_bond_breaks);
  cfg.require(b.min_time_step_s >= 0, "breakage.min_time_step_s", "must be >= 0 (0 = no density scaling)");
  cfg.require(b.fines_overlap > 0 && b.fines_overlap < e.overlap_limit, "breakage.fines_overlap",
              "must be in (0, run.overlap_limit)");
  cfg.require(b.check_interval > 0, "breakage.check_every_steps", "must be positive");
  cfg.require(b.min_split_diameter_m >= 0, "breakage.min_split_diameter_m", "must be >= 0");
  cfg.require(b.strength.d0_m >= 0, "breakage.d0_m", "must be >= 0 (0 = mean grain diameter)");
  cfg.require(b.time_step_safety > 0 && b.time_step_safety <= 1, "breakage.time_step_safety", "must be in (0, 1]");

  // Physics in range here, where the key and the file are known.
  cfg.require(e.material.shear_modulus_Pa > 0, "material.shear_modulus_Pa", "must be positive");
  cfg.require(e.material.poisson_ratio > -1 && e.material.poisson_ratio < 0.5, "material.poisson_ratio",
              "must be in (-1, 0.5)");
  cfg.require(e.material.density_kg_m3 > 0, "material.density_kg_m3", "must be positive");
  cfg.require(e.friction >= 0, "contact.friction", "must be >= 0");
  cfg.require(e.restitution > 0 && e.restitution <= 1, "contact.restitution", "must be in (0, 1]");
  cfg.require(e.local_damping >= 0 && e.local_damping < 1, "contact.local_damping", "must be in [0, 1)");
  cfg.require(e.walls.cylinder_radius > 0, "walls.cylinder_radius_m", "must be positive");
  cfg.require(e.walls.platen_friction >= 0, "walls.platen_friction", "must be >= 0");
  cfg.require(e.walls.cylinder_friction >= 0, "walls.cylinder_friction", "must be >= 0");
  cfg.require(e.skin >= 0, "run.neighbour_skin_m", "must be >= 0");
  cfg.require(e.overlap_limit > 0, "run.overlap_limit", "must be positive");
  cfg.require(e.time_step >= 0, "run.time_step_s", "must be >= 0 (0 = automatic)");
  cfg.require(s.time_step_safety > 0 && s.time_step_safety <= 1, "run.time_step_safety", "must be in (0, 1]");
  cfg.require(s.reference_overlap > 0 && s.reference_overlap < 1, "run.reference_overlap", "must be in (0, 1)");
  cfg.require(s.mass_scaling >= 1, "run.mass_scaling", "must be >= 1 (1 = none)");
  cfg.require(s.threads >= 0, "run.threads", "must be >= 0 (0 = all)");
  cfg.require(s.platen_speed > 0, "oedometer.platen_speed_m_s", "must be positive");
  cfg.require(s.pluviation.press_speed_m_s > 0, "pluviation.press_speed_m_s", "must be positive");
  cfg.require(s.pluviation.press_max_stress_Pa > 0, "pluviation.press_max_stress_Pa", "must be positive");
  cfg.require(s.target_strain > 0 && s.target_strain < 0.9, "oedometer.target_strain", "must be in (0, 0.9)");
  cfg.require(s.history_every > 0, "oedometer.history_every_steps", "must be positive");
  cfg.require(s.checkpoint_every > 0, "oedometer.checkpoint_every_steps", "must be positive");
  for (double x : s.snapshot_strains)
    cfg.require(x >= 0 && x <= s.target_strain, "oedometer.snapshot_strains", "must lie in [0, target_strain]");
  std::sort(s.snapshot_strains.begin(), s.snapshot_strains.end());
  cfg.finish();
  return s;
}

namespace {

std::string fmt17(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

struct Scene {
  double h0 = 0;
  int64_t next_snapshot = 0;
  std::string encode() const { return fmt17(h0) + " " + std::to_string(next_snapshot); }
  std::string breakage_state;  // BreakageModel::encode() when breakage is on
  static Scene decode(const std::string& s) {
    Scene c;
    std::istringstream is(s);
    if (!(is >> c.h0 >> c.next_snapshot)) throw InputError("checkpoint: scene state unreadable");
    std::getline(is >> std::ws, c.breakage_state, '\0');
    return c;
  }
};

// The specimen of a new run: read or pluviated, masses scaled (recorded in
// run.json), every sphere inside the cylinder and above the bottom platen,
// and no overlap the engine would refuse at its first step (InputError
// naming the spheres, their rows and the file).
Particles load_specimen(const OedometerSetup& s, const EngineOptions& eo) {
  const double R = s.engine.walls.cylinder_radius;
  Particles p;
  if (!s.packing_csv.empty()) {
    p = read_packing_csv(s.packing_csv, eo.material.density_kg_m3);
  } else {
    p = pluviate(s.pluviation, eo).particles;
  }
  for (int64_t i = 0; i < p.size(); ++i) {  // explicit, recorded mass scaling
    p.m[i] *= s.mass_scaling;
    p.inertia[i] *= s.mass_scaling;
    const double rho = std::hypot(p.x[i], p.y[i]);
    // Settled grains press slightly into the walls: allow 1 % of a radius.
    if (rho + p.r[i] > R + 0.01 * p.r[i] || p.z[i] < 0.99 * p.r[i])
      throw InputError((s.packing_csv.empty() ? std::string("pluviated packing") : s.packing_csv) + ": sphere " +
                       std::to_string(i) + " crosses the cylinder (radius " + fmt17(R) + " m) or the bottom platen");
  }
  {
    // Overlaps beyond the engine's limit would stop the run at its first
    // step: name the spheres and the file now.
    const PairListCSR pl = build_pairs_grid(p, 0.0);
    for (int64_t i = 0; i + 1 < static_cast<int64_t>(pl.offsets.size()); ++i)
      for (int64_t k = pl.offsets[i]; k < pl.offsets[i + 1]; ++k) {
        const int64_t j = pl.j[k];
        const double d = std::sqrt(std::pow(p.x[j] - p.x[i], 2) + std::pow(p.y[j] - p.y[i], 2) + std::pow(p.z[j] - p.z[i], 2));
        const double ov = (p.r[i] + p.r[j] - d) / std::min(p.r[i], p.r[j]);
        if (ov > eo.overlap_limit)
          throw InputError((s.packing_csv.empty() ? std::string("pluviated packing") : s.packing_csv) + ": spheres " +
                           std::to_string(i) + " and " + std::to_string(j) + " (rows " + std::to_string(i + 2) + " and " +
                           std::to_string(j + 2) + ") overlap by " + fmt17(ov) + " of the smaller radius (limit run.overlap_limit = " +
                           fmt17(eo.overlap_limit) + ")");
      }
  }
  return p;
}

// run.json: every choice that changes the physics.
void write_run_record(const std::filesystem::path& rundir, const OedometerSetup& s, const EngineOptions& eo,
                      int64_t spheres, double h0, double porosity, double critical_time_step) {
  json rec = {{"spheres", spheres},
              {"initial_height_m", h0},
              {"initial_porosity", porosity},
              {"time_step_s", eo.time_step},
              {"critical_time_step_s", critical_time_step},
              {"critical_step_reference_overlap", s.reference_overlap},
              {"mass_scaling", s.mass_scaling},
              {"damping", {{"viscous_restitution", eo.restitution}, {"local", eo.local_damping},
                           {"local_scope", Config::name_of(kDampingScope, eo.local_damping_total)}}},
              {"contact", "hertz_mindlin"},
              {"contact_kernel", kernels_name(eo.kernel_isa)},
              {"threads", omp_get_max_threads()},
              {"specimen", s.packing_csv.empty() ? std::string("pluviation") : s.packing_csv}};
  if (s.breakage) {
    const breakage::BreakageOptions& b = s.breakage_options;
    rec["breakage"] = {{"min_split_diameter_m", b.min_split_diameter_m},
                       {"density_scaling_min_time_step_s", b.min_time_step_s},
                       {"time_step_safety", b.time_step_safety},
                       {"sublimit_policy", Config::name_of(kSublimitPolicy, b.sublimit)},
                       {"fines_overlap", b.fines_overlap},
                       {"split_bonded", b.split_bonded},
                       {"bond_radius_rule", Config::name_of(kBondRadiusRule, b.bond.radius_rule)},
                       {"bond_damping", b.bond.damping_ratio},
                       {"birth_overlap", Config::name_of(kBirthOverlap, b.birth_overlap)}};
  }
  write_file_atomic(rundir / "run.json", rec.dump(2) + "\n");
}

}  // namespace

OedometerSummary run_oedometer(const OedometerSetup& s, const std::filesystem::path& rundir, const RunControl& c) {
  namespace fs = std::filesystem;
  // The run folder is made only once the input has passed every check:
  // a bad packing or config leaves nothing behind.
  if (s.threads > 0) omp_set_num_threads(s.threads);
  const double R = s.engine.walls.cylinder_radius, area = std::numbers::pi * R * R;
  const fs::path ckpt = rundir / "checkpoint.bin";
  OedometerSummary sum;
  EngineOptions eo = s.engine;
  Scene scene;
  HistoryTable hist(s.breakage);
  std::optional<Engine> eng;
  double vsolid = 0;
  if (c.restart) {
    CheckpointState st = load_checkpoint(ckpt);
    scene = Scene::decode(st.scene);
    const CriticalTimeStep ct = critical_time_step(st.particles, eo.material, {s.reference_overlap});
    if (eo.time_step == 0) eo.time_step = s.time_step_safety * ct.dt_critical;
    sum.critical_time_step = ct.dt_critical;
    eng.emplace(resume_engine(st, eo));
    fs::create_directories(rundir / "snapshots");
    // A run killed while writing a file leaves its temporary beside it.
    remove_stale_temporaries(rundir);
    remove_stale_temporaries(rundir / "snapshots");
    hist.read_until(rundir / "history.csv", eng->step_count());
  } else {
    Particles p = load_specimen(s, eo);
    double por = 0;
    packing_height_porosity(p, R, scene.h0, por);
    const CriticalTimeStep ct = critical_time_step(p, eo.material, {s.reference_overlap});
    sum.critical_time_step = ct.dt_critical * std::sqrt(s.mass_scaling);
    if (eo.time_step == 0) eo.time_step = s.time_step_safety * sum.critical_time_step;
    if (eo.time_step > sum.critical_time_step)
      throw InputError(s.source + ": run.time_step_s = " + fmt17(eo.time_step) + " s exceeds the critical step " +
                       fmt17(sum.critical_time_step) + " s of this packing");
    eo.walls.top_z = scene.h0;
    eo.walls.top_vz = -s.platen_speed;
    eng.emplace(std::move(p), eo);
    fs::create_directories(rundir / "snapshots");
    write_packing_csv(eng->particles(), rundir / "packing_initial.csv");
    write_run_record(rundir, s, eo, eng->particles().size(), scene.h0, por, sum.critical_time_step);
  }
  Engine& e = *eng;
  // The initial grains: the packing now, or packing_initial.csv on a restart
  // (by then splits have replaced some). Their volume is the reference of the
  // porosity, summed in the same order either way, so a restart reproduces it
  // bit for bit.
  const Particles restart_p0 = c.restart ? read_packing_csv(rundir / "packing_initial.csv", eo.material.density_kg_m3) : Particles{};
  const Particles& p0 = c.restart ? restart_p0 : e.particles();
  for (int64_t i = 0; i < p0.size(); ++i) vsolid += 4.0 / 3.0 * std::numbers::pi * std::pow(p0.r[i], 3);
  std::optional<breakage::BreakageModel> brk;
  if (s.breakage) {
    breakage::BreakageOptions bo = s.breakage_options;
    bo.bond.youngs_modulus_Pa = eo.material.youngs_modulus();
    bo.bond.shear_modulus_Pa = eo.material.shear_modulus_Pa;
    if (bo.strength.d0_m == 0) {  // mean diameter of the initial grains
      double sum_d = 0;
      for (int64_t i = 0; i < p0.size(); ++i) sum_d += 2 * p0.r[i];
      bo.strength.d0_m = sum_d / static_cast<double>(p0.size());
    }
    brk.emplace(e, bo);
    if (c.restart) brk->restore(scene.breakage_state);
  }
  sum.time_step = eo.time_step;
  sum.spheres = e.particles().size();
  sum.initial_height_m = scene.h0;
  sum.initial_porosity = 1 - vsolid / (area * scene.h0);

  auto strain = [&] { return (scene.h0 - e.walls().top_z) / scene.h0; };
  auto record = [&] {
    const WallForces& w = e.wall_forces();
    const double h = e.walls().top_z;
    const double st = w.top_z / area + 0.0, sb = 0.0 - w.bottom_z / area, sl = w.cylinder_radial / (2 * std::numbers::pi * R * h);
    const double sv = 0.5 * (st + sb);
    hist.add({static_cast<double>(e.step_count()), e.time(), strain(), st, sb, sl, sv > 0 ? sl / sv : 0.0,
              e.kinetic_energy(), e.coordination_number(), static_cast<double>(e.contact_count()),
              1 - (vsolid - (brk ? brk->record().volume_lost_m3 : 0.0)) / (area * h), h});
    if (brk) {
      const breakage::BreakageRecord& r = brk->record();
      auto gen = [&](size_t g) {
        double v = 0;
        for (size_t k = g; k < r.splits_by_generation.size() && (g == 3 || k == g); ++k) v += static_cast<double>(r.splits_by_generation[k]);
        return v;
      };
      std::vector<double> row{static_cast<double>(r.grains_broken), gen(0), gen(1), gen(2), gen(3),
                              static_cast<double>(r.bonds_broken), static_cast<double>(r.bonds_dropped),
                              static_cast<double>(r.bonds_intact), static_cast<double>(r.spheres),
                              static_cast<double>(r.particles), r.volume_lost_m3, e.options().time_step,
                              static_cast<double>(r.fines_removed), r.fines_volume_m3, r.added_mass_fraction};
      for (size_t k = 0; k < row.size(); ++k) hist.last(HistoryTable::base_columns().size() + k) = row[k];
    }
  };
  // The snapshot index (dem/run_folder.hpp): on a restart, the entries the
  // checkpoint had already written.
  std::vector<SnapshotEntry> index = c.restart ? read_snapshot_index(rundir, e.step_count()) : std::vector<SnapshotEntry>{};
  auto snapshot = [&] {
    const double target = s.snapshot_strains[static_cast<size_t>(scene.next_snapshot)];
    char name[64];
    std::snprintf(name, sizeof name, "strain_%05.2fpct.h5", 100 * target);
    const json attr = {{"requested_strain", target}, {"strain", strain()}, {"time_s", e.time()}, {"step", e.step_count()}};
    write_snapshot(e.particles(), rundir / "snapshots" / name, attr.dump());
    // The next snapshot's lineage starts here (every sphere's particle now).
    e.particles().previous_particle = e.particles().particle;
    SnapshotEntry entry{std::string("snapshots/") + name, e.step_count(), e.time(), strain(), target, ""};
    if (brk) {
      std::string bn = name;
      bn.replace(bn.size() - 3, 3, "_bonds.csv");
      write_bonds_csv(*brk, rundir / "snapshots" / bn);
      entry.bonds = "snapshots/" + bn;
    }
    index.push_back(entry);
    write_snapshot_index(rundir, index);
    ++scene.next_snapshot;
  };
  auto checkpoint = [&] {
    hist.write(rundir / "history.csv");
    if (brk)  // one row per split of this process (a restart starts a new list)
      write_splits_csv(brk->events(), rundir / (c.restart ? "splits_after_restart.csv" : "splits.csv"));
    if (brk && s.log_bond_breaks)
      write_bond_breaks_csv(brk->bond_break_log(), rundir / (c.restart ? "bond_breaks_after_restart.csv" : "bond_breaks.csv"));
    save_checkpoint(e, brk ? scene.encode() + " " + brk->encode() : scene.encode(), ckpt);
  };

  const auto t0 = std::chrono::steady_clock::now();
  const int64_t step0 = e.step_count();
  Progress bar("oedometer strain", 100 * s.target_strain, "%");
  if (!c.restart) record();
  const int64_t nsnap = static_cast<int64_t>(s.snapshot_strains.size());
  // Steps until the loop below has something to do: a history row, a
  // checkpoint, the stop step, or the strain of the next snapshot or of the
  // target (the platen's path is known: the engine adds dt vz to its height
  // each step, as done here). Engine::run() fuses the steps in between
  // (same bits as one step() at a time). With breakage: one step, as the
  // model checks and edits the spheres between steps.
  const auto steps_to_next_event = [&]() -> int64_t {
    if (brk) return 1;
    const int64_t sc = e.step_count();
    int64_t lim = std::min(s.history_every - sc % s.history_every, s.checkpoint_every - sc % s.checkpoint_every);
    if (c.stop_after_steps >= 0) lim = std::min(lim, c.stop_after_steps - sc);
    const double dt = e.options().time_step, vz = e.walls().top_vz;
    const bool snap = scene.next_snapshot < nsnap;
    const double next_snap = snap ? s.snapshot_strains[static_cast<size_t>(scene.next_snapshot)] - 1e-12 : 0;
    double z = e.walls().top_z;
    int64_t k = 0;
    while (k < lim) {
      z += dt * vz;
      ++k;
      const double st = (scene.h0 - z) / scene.h0;
      if (st >= s.target_strain || (snap && st >= next_snap)) break;
    }
    return std::max<int64_t>(k, 1);
  };
  while (true) {
    while (scene.next_snapshot < nsnap && strain() >= s.snapshot_strains[static_cast<size_t>(scene.next_snapshot)] - 1e-12)
      snapshot();
    if (strain() >= s.target_strain) {
      sum.finished = true;
      break;
    }
    if (c.stop_after_steps >= 0 && e.step_count() >= c.stop_after_steps) break;
    e.run(steps_to_next_event());
    if (brk && brk->check_due()) brk->check();
    if (e.step_count() % s.history_every == 0) {
      record();
      if (!c.quiet) bar.update(100 * strain());
    }
    if (e.step_count() % s.checkpoint_every == 0) checkpoint();
  }
  if (sum.finished && e.step_count() % s.history_every != 0) record();  // last row at the target
  bar.finish();
  checkpoint();
  sum.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  sum.steps = e.step_count();
  sum.particle_steps_per_second =
      sum.wall_seconds > 0 ? static_cast<double>(sum.steps - step0) * static_cast<double>(sum.spheres) / sum.wall_seconds : 0;
  sum.strain = strain();
  sum.top_stress_Pa = e.wall_forces().top_z / area;
  sum.final_state = e.particles();
  if (brk) sum.breakage = brk->record();
  sum.time_step = e.options().time_step;
  return sum;
}

}  // namespace tg::dem
