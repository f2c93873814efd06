// The oedometer scene: config strictness, run folder contents, and restart
// from a checkpoint continuing bit for bit.
#include "dem/oedometer.hpp"
#include "dem/run_folder.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#include "core/errors.hpp"
#include "core/io/hdf5.hpp"
#include "core/table.hpp"
#include "dem/packing_io.hpp"

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
  EXPECT_EQ(fields, 30);
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
    if (!e.bonds.empty()) EXPECT_TRUE(fs::exists(d / "run" / e.bonds)) << e.bonds;
  }
  EXPECT_EQ(run.history.rows(), h.rows());
  EXPECT_THROW(read_run_folder(d), InputError);  // no snapshots.csv: not a run folder
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
  for (const char* f : {"dem/examples/oedometer.toml", "dem/examples/demo.toml"}) {
    Config cfg = Config::from_file(root / f);
    EXPECT_NO_THROW(read_oedometer_config(cfg, root / "dem/examples")) << f;
  }
}

}  // namespace
}  // namespace tg::dem
