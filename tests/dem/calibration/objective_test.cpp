// The calibration objective (dem/calibration/objective.hpp) on hand-computed
// cases, the target file's checks, and the crush tests behind the crush term.
#include "dem/calibration/objective.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "core/errors.hpp"
#include "dem/breakage/crush.hpp"
#include "dem/calibration/calibrate.hpp"

namespace cal = tg::dem::calibration;
namespace fs = std::filesystem;

namespace {
struct TmpDir {
  fs::path p;
  TmpDir() {
    p = fs::temp_directory_path() / ("tg_calib_obj_" + std::to_string(::getpid()));
    fs::remove_all(p);
    fs::create_directories(p);
  }
  ~TmpDir() { fs::remove_all(p); }
  fs::path write(const std::string& name, const std::string& text) const {
    std::ofstream(p / name) << text;
    return p / name;
  }
};

std::string error_of(const fs::path& f) {
  try {
    cal::read_target(f);
  } catch (const tg::InputError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(CalibrationObjective, HandComputedMisfits) {
  cal::Target t;
  t.curve_strain = {0.02, 0.04};
  t.curve_stress_Pa = {1e6, 2e6};
  t.broken_strain = {0.04};
  t.broken_fraction = {0.25};
  t.w_curve = 1;
  t.w_broken = 2;
  tg::Table h;
  h.add("strain", {0.0, 0.03, 0.05});
  h.add("top_stress_Pa", {0.0, 3e6, 3e6});
  h.add("grains_broken", {0, 10, 30});
  // Run at 0.02: 2 MPa (vs 1), at 0.04: 3 MPa (vs 2): RMS diff 1 MPa over
  // RMS target sqrt(2.5) MPa. Broken at 0.04: 20 / 100 = 0.2 vs 0.25.
  const cal::RunScore s = cal::score_run(t, h, 100);
  EXPECT_NEAR(s.curve_misfit, 1 / std::sqrt(2.5), 1e-12);
  EXPECT_NEAR(s.broken_misfit, 0.05, 1e-12);
  EXPECT_NEAR(s.objective, 1 / std::sqrt(2.5) + 2 * 0.05, 1e-12);
  EXPECT_DOUBLE_EQ(s.final_broken_fraction, 0.3);
  EXPECT_DOUBLE_EQ(s.peak_stress_Pa, 3e6);
  // No yield in three points: a yield target scores 1.
  t.yield_stress_Pa = 2e6;
  EXPECT_NEAR(cal::score_run(t, h, 100).objective, s.objective + 1, 1e-12);
  // A run short of the largest target strain has no objective.
  t.curve_strain = {0.02, 0.06};
  EXPECT_TRUE(std::isnan(cal::score_run(t, h, 100).objective));
}

// A loading history that reaches 2 MPa at row 1, drops below it, and reaches
// 4 MPa exactly at row 3 (the rows the at-stress targets read).
static tg::Table stress_history() {
  tg::Table h;
  h.add("strain", {0.0, 0.02, 0.04, 0.06});
  h.add("top_stress_Pa", {0.0, 2.5e6, 1.9e6, 4.0e6});
  h.add("grains_broken", {0, 4, 12, 25});
  return h;
}

TEST(CalibrationObjective, BrokenAtStressHandComputed) {
  cal::Target t;
  t.broken_stress_Pa = {2e6, 4e6};
  t.broken_fraction_at_stress = {0.05, 0.3};
  t.w_broken_stress = 2;
  tg::Table h = stress_history();
  // 2 MPa is first reached at row 1 (4 / 100 = 0.04 vs 0.05), 4 MPa at row 3
  // (exactly: 0.25 vs 0.3): RMS of (-0.01, -0.05).
  const cal::RunScore s = cal::score_run(t, h, 100);
  EXPECT_NEAR(s.broken_stress_misfit, std::sqrt((0.01 * 0.01 + 0.05 * 0.05) / 2), 1e-12);
  EXPECT_NEAR(s.objective, 2 * s.broken_stress_misfit, 1e-12);
  // A stress the run never reaches misses by 1.
  t.broken_stress_Pa = {5e6};
  t.broken_fraction_at_stress = {0.3};
  EXPECT_NEAR(cal::score_run(t, h, 100).broken_stress_misfit, 1.0, 1e-12);
}

TEST(CalibrationObjective, BondsAtStressHandComputed) {
  cal::Target t;
  t.broken_stress_Pa = {2e6, 4e6};
  t.bonds_broken_at_stress = {299, 9999};
  t.w_bonds = 3;
  tg::Table h = stress_history();
  h.add("bonds_broken", {0, 599, 800, 999});
  // Rows 1 and 3: 600 / 300 = 2 (log10 0.30103), 1000 / 10000 = 0.1 (-1,
  // the cap). No grain target given: only the bond term counts.
  const cal::RunScore s = cal::score_run(t, h, 100);
  const double l2 = std::log10(2.0);
  EXPECT_NEAR(s.bonds_misfit, std::sqrt((l2 * l2 + 1.0) / 2), 1e-12);
  EXPECT_DOUBLE_EQ(s.broken_stress_misfit, 0.0);
  EXPECT_NEAR(s.objective, 3 * s.bonds_misfit, 1e-12);
  // Exactly on target scores 0; a stress never reached scores 1.
  t.bonds_broken_at_stress = {599, 999};
  EXPECT_NEAR(cal::score_run(t, h, 100).bonds_misfit, 0.0, 1e-12);
  t.broken_stress_Pa = {2e6, 5e6};
  EXPECT_NEAR(cal::score_run(t, h, 100).bonds_misfit, std::sqrt(0.5), 1e-12);
  // Without the column (breakage off) the target is an error, not a zero.
  tg::Table h2;
  h2.add("strain", {0.0, 0.06});
  h2.add("top_stress_Pa", {0.0, 4e6});
  h2.add("grains_broken", {0, 1});
  EXPECT_THROW(cal::score_run(t, h2, 100), tg::InputError);
}

TEST(CalibrationObjective, ReadsBondsAtStressTarget) {
  TmpDir d;
  const cal::Target t = cal::read_target(
      d.write("b.toml", "[target]\nbroken_at_stress_Pa = [2e6, 4e6]\nbonds_broken_at_stress = [300, 10000]\n"
                        "[weights]\nbonds_at_stress = 0.5\n"));
  ASSERT_EQ(t.bonds_broken_at_stress.size(), 2u);
  EXPECT_DOUBLE_EQ(t.bonds_broken_at_stress[1], 10000);
  EXPECT_TRUE(t.broken_fraction_at_stress.empty());
  EXPECT_DOUBLE_EQ(t.w_bonds, 0.5);
  EXPECT_NE(error_of(d.write("c.toml", "[target]\nbroken_at_stress_Pa = [2e6, 4e6]\nbonds_broken_at_stress = [300]\n"))
                .find("one value per target.broken_at_stress_Pa"),
            std::string::npos);
  EXPECT_NE(error_of(d.write("e.toml", "[target]\nbroken_at_stress_Pa = [2e6]\nbonds_broken_at_stress = [-3]\n"))
                .find("bond counts >= 0"),
            std::string::npos);
  // Stresses with neither list: an error naming the missing list.
  EXPECT_NE(error_of(d.write("f.toml", "[target]\nbroken_at_stress_Pa = [2e6]\n")).find("target.broken_fraction_at_stress"),
            std::string::npos);
}

TEST(CalibrationObjective, ReadsBrokenAtStressTarget) {
  TmpDir d;
  const cal::Target t = cal::read_target(d.write(
      "s.toml", "[target]\nbroken_at_stress_Pa = [2e6, 4e6]\nbroken_fraction_at_stress = [0.022, 0.31]\n"
                "[weights]\nbroken_at_stress = 0.5\n"));
  ASSERT_EQ(t.broken_stress_Pa.size(), 2u);
  EXPECT_DOUBLE_EQ(t.broken_stress_Pa[1], 4e6);
  EXPECT_DOUBLE_EQ(t.broken_fraction_at_stress[0], 0.022);
  EXPECT_DOUBLE_EQ(t.w_broken_stress, 0.5);
  EXPECT_NE(error_of(d.write("u.toml", "[target]\nbroken_at_stress_Pa = [2e6]\nbroken_fraction_at_stress = []\n"))
                .find("one value per target.broken_at_stress_Pa"),
            std::string::npos);
  EXPECT_NE(error_of(d.write("v.toml", "[target]\nbroken_at_stress_Pa = [-1.0]\nbroken_fraction_at_stress = [0.1]\n"))
                .find("stresses > 0"),
            std::string::npos);
}

TEST(CalibrationObjective, CrushTermHandComputed) {
  cal::Target t;
  t.curve_strain = {0.03};
  t.curve_stress_Pa = {2e6};
  t.crush_bonds_broken = 120;
  t.w_crush = 0.5;
  tg::Table h;
  h.add("strain", {0.0, 0.03});
  h.add("top_stress_Pa", {0.0, 3e6});
  // Curve: |3 - 2| / 2 = 0.5. Crush: run mean 150 vs 120 -> 30 / 120 = 0.25,
  // weighted 0.5 -> 0.125; 90 is as far below: the same term.
  const cal::RunScore s = cal::score_run(t, h, 10, 150.0);
  EXPECT_NEAR(s.curve_misfit, 0.5, 1e-12);
  EXPECT_NEAR(s.crush_misfit, 0.25, 1e-12);
  EXPECT_DOUBLE_EQ(s.crush_bonds_broken, 150.0);
  EXPECT_NEAR(s.objective, 0.5 + 0.125, 1e-12);
  EXPECT_NEAR(cal::score_run(t, h, 10, 90.0).objective, 0.625, 1e-12);
  // The crush tests failed (NaN): no objective, not a silent zero term.
  EXPECT_TRUE(std::isnan(cal::score_run(t, h, 10).objective));
  // Without a crush target the mean is ignored.
  t.crush_bonds_broken = 0;
  EXPECT_NEAR(cal::score_run(t, h, 10, 150.0).objective, 0.5, 1e-12);
}

TEST(CalibrationObjective, ReadsCrushTarget) {
  TmpDir d;
  const auto t = cal::read_target(d.write("c.toml", "[crush]\nbonds_broken = 134.5\ngrains = 12\n[weights]\ncrush = 2.0\n"));
  EXPECT_DOUBLE_EQ(t.crush_bonds_broken, 134.5);
  EXPECT_EQ(t.crush_grains, 12);
  EXPECT_DOUBLE_EQ(t.crush_diameter_m, 1.2e-3);  // documented defaults
  EXPECT_DOUBLE_EQ(t.crush_travel, 0.4);
  EXPECT_DOUBLE_EQ(t.w_crush, 2.0);
  EXPECT_NE(error_of(d.write("n.toml", "[crush]\nbonds_broken = -3.0\n")).find("crush.bonds_broken must be > 0"),
            std::string::npos);
  EXPECT_NE(error_of(d.write("k.toml", "[crush]\nbonds_broken = 100.0\nseeds = 30\n")).find("unknown key 'crush.seeds'"),
            std::string::npos);
  EXPECT_NE(error_of(d.write("g.toml", "[crush]\nbonds_broken = 100.0\ngrains = 0\n")).find("crush.grains must be >= 1"),
            std::string::npos);
}

TEST(CalibrationObjective, ExactRunScoresZero) {
  cal::Target t;
  t.curve_strain = {0.01, 0.02, 0.03};
  t.curve_stress_Pa = {1e5, 4e5, 9e5};
  tg::Table h;
  h.add("strain", {0.0, 0.01, 0.02, 0.03});
  h.add("top_stress_Pa", {0.0, 1e5, 4e5, 9e5});
  EXPECT_DOUBLE_EQ(cal::score_run(t, h, 10).objective, 0.0);
}

TEST(CalibrationObjective, ReadsTargetFileAndCsv) {
  TmpDir d;
  d.write("curve.csv", "strain,stress_Pa\n0.01,1e5\n0.02,3e5\n");
  const auto t = cal::read_target(d.write("t.toml",
                                           "[target]\nstress_strain_csv = \"curve.csv\"\nyield_stress_Pa = 2e6\n"
                                           "[weights]\nyield_stress = 0.5\n"
                                           "[parameters]\nsigma_t0_Pa = [1e6, 3e7]\n"));
  EXPECT_EQ(t.curve_stress_Pa, (std::vector<double>{1e5, 3e5}));
  EXPECT_DOUBLE_EQ(t.w_yield, 0.5);
  EXPECT_DOUBLE_EQ(t.parameters[0].max, 3e7);
  EXPECT_DOUBLE_EQ(t.parameters[1].min, cal::default_parameters()[1].min);
  EXPECT_DOUBLE_EQ(t.largest_strain(), 0.02);
  // A run's history.csv is a curve target as it is (top_stress_Pa).
  const auto h = cal::read_target(d.write("h.csv", "step,strain,top_stress_Pa\n0,0,0\n10,0.01,2e5\n"));
  EXPECT_EQ(h.curve_stress_Pa, (std::vector<double>{0, 2e5}));
}

TEST(CalibrationObjective, BadTargetsNameFileAndProblem) {
  TmpDir d;
  EXPECT_NE(error_of(d.write("a.toml", "[target]\nyield_stres_Pa = 2e6\n")).find("unknown key 'target.yield_stres_Pa'"),
            std::string::npos);
  EXPECT_NE(error_of(d.write("b.toml", "[weights]\nstress_strain = 1.0\n")).find("no target"), std::string::npos);
  EXPECT_NE(error_of(d.write("c.csv", "strain,stress_Pa\n")).find("no rows"), std::string::npos);
  EXPECT_NE(error_of(d.write("d.toml", "[target]\nyield_stress_Pa = 2e6\n[parameters]\nsigma_t0_Pa = [2e7, 1e7]\n"))
                .find("parameters.sigma_t0_Pa must be [min, max]"),
            std::string::npos);
  EXPECT_NE(error_of(d.write("e.csv", "strain,stress_Pa\n0.02,1\n0.01,2\n")).find("must increase"), std::string::npos);
  EXPECT_NE(error_of(d.write("f.toml", "[target]\nbroken_strain = [0.1]\nbroken_fraction = [1.5]\n")).find("[0, 1]"),
            std::string::npos);
  EXPECT_NE(error_of(d.p / "missing.toml").find("not found"), std::string::npos);
}

TEST(CalibrationObjective, InterpolatesAndClamps) {
  const std::vector<double> x{0, 1, 3}, y{0, 10, 30};
  EXPECT_DOUBLE_EQ(cal::interpolate(x, y, 2.0), 20.0);
  EXPECT_DOUBLE_EQ(cal::interpolate(x, y, -1.0), 0.0);
  EXPECT_DOUBLE_EQ(cal::interpolate(x, y, 5.0), 30.0);
  EXPECT_DOUBLE_EQ(cal::interpolate(x, y, 1.0), 10.0);
}

// The crush term's tests (calibrate.hpp): each candidate's mean is the mean
// of run_crush over strength seeds 1..grains with the target's diameter and
// travel, d0 = 0 read as the crush diameter, and the same for any threads.
TEST(CalibrationObjective, CrushMeanIsTheCrushTestsMean) {
  cal::Target t;
  t.crush_grains = 2;
  t.crush_diameter_m = 1.2e-3;
  t.crush_travel = 0.08;  // past the split and the first bond breaks (dozens), < 1 s a test
  std::vector<tg::dem::OedometerSetup> s(3);
  for (auto& x : s) x.breakage_options.min_time_step_s = 2e-8;
  s[0].breakage_options.bond.radius_multiplier = 0.9;
  s[1].breakage_options.bond.radius_multiplier = 1.6;
  s[1].breakage_options.strength.sigma_t0_Pa = 8e6;
  s[2].breakage_options.fines_overlap = 2;  // every test of this setup throws
  const std::vector<cal::CrushMean> m = cal::crush_bonds_broken(t, s, 2);
  ASSERT_EQ(m.size(), 3u);
  double direct = 0;
  for (uint64_t seed : {1, 2}) {
    tg::dem::breakage::CrushOptions c;
    c.diameter_m = 1.2e-3;
    c.final_travel_fraction = 0.08;
    c.engine = s[1].engine;
    c.breakage = s[1].breakage_options;
    c.breakage.strength.d0_m = 1.2e-3;
    c.breakage.strength.seed = seed;
    direct += static_cast<double>(tg::dem::breakage::run_crush(c).final_record.bonds_broken);
  }
  EXPECT_GT(direct, 0);  // the test breaks bonds: the term measures something
  EXPECT_EQ(m[1].bonds_broken, direct / 2);  // 2 threads over the setups = one by one, bit for bit
  EXPECT_EQ(m[1].failed, 0);
  EXPECT_TRUE(m[1].first_failure.empty());
  // A setup whose tests fail has no mean, and says which seed failed first and why.
  EXPECT_TRUE(std::isnan(m[2].bonds_broken));
  EXPECT_EQ(m[2].failed, 2);
  EXPECT_EQ(m[2].first_failure, "strength seed 1: breakage: fines overlap must be in (0, 1)");
}
