// The calibration objective (dem/calibration/objective.hpp) on hand-computed
// cases, and the target file's checks.
#include "dem/calibration/objective.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "core/errors.hpp"

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
