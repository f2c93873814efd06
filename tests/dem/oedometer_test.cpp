// The oedometer scene: config strictness, run folder contents, and restart
// from a checkpoint continuing bit for bit.
#include "dem/oedometer.hpp"
#include "dem/run_folder.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>

#include "core/errors.hpp"
#include "core/io/hdf5.hpp"
#include "core/table.hpp"
#include "dem/checkpoint.hpp"
#include "dem/packing_io.hpp"
#include "dem/pluviation.hpp"

namespace tg::dem {
namespace {
namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("tg_dem_oedo_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

// A tiny specimen: 25 grains inserted (not settled) in a Ø6 mm cell; fast platen.
OedometerSetup tiny(const fs::path& dir) {
  PluviationOptions po;
  po.cylinder_radius_m = 3e-3;
  po.generation_height_m = 6e-3;
  po.target_height_m = 3e-3;
  const Particles p = insert_grains(po, 2180);
  write_packing_csv(p, dir / "packing.csv");
  Config cfg = Config::from_string(
      "[walls]\ncylinder_radius_m = 3e-3\n[specimen]\npacking_csv = \"packing.csv\"\n"
      "[oedometer]\nplaten_speed_m_s = 0.5\ntarget_strain = 0.05\nsnapshot_strains = [0.0, 0.02, 0.05]\n"
      "history_every_steps = 200\ncheckpoint_every_steps = 1000\n",
      "tiny.toml");
  return read_oedometer_config(cfg, dir);
}

TEST(Oedometer, RestartContinuesBitForBit) {
  const fs::path d = scratch("restart");
  const OedometerSetup s = tiny(d);
  RunControl full;
  full.quiet = true;
  const OedometerSummary a = run_oedometer(s, d / "a", full);
  ASSERT_TRUE(a.finished);
  ASSERT_GT(a.steps, 3000);
  RunControl part = full;
  part.stop_after_steps = a.steps / 2 + 7;  // not on a checkpoint/history boundary
  const OedometerSummary b = run_oedometer(s, d / "b", part);
  EXPECT_FALSE(b.finished);
  RunControl resume = full;
  resume.restart = true;
  const OedometerSummary c = run_oedometer(s, d / "b", resume);
  EXPECT_TRUE(c.finished);
  EXPECT_EQ(c.steps, a.steps);
  int fields = 0;
  a.final_state.for_each_field([&](std::string_view name, const auto& va) {
    c.final_state.for_each_field([&](std::string_view nc, const auto& vc) {
      if constexpr (std::is_same_v<std::decay_t<decltype(va)>, std::decay_t<decltype(vc)>>)
        if (name == nc) {
          ++fields;
          EXPECT_TRUE(va == vc) << "field " << name << " differs after restart";
        }
    });
  });
  EXPECT_EQ(fields, 31);
  EXPECT_EQ(a.top_stress_Pa, c.top_stress_Pa);
  // The histories agree too (the restarted one was stitched from the checkpoint).
  const Table ha = read_csv(d / "a" / "history.csv"), hc = read_csv(d / "b" / "history.csv");
  EXPECT_EQ(ha.num("top_stress_Pa"), hc.num("top_stress_Pa"));
  EXPECT_EQ(ha.num("step"), hc.num("step"));
  double peak = 0;
  for (double v : ha.num("top_stress_Pa")) peak = std::max(peak, v);
  EXPECT_GT(peak, 0);  // the platen did load the grains
  fs::remove_all(d);
}

TEST(Oedometer, RunFolderHasHistoryAndSnapshots) {
  const fs::path d = scratch("folder");
  const OedometerSetup s = tiny(d);
  RunControl c;
  c.quiet = true;
  const OedometerSummary r = run_oedometer(s, d / "run", c);
  const Table h = read_csv(d / "run" / "history.csv",
                           {"strain", "top_stress_Pa", "bottom_stress_Pa", "lateral_stress_Pa", "K0",
                            "kinetic_energy_J", "coordination", "contacts"});
  EXPECT_GT(h.rows(), 10);
  EXPECT_NEAR(h.num("strain").back(), 0.05, 0.001);
  // Strain = platen travel / H0 (H0 = top of the highest grain).
  EXPECT_NEAR(h.num("strain").back(), (r.initial_height_m - h.num("platen_z_m").back()) / r.initial_height_m, 1e-12);
  for (const char* name : {"strain_00.00pct", "strain_02.00pct", "strain_05.00pct"}) {
    const fs::path f = d / "run" / "snapshots" / (std::string(name) + ".h5");
    ASSERT_TRUE(fs::exists(f)) << f;
    EXPECT_TRUE(fs::exists(d / "run" / "snapshots" / (std::string(name) + ".xmf")));
    const Table t = H5Reader(f.string()).read_table("spheres");
    EXPECT_EQ(t.rows(), r.spheres);
    EXPECT_TRUE(t.has("particle") && t.has("vx_m_s") && t.has("r_m"));
  }
  // The initial snapshot holds the input packing.
  const Particles p0 = read_packing_csv(d / "packing.csv", 2180);
  const Table t0 = H5Reader((d / "run" / "snapshots" / "strain_00.00pct.h5").string()).read_table("spheres");
  EXPECT_EQ(t0.num("z_m"), p0.z);
  // The snapshot index (dem/run_folder.hpp), read back the way compare reads it.
  const RunFolder run = read_run_folder(d / "run");
  ASSERT_EQ(run.snapshots.size(), 3u);
  const double requested[3] = {0.0, 0.02, 0.05};
  for (size_t k = 0; k < 3; ++k) {
    const SnapshotEntry& e = run.snapshots[k];
    EXPECT_EQ(e.requested_strain, requested[k]);
    // Taken at the first step at or past the requested strain: one platen step beyond it at most.
    EXPECT_GE(e.axial_strain, requested[k] - 1e-12);
    EXPECT_LE(e.axial_strain, requested[k] + 0.5 * r.time_step / r.initial_height_m + 1e-12);
    EXPECT_TRUE(fs::exists(run.snapshot_path(k))) << e.file;
    EXPECT_EQ(e.bonds.empty(), !s.breakage);  // the bonds sidecar is declared when the run breaks grains
    if (!e.bonds.empty()) {
      EXPECT_TRUE(fs::exists(d / "run" / e.bonds)) << e.bonds;
    }
  }
  EXPECT_EQ(run.history.rows(), h.rows());
  EXPECT_THROW(read_run_folder(d), InputError);  // no snapshots.csv: not a run folder
  fs::remove_all(d);
}

// The stress columns against computations made here. A settled
// frictionless specimen (grains and walls μ = 0, so that no wall friction
// carries weight: no Janssen arching) under a platen creeping at 0.1 mm/s:
//  * bottom - top stress = the grains' weight / floor area, in the dynamic
//    form the creeping platen needs (impulse balance, below: single rows
//    swing by 6 % as the specimen rattles);
//  * at the last row, bottom and lateral stress equal the wall forces of the
//    final snapshot (same state), summed here: Hertz + Tsuji dashpot of each
//    sphere-floor and sphere-cylinder overlap (F = 2/3 kn d + c v,
//    kn = 2 E* sqrt(r d), E* = E / (2 (1 - nu^2)) for a wall of the grains'
//    material, m* = m), over the floor area and the wall area 2 pi R h;
//  * K0 = lateral / mean of top and bottom.
TEST(Oedometer, StressColumnsAtRestAreTheWeightAndTheWallForces) {
  const fs::path d = scratch("stress");
  PluviationOptions po;
  po.cylinder_radius_m = 2.5e-3;
  po.generation_height_m = 6e-3;
  po.target_height_m = 2e-3;
  po.max_time_s = 0.3;
  po.press_to_target_height = false;
  EngineOptions eo;
  const PluviationResult pr = pluviate(po, eo);
  ASSERT_TRUE(pr.settled);
  write_packing_csv(pr.particles, d / "packing.csv");
  Config cfg = Config::from_string(
      "[walls]\ncylinder_radius_m = 2.5e-3\nplaten_friction = 0.0\ncylinder_friction = 0.0\n[contact]\nfriction = 0.0\n"
      "[specimen]\npacking_csv = \"packing.csv\"\n[breakage]\nenabled = false\n"
      "[oedometer]\nplaten_speed_m_s = 1e-4\ntarget_strain = 2e-4\nsnapshot_strains = [2e-4]\n"
      "history_every_steps = 100\n",
      "stress.toml");
  const OedometerSetup s = read_oedometer_config(cfg, d);
  RunControl c;
  c.quiet = true;
  const OedometerSummary r = run_oedometer(s, d / "run", c);
  ASSERT_TRUE(r.finished);
  const Table h = read_csv(d / "run" / "history.csv");
  const Table t = H5Reader((d / "run" / "snapshots" / "strain_00.02pct.h5").string()).read_table("spheres");
  const Material m = s.engine.material;
  const double R = 2.5e-3, area = std::numbers::pi * R * R, g = 9.81;
  const double estar = m.youngs_modulus() / (2 * (1 - m.poisson_ratio * m.poisson_ratio));
  const double le = std::log(s.engine.restitution), beta = -le / std::sqrt(le * le + std::numbers::pi * std::numbers::pi);
  double weight = 0, f_floor = 0, f_wall = 0;
  for (int64_t i = 0; i < t.rows(); ++i) {
    const double x = t.num("x_m")[i], y = t.num("y_m")[i], z = t.num("z_m")[i], rr = t.num("r_m")[i];
    const double mass = m.density_kg_m3 * 4.0 / 3.0 * std::numbers::pi * rr * rr * rr;
    weight += mass * g;
    // Hertz + Tsuji dashpot against a wall (m* = m, R* = r), approach speed v.
    auto wall_force = [&](double delta, double v) {
      const double kn = 2 * estar * std::sqrt(rr * delta);
      return std::max(0.0, 2.0 / 3.0 * kn * delta + 2 * std::sqrt(5.0 / 6.0) * beta * std::sqrt(kn * mass) * v);
    };
    if (z < rr) f_floor += wall_force(rr - z, -t.num("vz_m_s")[i]);
    const double rho = std::hypot(x, y), over = rho + rr - R;
    if (over > 0) f_wall += wall_force(over, (x * t.num("vx_m_s")[i] + y * t.num("vy_m_s")[i]) / rho);
  }
  const double h0 = h.num("platen_z_m")[h.rows() - 1];  // wall height at the last row
  const int64_t last = h.rows() - 1;
  const double top = h.num("top_stress_Pa")[last], bottom = h.num("bottom_stress_Pa")[last], lateral = h.num("lateral_stress_Pa")[last];
  std::printf("last row: top %.6g Pa, bottom %.6g Pa (weight/area %.6g, floor Hertz %.6g), lateral %.6g Pa (wall Hertz %.6g), K0 %.6g\n",
              top, bottom, weight / area, f_floor / area, lateral, f_wall / (2 * std::numbers::pi * R * h0), h.num("K0")[last]);
  EXPECT_GT(f_wall, 0.0);  // a settled specimen presses on the cylinder
  EXPECT_NEAR(bottom, f_floor / area, 1e-4 * bottom);  // measured 1.4e-5 (snapshot velocities half a step apart)
  EXPECT_NEAR(lateral, f_wall / (2 * std::numbers::pi * R * h0), 1e-4 * lateral);
  EXPECT_NEAR(h.num("K0")[last], lateral / (0.5 * (top + bottom)), 1e-12);
  // Impulse balance, the dynamic form of "bottom - top = weight / area": the
  // grains' vertical momentum P obeys dP/dt = (bottom - top) A - W, so
  //   integral over the run of (bottom - top) dt = (W T + P(T) - P(0)) / A,
  // P(0) = 0 (the packing file holds no velocities), P(T) = sum m vz of the
  // final snapshot. The history integrated by the trapezoid rule (rows every
  // 100 steps; row 0 is written before the first force evaluation and reads
  // 0, see bench/dem/RESULTS.md, so from row 1: 1/600 of the run missing).
  double p_end = 0;
  for (int64_t i = 0; i < t.rows(); ++i)
    p_end += m.density_kg_m3 * 4.0 / 3.0 * std::numbers::pi * std::pow(t.num("r_m")[i], 3) * t.num("vz_m_s")[i];
  const auto& time = h.num("time_s");
  const auto& tops = h.num("top_stress_Pa");
  const auto& bots = h.num("bottom_stress_Pa");
  ASSERT_GE(h.rows(), 100);
  double integral = 0, worst = 0;
  for (int64_t q = 2; q < h.rows(); ++q)
    integral += 0.5 * (time[q] - time[q - 1]) * (bots[q] - tops[q] + bots[q - 1] - tops[q - 1]);
  for (int64_t q = 1; q < h.rows(); ++q) worst = std::max(worst, std::abs((bots[q] - tops[q]) / (weight / area) - 1));
  const double span = time.back() - time[1];
  const double expected = (weight * span + p_end) / area;  // P(t1) ~ 0: 100 steps after rest
  std::printf("integral of (bottom - top) dt %.6g Pa s, impulse balance %.6g Pa s (weight alone %.6g); rows within %.1f %% of "
              "weight / area\n", integral, expected, weight * span / area, 100 * worst);
  EXPECT_NEAR(integral, expected, 1e-3 * weight * span / area);  // measured 1.3e-4
  fs::remove_all(d);
}

TEST(Oedometer, ConfigDefaultsAreTheStudysAndUnknownKeysFail) {
  Config empty = Config::from_string("", "empty.toml");
  const OedometerSetup s = read_oedometer_config(empty, ".");
  EXPECT_EQ(s.engine.material.shear_modulus_Pa, 2.2e9);
  EXPECT_EQ(s.engine.material.poisson_ratio, 0.25);
  EXPECT_EQ(s.engine.material.density_kg_m3, 2180);
  EXPECT_EQ(s.engine.friction, 0.5);
  EXPECT_EQ(s.engine.walls.cylinder_radius, 7.5e-3);
  EXPECT_EQ(s.platen_speed, 0.1);
  EXPECT_EQ(s.pluviation.target_height_m, 12.25e-3);
  EXPECT_EQ(s.snapshot_strains, (std::vector<double>{0.0, 0.044, 0.0712, 0.1128, 0.1548}));
  Config typo = Config::from_string("[contact]\nfriciton = 0.3\n", "typo.toml");
  EXPECT_THROW(read_oedometer_config(typo, "."), InputError);
  Config bad = Config::from_string("[run]\nmass_scaling = 0.5\n", "bad.toml");
  EXPECT_THROW(read_oedometer_config(bad, "."), InputError);
}

// Every key of the documented example config is accepted (docs match code).
TEST(Oedometer, ExampleConfigsParse) {
  const char* src = std::getenv("TOMOGRAIN_SOURCE_DIR");
  const fs::path root = src ? fs::path(src) : fs::path(TOMOGRAIN_TEST_SOURCE_DIR);
  for (const char* f : {"dem/examples/oedometer.toml", "dem/examples/demo.toml", "dem/examples/oedometer_calibrated.toml"}) {
    Config cfg = Config::from_file(root / f);
    EXPECT_NO_THROW(read_oedometer_config(cfg, root / "dem/examples")) << f;
  }
}

// The cut between the pair list's parts orders the force sums, so a
// checkpoint keeps it: a chain of 512 overlapping spheres and 512 lone ones
// (cut at row 320 after the first step, not at the default half) saved and
// resumed continues with the same cut and the same bits as the run itself.
TEST(Oedometer, CheckpointKeepsThePartCut) {
  Particles p;
  const double r = 0.68e-3, rho = EngineOptions{}.material.density_kg_m3;
  for (int s = 0; s < 512; ++s) p.append_sphere(s * 1.9 * r, 0, 0, r, rho, s);
  for (int s = 0; s < 512; ++s) p.append_sphere(s * 3 * r, 1.0, 0, r, rho, 512 + s);
  EngineOptions o;
  o.time_step = 1e-8;  // gravity on: a weight among the sums makes their order matter
  o.walls.bottom = o.walls.top = o.walls.cylinder = false;
  Engine a(std::move(p), o);
  a.step();
  ASSERT_EQ(a.part_split(), 320);
  const fs::path dir = scratch("cut");
  save_checkpoint(a, "scene", dir / "c.bin");
  CheckpointState st = load_checkpoint(dir / "c.bin");
  EXPECT_EQ(st.part_split, 320);
  Engine b = resume_engine(st, o);
  EXPECT_EQ(b.part_split(), 320);
  a.run(20);
  b.run(20);
  EXPECT_TRUE(a.particles().fx == b.particles().fx);
  EXPECT_TRUE(a.particles().x == b.particles().x);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace tg::dem
