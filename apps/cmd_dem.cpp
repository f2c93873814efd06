// `tomograin dem ...`: the DEM engine's jobs (oedometer run, specimen pack).
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <filesystem>

#include "apps/command.hpp"
#include "core/config.hpp"
#include "core/errors.hpp"
#include "core/table.hpp"
#include "dem/breakage/crush.hpp"
#include "dem/calibration/calibrate.hpp"
#include "dem/oedometer.hpp"
#include "dem/packing_io.hpp"
#include "dem/pluviation.hpp"
#include "dem/yield_stress.hpp"

namespace cmd_dem {
struct Opts {
  std::string config, out;
  bool restart = false;
  tg::dem::breakage::CrushOptions crush;
  std::string crush_model;
  tg::dem::calibration::CalibrateOptions calib;
  std::string calib_config, calib_target;
  std::string curve;
  double floor_mpa = 0.1;
  bool no_plot = false;
};

tg::dem::OedometerSetup load(const std::string& path) {
  if (!std::filesystem::exists(path)) throw tg::InputError(path + ": config file not found");
  tg::Config cfg = tg::Config::from_file(path);
  return tg::dem::read_oedometer_config(cfg, std::filesystem::path(path).parent_path());
}
}  // namespace cmd_dem

namespace cmd_dem {
static tg::app::Registrar reg{{"dem", 60,
      "DEM of the oedometer test: specimen preparation and compression.\n\n"
      "Subcommands:\n"
      "  pack       pluviate a specimen and write it as CSV (x_m,y_m,z_m,r_m)\n"
      "  oedometer  compress a specimen at constant platen speed; writes a run folder\n"
      "  crush      single-grain crushing test with the breakage model (history CSV)\n"
      "  calibrate  fit sigma_t0 and lambda to a stress-strain curve (and yield, broken fraction)\n"
      "  yield      the yield stress of a stress-strain curve (a run's history.csv or an experiment's)\n\n"
      "Every parameter is a key of one TOML config (SI units, defaults from the\n"
      "reference study); see dem/examples/oedometer.toml for all keys, documented.\n\n"
      "Examples:\n"
      "  tomograin dem pack dem/examples/oedometer.toml -o packing.csv\n"
      "  tomograin dem oedometer dem/examples/demo.toml -o runs/demo\n"
      "  tomograin dem oedometer cfg.toml -o runs/a --restart   # continue from checkpoint",
      [](CLI::App* sub) -> tg::app::Runner {
  sub->require_subcommand(1);
  auto o = std::make_shared<Opts>();
  CLI::App* oed = sub->add_subcommand(
      "oedometer",
      "Oedometric compression: the top platen moves down at oedometer.platen_speed_m_s (0.1 m/s) until\n"
      "oedometer.target_strain (15.48 %), strain measured from the top of the highest grain.\n"
      "The specimen is specimen.packing_csv if given, else pluviated ([pluviation] keys).\n"
      "RUNDIR receives: config.toml (copy), run.json (time step, critical step, damping, mass\n"
      "scaling, threads), history.csv (strain, top/bottom/lateral stress in Pa, K0, kinetic energy,\n"
      "coordination number, contacts, porosity), snapshots/strain_*.h5 + .xmf (ParaView: open the\n"
      ".xmf, apply Glyph scaled by r_m), checkpoint.bin (for --restart).\n"
      "Breakage ([breakage], on by default, Table 1): history.csv gains grains broken, splits per\n"
      "generation, bonds broken, spheres, volume lost, fines removed, added mass (density scaling keeps\n"
      "dt >= breakage.min_time_step_s, 1e-8 s); splits.csv lists every split; snapshots get bond CSVs;\n"
      "breakage.log_bond_breaks = true adds bond_breaks.csv (every bond broken, with its age in steps and s).\n\n"
      "Example:\n  tomograin dem oedometer dem/examples/demo.toml -o runs/demo");
  oed->add_option("config", o->config, "TOML config (unknown keys are errors)")->required();
  oed->add_option("-o,--output", o->out, "Run folder (created)")->required();
  oed->add_flag("--restart", o->restart, "Continue the run in RUNDIR from its checkpoint.bin");
  CLI::App* pack = sub->add_subcommand(
      "pack",
      "Specimen by pluviation: diameters ~ normal (pluviation.d50_m 1.36 mm, pluviation.cu 1.07),\n"
      "random non-overlapping insertion in a Ø15 mm x 30 mm cylinder, settling under gravity until the\n"
      "kinetic energy is below pluviation.kinetic_energy_tol_J, with friction\n"
      "pluviation.deposition_friction (default 0: frictionless deposition, dense). The grain count fills\n"
      "pluviation.target_height_m (12.25 mm) at pluviation.target_porosity (44.5 %). A deposit that\n"
      "settles higher is pressed down to that height by the top platen (pluviation.press_speed_m_s\n"
      "0.02 m/s; it stops early above press_max_stress_Pa, 10 kPa), held until at rest and released,\n"
      "as in the study (off: pluviation.press_to_target_height = false).\n"
      "Prints count, height and porosity reached; writes CSV x_m,y_m,z_m,r_m (metres, axis z, bottom z = 0).\n\n"
      "Example:\n  tomograin dem pack dem/examples/oedometer.toml -o packing.csv");
  pack->add_option("config", o->config, "TOML config (same keys as `dem oedometer`)")->required();
  pack->add_option("-o,--output", o->out, "Packing CSV to write")->required();
  CLI::App* crush = sub->add_subcommand(
      "crush",
      "Single-particle crushing test: one grain between two platens, the top one moving down at\n"
      "--speed (0.1 m/s) until --travel x d. The grain splits when F/d^2 first exceeds its Weibull\n"
      "strength (sigma_t0 12 MPa, m = 3, d0 = --d0, drawn from --seed; checked every 10 steps) into\n"
      "two bonded 17-sphere fragments (54 % of its volume), whose bonds (3.3 MPa, lambda 1.25) and\n"
      "elements (d >= 0.2 mm) break in turn. Gravity and cylinder off; Table 1 material.\n"
      "Writes a CSV: step, time_s, travel_m, force_N (top platen), grains_broken, bonds_broken,\n"
      "bonds_dropped, spheres, particles, volume_lost_m3; prints every split.\n\n"
      "With --model CONFIG the material, contact, damping and breakage options (sigma_t0, m, lambda,\n"
      "bond strengths, ...) are an oedometer config's, as `dem calibrate`'s crush term uses them (d0 = 0\n"
      "there means d); options given here still win.\n\n"
      "Examples:\n  tomograin dem crush -d 1.2e-3 --travel 0.1 -o crush.csv\n"
      "  tomograin dem crush --model dem/examples/oedometer_calibrated.toml --seed 7 -o crush.csv");
  crush->add_option("-d,--diameter", o->crush.diameter_m, "Grain diameter, m (default 1.2e-3)");
  crush->add_option("--speed", o->crush.platen_speed_m_s, "Platen speed, m/s (default 0.1)");
  crush->add_option("--travel", o->crush.final_travel_fraction, "Final platen travel / d (default 0.4)");
  crush->add_option("--d0", o->crush.breakage.strength.d0_m, "Weibull reference size d0, m (default 1e-3)");
  crush->add_option("--seed", o->crush.breakage.strength.seed, "Strength seed (default 1)");
  crush->add_option("--min-split", o->crush.breakage.min_split_diameter_m, "Smallest diameter that splits, m (default 2e-4)");
  crush->add_option("--bond-radius-multiplier", o->crush.breakage.bond.radius_multiplier,
                    "Bond radius multiplier lambda of the fragments (default 1.25)");
  crush->add_option("--min-dt", o->crush.breakage.min_time_step_s,
                    "Density scaling: new spheres are made heavy enough for this time step, s (default 1e-8; 0 = off)");
  crush->add_option("--model", o->crush_model, "Oedometer TOML config whose material, contact and breakage options to use");
  crush->add_option("-o,--output", o->out, "History CSV to write")->required();
  CLI::App* cal = sub->add_subcommand(
      "calibrate",
      "Fits breakage.sigma_t0_Pa and breakage.bond_radius_multiplier (lambda) of CONFIG to a target with\n"
      "few full oedometer runs: a seeded Latin hypercube of --initial runs, then rounds of --batch runs\n"
      "where a Gaussian-process surrogate (Matern 5/2) expects the most improvement, --runs in all.\n"
      "Runs are child processes (`dem oedometer`, --jobs at a time, one thread each) in DIR/runs/run_NNN;\n"
      "the proposals depend on --seed, --initial, --batch, --runs, never on --jobs.\n"
      "TARGET: a CSV curve (columns strain, stress_Pa; a run's history.csv also works) or a TOML file:\n"
      "  [target]\n"
      "  stress_strain_csv = \"curve.csv\"    # relative to TARGET\n"
      "  yield_stress_Pa = 2.0e6             # bilinear strain-log(stress) rule above 0.1 MPa\n"
      "  broken_strain = [0.044, 0.1548]     # grains broken / initial grains at these strains\n"
      "  broken_fraction = [0.05, 0.35]\n"
      "  broken_at_stress_Pa = [2.0e6, 4.0e6]      # grains broken / initial grains when the top\n"
      "  broken_fraction_at_stress = [0.022, 0.31] # stress first reaches these (1 if never)\n"
      "  bonds_broken_at_stress = [300, 10000]     # bonds broken by stress there (as a ratio)\n"
      "  [crush]                             # single-grain crush tests, run in this process\n"
      "  bonds_broken = 134.0                # mean bonds broken by stress over the tests\n"
      "  grains = 30                         # strength seeds 1..grains (defaults shown)\n"
      "  diameter_m = 1.2e-3\n  travel = 0.4                        # platen travel / diameter\n"
      "  [weights]                           # default 1 each\n"
      "  stress_strain = 1.0\n  yield_stress = 1.0\n  broken_fraction = 1.0\n  broken_at_stress = 1.0\n"
      "  bonds_at_stress = 1.0\n  crush = 1.0\n"
      "  [parameters]                        # searched ranges (these are the defaults)\n"
      "  sigma_t0_Pa = [6.0e6, 24.0e6]\n  bond_radius_multiplier = [0.8, 1.6]\n"
      "Objective J = sum of weight x misfit: curve RMS(sigma_run - sigma_target)/RMS(sigma_target) over the\n"
      "target's points; |yield_run - yield|/yield; RMS of broken-fraction differences (at strains; at\n"
      "stresses, 1 for one never reached); RMS of min(1, |log10 ratio|) of the bonds broken at the\n"
      "stresses (1 for one never reached); |b_run - b|/b of the crush tests' mean bonds broken (CONFIG's\n"
      "material and breakage, the candidate's parameters). With a [crush] target the search models b_run\n"
      "(log) and J - w_crush x m_crush with a surrogate each and combines them: the crush term's narrow\n"
      "valley along lambda is kept, where one surrogate of J rounds it off.\n"
      "DIR receives runs.csv (every run's parameters, figures, misfits, objective), best.toml (CONFIG with\n"
      "the best run's parameters), calibration.json (objective, weights, ranges, best, surrogate's\n"
      "predicted optimum), surface.csv and objective_surface.png (Debian's python3-matplotlib).\n"
      "Measured (bench/dem/RESULTS.md): on the 126-grain demo cell sigma_t0 is recovered within 3 %;\n"
      "lambda hardly moves the oedometer curve and is not identifiable from it; the [crush] target\n"
      "identifies it (dem/calibration/README.md).\n\n"
      "Example:\n"
      "  tomograin dem calibrate dem/examples/demo.toml --target curve.csv -o calib --runs 20 --jobs 2 --batch 2");
  cal->add_option("config", o->calib_config, "Oedometer TOML config (unknown keys are errors; breakage on)")->required();
  cal->add_option("--target", o->calib_target, "Target: curve CSV or TOML (above)")->required();
  cal->add_option("-o,--output", o->out, "Output folder (new or empty)")->required();
  cal->add_option("--runs", o->calib.search.evaluations, "DEM runs in all (default 20)");
  cal->add_option("--initial", o->calib.search.initial, "Latin hypercube runs first (default 8)");
  cal->add_option("--batch", o->calib.search.batch, "Runs proposed per round after them (default 1)");
  cal->add_option("--seed", o->calib.search.seed, "Seed of the design and the search (default 1)");
  cal->add_option("--jobs", o->calib.jobs, "Runs at a time, as child processes (default 1)");
  cal->add_option("--threads-per-run", o->calib.threads_per_run, "OpenMP threads of each run (default 1)");
  cal->add_option("--python", o->calib.python, "Python with matplotlib for the plot (default /usr/bin/python3)");
  cal->add_flag("--no-plot", o->no_plot, "No objective_surface.png (the data files are written all the same)");
  CLI::App* yld = sub->add_subcommand(
      "yield",
      "Yield stress of an oedometer curve, by the rule the report and `dem calibrate` use: strain\n"
      "against log10(stress) over the points above --floor-mpa, up to each new peak (drops and unloading\n"
      "left out), fitted by two straight lines split where they leave the least residual, the second at\n"
      "least 1.5 times as steep as the first (a knee); the yield is where they cross (dem/yield_stress.hpp).\n"
      "Strain stands in for the void ratio: e = e0 - (1 + e0) strain while the solids keep their volume\n"
      "(a DEM run's porosity column also counts the volume its fragments lose, which is not the\n"
      "specimen's compression).\n"
      "CURVE: CSV with columns strain and stress_Pa (or top_stress_Pa: a run's history.csv), strain\n"
      "increasing. Prints one line: yield_MPa, the strain where the curve first reaches it, the points\n"
      "fitted; yield_MPa nan when the curve has fewer than 6 points above the floor or no knee in them\n"
      "(a straight line, a curve that only stiffens).\n\n"
      "Example:\n  tomograin dem yield runs/a/history.csv");
  yld->add_option("curve", o->curve, "Stress-strain CSV (columns strain, stress_Pa or top_stress_Pa)")->required();
  yld->add_option("--floor-mpa", o->floor_mpa, "Points at or below this stress are left out, MPa (default 0.1)")
      ->check(CLI::PositiveNumber);
  return [o, oed, pack, crush, cal, yld] {
    if (yld->parsed()) {
      if (std::filesystem::path(o->curve).extension() != ".csv")
        throw tg::InputError(o->curve + ": not a .csv curve (columns strain, stress_Pa or top_stress_Pa)");
      if (!std::filesystem::exists(o->curve)) throw tg::InputError(o->curve + ": curve file not found");
      const tg::dem::calibration::Target t = tg::dem::calibration::read_target(o->curve);
      std::vector<double> mpa;
      for (double s : t.curve_stress_Pa) mpa.push_back(s / 1e6);
      const double y = tg::dem::yield_stress_mpa(t.curve_strain, mpa, o->floor_mpa);
      double at = std::numeric_limits<double>::quiet_NaN();
      int fitted = 0;
      double peak = 0;
      for (size_t i = 0; i < mpa.size(); ++i) {
        if (std::isnan(at) && mpa[i] >= y) at = t.curve_strain[i];
        if (mpa[i] > o->floor_mpa && mpa[i] > peak) ++fitted, peak = mpa[i];
      }
      std::printf("yield_MPa %.6g strain_pct %.4g points %d (bilinear strain-log10 stress above %g MPa): %s\n", y,
                  100 * at, fitted, o->floor_mpa, o->curve.c_str());
      return 0;
    }
    if (cal->parsed()) {
      namespace cal_ns = tg::dem::calibration;
      o->calib.config = o->calib_config;
      o->calib.target = o->calib_target;
      o->calib.out = o->out;
      o->calib.plot = !o->no_plot;
      std::error_code ec;
      o->calib.executable = std::filesystem::read_symlink("/proc/self/exe", ec).string();
      const cal_ns::CalibrationResult r = cal_ns::run_calibration(o->calib);
      const auto& params = r.target.parameters;
      std::printf("best run %d of %zu: objective %.5g;", r.search.best, r.search.values.size(),
                  r.search.values[r.search.best]);
      for (size_t k = 0; k < params.size(); ++k) std::printf(" %s %.5g", params[k].name.c_str(), r.best_parameters[k]);
      std::printf("\nsurrogate's optimum: objective %.5g +- %.2g;", r.search.predicted_value, r.search.predicted_sd);
      for (size_t k = 0; k < params.size(); ++k) std::printf(" %s %.5g", params[k].name.c_str(), r.predicted_parameters[k]);
      std::printf("\nwritten: %s/{runs.csv,best.toml,calibration.json,surface.csv,objective_surface.png}\n",
                  o->out.c_str());
      return 0;
    }
    if (crush->parsed()) {
      if (!o->crush_model.empty()) {
        // The config's model, then the options given on the command line on top.
        const tg::dem::breakage::CrushOptions& given = o->crush;
        tg::dem::breakage::CrushOptions c = tg::dem::calibration::crush_options(
            load(o->crush_model), given.diameter_m, given.final_travel_fraction, given.breakage.strength.seed);
        c.platen_speed_m_s = given.platen_speed_m_s;
        if (crush->count("--d0")) c.breakage.strength.d0_m = given.breakage.strength.d0_m;
        if (crush->count("--min-split")) c.breakage.min_split_diameter_m = given.breakage.min_split_diameter_m;
        if (crush->count("--bond-radius-multiplier")) c.breakage.bond.radius_multiplier = given.breakage.bond.radius_multiplier;
        if (crush->count("--min-dt")) c.breakage.min_time_step_s = given.breakage.min_time_step_s;
        o->crush = c;
      }
      const auto r = tg::dem::breakage::run_crush(o->crush);
      std::printf("grain strength %.4g MPa; dt %.3g s -> %.3g s\n", r.strength_Pa / 1e6, r.time_step_initial_s, r.time_step_final_s);
      for (const auto& e : r.splits)
        std::printf("split step %lld sphere %lld gen %d d %.4g mm F %.4g N F/d^2 %.4g MPa strength %.4g MPa normal (%.3f %.3f %.3f)\n",
                    static_cast<long long>(e.step), static_cast<long long>(e.sphere), e.generation, e.diameter_m * 1e3,
                    e.f_max_N, e.stress_Pa / 1e6, e.strength_Pa / 1e6, e.plane.normal.x, e.plane.normal.y, e.plane.normal.z);
      tg::Table t;
      std::vector<double> c[10];
      for (const auto& h : r.history) {
        const double v[10] = {static_cast<double>(h.step), h.time_s, h.travel_m, h.force_N,
                              static_cast<double>(h.record.grains_broken), static_cast<double>(h.record.bonds_broken),
                              static_cast<double>(h.record.bonds_dropped), static_cast<double>(h.record.spheres),
                              static_cast<double>(h.record.particles), h.record.volume_lost_m3};
        for (int k = 0; k < 10; ++k) c[k].push_back(v[k]);
      }
      const char* names[10] = {"step", "time_s", "travel_m", "force_N", "grains_broken", "bonds_broken", "bonds_dropped",
                               "spheres", "particles", "volume_lost_m3"};
      for (int k = 0; k < 10; ++k) t.add(names[k], c[k]);
      tg::write_csv(t, o->out);
      return 0;
    }
    const tg::dem::OedometerSetup s = load(o->config);
    if (pack->parsed()) {
      if (s.threads > 0) omp_set_num_threads(s.threads);
      const tg::dem::PluviationResult r = tg::dem::pluviate(s.pluviation, s.engine);
      tg::dem::write_packing_csv(r.particles, o->out);
      std::printf("pluviated %lld grains: height %.4f mm, porosity %.2f %%, settled %s after %.3f s (KE %.3g J)\n",
                  static_cast<long long>(r.particles.size()), r.height_m * 1e3, 100 * r.porosity,
                  r.settled ? "yes" : "NO", r.settle_time_s, r.kinetic_energy_J);
      if (r.pressed && r.press_stop_stress_Pa == 0)
        std::printf("  the free deposit (%.4f mm, porosity %.2f %%) was pressed to the target height\n",
                    r.deposit_height_m * 1e3, 100 * r.deposit_porosity);
      else if (r.pressed)
        std::printf("  the free deposit (%.4f mm, porosity %.2f %%) was pressed until the platen stress reached\n"
                    "  %.0f Pa (pluviation.press_max_stress_Pa), short of the target height %.4f mm\n",
                    r.deposit_height_m * 1e3, 100 * r.deposit_porosity, r.press_stop_stress_Pa,
                    s.pluviation.target_height_m * 1e3);
      return 0;
    }
    (void)oed;
    namespace fs = std::filesystem;
    // Bad input found while setting up (packing, physics) leaves no run
    // folder behind; a run that has begun its history keeps everything.
    const bool fresh = !o->restart && !fs::exists(o->out);
    auto run = [&] {
      fs::create_directories(o->out);
      if (!o->restart) fs::copy_file(o->config, fs::path(o->out) / "config.toml", fs::copy_options::overwrite_existing);
      tg::dem::RunControl c;
      c.restart = o->restart;
      return tg::dem::run_oedometer(s, o->out, c);
    };
    tg::dem::OedometerSummary r;
    try {
      r = run();
    } catch (const tg::InputError&) {
      std::error_code ec;
      if (fresh && !fs::exists(fs::path(o->out) / "history.csv")) fs::remove_all(o->out, ec);
      throw;
    }
    std::printf("oedometer: %lld spheres, H0 %.4f mm, porosity %.2f %%, dt %.3g s (critical %.3g s), %lld steps\n"
                "  strain %.2f %%, top stress %.4g MPa, wall %.1f s, %.3g particle-steps/s (%d threads)\n",
                static_cast<long long>(r.spheres), r.initial_height_m * 1e3, 100 * r.initial_porosity, r.time_step,
                r.critical_time_step, static_cast<long long>(r.steps), 100 * r.strain, r.top_stress_Pa / 1e6,
                r.wall_seconds, r.particle_steps_per_second, omp_get_max_threads());
    if (s.breakage)
      std::printf("  breakage: %lld grains broken, %lld bonds broken, %lld spheres, %lld particles, %.3g mm^3 lost\n",
                  static_cast<long long>(r.breakage.grains_broken), static_cast<long long>(r.breakage.bonds_broken),
                  static_cast<long long>(r.breakage.spheres), static_cast<long long>(r.breakage.particles),
                  r.breakage.volume_lost_m3 * 1e9);
    // The whole history (a restarted run's too): the yield by the report's rule.
    const tg::Table h = tg::read_csv(fs::path(o->out) / "history.csv");
    std::vector<double> mpa;
    for (double x : h.num("top_stress_Pa")) mpa.push_back(x / 1e6);
    const double y = tg::dem::yield_stress_mpa(h.num("strain"), mpa);
    if (std::isnan(y))
      std::printf("  yield: none (fewer than 6 rows above 0.1 MPa, or no knee; `tomograin dem yield --help`)\n");
    else
      std::printf("  yield %.3g MPa (`tomograin dem yield %s/history.csv` says how)\n", y, o->out.c_str());
    return 0;
  };
}}};
}  // namespace cmd_dem
