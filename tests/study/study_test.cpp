// The study file: what it accepts, what it refuses (naming file and key),
// the plan it makes; content hashes; the yield fit against an analytic curve.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "core/errors.hpp"
#include "core/io/volume_io.hpp"
#include "study/records.hpp"
#include "study/study.hpp"
#include "study/summary.hpp"

namespace fs = std::filesystem;
using namespace tg::study;

namespace {

struct Dir {
  fs::path p;
  Dir() {
    p = fs::temp_directory_path() / ("tg_study_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
                                     "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(p);
    fs::create_directories(p);
  }
  ~Dir() { fs::remove_all(p); }
  void write(const std::string& name, const std::string& text) const { std::ofstream(p / name) << text; }
  void scan(const std::string& name, int64_t nz) const {
    tg::Volume<uint16_t> v(tg::Shape{nz, 8, 8}, tg::Geometry::isotropic_m(10e-6));
    tg::WriteOptions wo;
    wo.progress = false;
    tg::write_volume(v, (p / name).string(), wo);
  }
};

const char* kDem = "[breakage]\nweibull_modulus = 3.0\n";

std::string study(const std::string& extra = "", const std::string& stages = "") {
  return "[study]\nname = \"a\"\n" +
         (stages.empty() ? std::string("[[stage]]\nscan = \"s0.h5\"\nstrain = 0.0\n"
                                       "[[stage]]\nscan = \"s1.h5\"\nstrain = 0.05\nname = \"late\"\n")
                         : stages) +
         extra;
}

// The InputError's message, or "" when `f` does not throw one.
template <class F>
std::string error_of(F f) {
  try {
    f();
  } catch (const tg::InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(Study, ReadsStagesVariantsAndPlans) {
  Dir d;
  d.scan("s0.h5", 8);
  d.scan("s1.h5", 8);
  d.write("dem.toml", kDem);
  d.write("s.toml", study("[segment]\nthreshold = \"local\"\n[dem]\nconfig = \"dem.toml\"\n"
                          "[[dem.variant]]\nname = \"m5\"\nset = { \"breakage.weibull_modulus\" = 5.0 }\n"
                          "[[dem.variant]]\nname = \"m9\"\nset = { \"breakage.new_table.x\" = 2 }\n"));
  const Study s = read_study(d.p / "s.toml");
  ASSERT_EQ(s.stages.size(), 2u);
  EXPECT_EQ(s.stages[0].name, "stage0");
  EXPECT_EQ(s.stages[1].name, "late");
  EXPECT_EQ(s.stages[1].strain, 0.05);
  EXPECT_EQ(s.stages[0].scan, (d.p / "s0.h5").string());  // relative to the study file
  EXPECT_TRUE(s.track_enabled);
  EXPECT_EQ(s.segment["threshold"].value_or(std::string()), "local");
  ASSERT_EQ(s.variants.size(), 2u);
  // Overrides land at their dotted path, the rest of the config is kept.
  const toml::table m5 = toml::parse(dem_config_text(s, s.variants[0]));
  EXPECT_EQ(m5["breakage"]["weibull_modulus"].value_or(0.0), 5.0);
  const toml::table m9 = toml::parse(dem_config_text(s, s.variants[1]));
  EXPECT_EQ(m9["breakage"]["weibull_modulus"].value_or(0.0), 3.0);
  EXPECT_EQ(m9["breakage"]["new_table"]["x"].value_or(int64_t{0}), 2);

  const Plan p = make_plan(s, d.p / "out", 8 * 8 * 8);
  std::vector<std::string> ids;
  for (const auto& st : p.steps) ids.push_back(st.id);
  EXPECT_EQ(ids, (std::vector<std::string>{"analyse-stage0", "analyse-late", "track", "dem-m5", "compare-m5",
                                           "dem-m9", "compare-m9", "summary"}));
  EXPECT_EQ(p.step("track").needs, (std::vector<std::string>{"analyse-stage0", "analyse-late"}));
  EXPECT_TRUE(p.step("track").inputs.empty());  // the labels only: the scans are not read
  EXPECT_EQ(p.step("compare-m9").needs, (std::vector<std::string>{"dem-m9"}));
  EXPECT_EQ(p.step("summary").needs.size(), 5u);
  EXPECT_EQ(p.record(p.step("track")), d.p / "out" / ".run" / "track.json");
  // Every step's needs come before it.
  for (size_t i = 0; i < p.steps.size(); ++i)
    for (const auto& n : p.steps[i].needs) {
      size_t j = 0;
      while (p.steps[j].id != n) ++j;
      EXPECT_LT(j, i) << p.steps[i].id << " needs " << n;
    }
  EXPECT_NE(error_of([&] { (void)p.step("nope"); }).find("no step 'nope'"), std::string::npos);
}

// [track] scans = true: the track step reads the stages' scans (so a changed scan re-runs it).
TEST(Study, TrackScansAreTheStepsInputs) {
  Dir d;
  d.scan("s0.h5", 8);
  d.scan("s1.h5", 8);
  d.write("s.toml", study("[track]\nscans = true\nmin_overlap = 0.3\n"));
  const Study s = read_study(d.p / "s.toml");
  EXPECT_TRUE(s.track_scans);
  EXPECT_FALSE(s.track.contains("scans"));  // not passed on as an option of its own
  EXPECT_TRUE(s.track.contains("min_overlap"));
  const Plan p = make_plan(s, d.p / "out", 8 * 8 * 8);
  EXPECT_EQ(p.step("track").inputs, (std::vector<fs::path>{d.p / "s0.h5", d.p / "s1.h5"}));
}

TEST(Study, RefusesBadFilesNamingFileAndKey) {
  Dir d;
  d.scan("s0.h5", 8);
  d.scan("s1.h5", 8);
  d.scan("big.h5", 9);
  d.write("dem.toml", kDem);
  const std::string two = "[[stage]]\nscan = \"s0.h5\"\nstrain = 0.0\n[[stage]]\nscan = \"s1.h5\"\nstrain = ";
  struct Case {
    std::string text, expect;
  } cases[] = {
      {study("[nonsense]\nx = 1\n"), "unknown key 'nonsense'"},
      {study("[study]\n"), "study"},  // a table defined twice: toml++'s own error, with line and column
      {"[study]\ngrain_diameter_um = -3\n" + two + "0.1\n", "study.grain_diameter_um must be positive"},
      {"[study]\nvoxel_size = 3\n" + two + "0.1\n", "unknown key 'study.voxel_size'"},
      {"[[stage]]\nscan = \"missing.h5\"\nstrain = 0.0\n", "stage[0].scan 'missing.h5': no such file"},
      {two + "0.0\n", "stage[1].strain must increase"},
      {two + "0.1\n[[stage]]\nscan = \"big.h5\"\nstrain = 0.2\n", "stage[2].scan has shape"},
      {"[[stage]]\nscan = \"s0.h5\"\n", "stage[0].strain is missing"},
      {"[[stage]]\nscan = \"s0.h5\"\nstrain = 0.0\nstrian = 1\n", "unknown key 'stage[0].strian'"},
      {two + "0.1\n[dem]\nconfig = \"nope.toml\"\n", "dem.config 'nope.toml': no such file"},
      {two + "0.1\n[dem]\nconfig = \"dem.toml\"\n[[dem.variant]]\nname = \"a b\"\n", "dem.variant[0].name"},
      {two + "0.1\n[dem]\nconfig = \"dem.toml\"\n[[dem.variant]]\nname = \"x\"\nset = { \"breakage.weibull_modulus.z\" = 1 }\n",
       "weibull_modulus is not a table"},
      {two + "0.1\n[compare]\nferet = \"60\"\n", "compare needs a DEM"},
      {"[[stage]]\nscan = \"s0.h5\"\nstrain = 0.0\n[track]\nenabled = true\n", "track.enabled needs two or more"},
      {two + "0.1\n[track]\nscans = [\"s0.h5\", \"s1.h5\"]\n", "track.scans must be true or false"},
      {"[study]\nname = \"x\"\n", "no [[stage]]"},
  };
  for (const auto& c : cases) {
    d.write("bad.toml", c.text);
    const std::string e = error_of([&] { (void)read_study(d.p / "bad.toml"); });
    EXPECT_NE(e.find("bad.toml"), std::string::npos) << c.text << "\n-> " << e;
    EXPECT_NE(e.find(c.expect), std::string::npos) << c.text << "\n-> " << e;
  }
}

TEST(Study, ContentHashFollowsContentNotTime) {
  Dir d;
  d.write("a.bin", "hello");
  d.write("b.bin", "hello");
  HashCache h(d.p / ".run");
  const std::string ha = h.hash(d.p / "a.bin");
  EXPECT_EQ(ha, h.hash(d.p / "b.bin"));  // same bytes, same hash
  EXPECT_EQ(ha.size(), 16u);
  d.write("a.bin", "hellO");
  fs::last_write_time(d.p / "a.bin", fs::last_write_time(d.p / "a.bin") + std::chrono::seconds(2));
  EXPECT_NE(h.hash(d.p / "a.bin"), ha);
  // A folder (TIFF slices): names and bytes in order.
  fs::create_directories(d.p / "f");
  std::ofstream(d.p / "f" / "s1.tif") << "x";
  const std::string hf = h.hash(d.p / "f");
  std::ofstream(d.p / "f" / "s2.tif") << "y";
  EXPECT_NE(h.hash(d.p / "f"), hf);
  // The cache survives a new process (read back from DIR/.run/hashes.json).
  h.save();
  HashCache again(d.p / ".run");
  EXPECT_EQ(again.hash(d.p / "b.bin"), ha);
  EXPECT_EQ(hash_strings({"a", "bc"}) == hash_strings({"ab", "c"}), false);  // parts are delimited
}

TEST(Study, RecordsAndLocks) {
  Dir d;
  const fs::path r = d.p / ".run" / "x.json";
  EXPECT_EQ(recorded_key(r), "");
  write_record(r, "x", "0123", 1.5);
  EXPECT_EQ(recorded_key(r), "0123");
  std::ofstream(r) << "{ broken";
  EXPECT_EQ(recorded_key(r), "");  // a damaged record is no record: the step runs again
  StepLock a(d.p / ".run" / "x.lock");
  EXPECT_NE(error_of([&] { StepLock b(d.p / ".run" / "x.lock"); }).find("another process"), std::string::npos);
}

TEST(Study, YieldOfABilinearCurve) {
  // strain = 0.01 log10(s / 0.1) up to 2 MPa, then 0.15 per decade: the two
  // lines meet at exactly 2 MPa.
  std::vector<double> e, s;
  const double ey = 0.01 * std::log10(2.0 / 0.1);
  for (double ls = std::log10(0.12); ls < std::log10(20.0); ls += 0.05) {
    const double x = std::pow(10.0, ls);
    s.push_back(x);
    e.push_back(x <= 2.0 ? 0.01 * std::log10(x / 0.1) : ey + 0.15 * std::log10(x / 2.0));
  }
  EXPECT_NEAR(yield_stress_mpa(e, s), 2.0, 1e-6);  // both sides fit exactly
  // Below the floor, falling stress and too few points are left out / NaN.
  EXPECT_TRUE(std::isnan(yield_stress_mpa({0.01, 0.02}, {0.5, 0.6})));
  // One straight line (no yield): any split's lines meet nowhere or outside the data.
  std::vector<double> e1, s1;
  for (double ls = -0.9; ls < 1.0; ls += 0.1) {
    s1.push_back(std::pow(10.0, ls));
    e1.push_back(0.02 * ls + 1e-4 * std::sin(40 * ls));
  }
  EXPECT_TRUE(std::isnan(yield_stress_mpa(e1, s1))) << "a straight line has no knee";
  // A curve that stiffens (0.15 strain per decade, then 0.01: the first
  // curve's branches the other way round) has no yield either.
  std::vector<double> e2;
  for (double x : s) e2.push_back(x <= 2.0 ? 0.15 * std::log10(x / 0.1) : 0.15 * std::log10(20.0) + 0.01 * std::log10(x / 2.0));
  EXPECT_TRUE(std::isnan(yield_stress_mpa(e2, s))) << yield_stress_mpa(e2, s);
  // A soft branch 1.6 times as steep as the stiff one is a knee; 1.4 times is not.
  for (const double ratio : {1.6, 1.4}) {
    std::vector<double> e3;
    for (double x : s) e3.push_back(x <= 2.0 ? 0.01 * std::log10(x / 0.1) : ey + ratio * 0.01 * std::log10(x / 2.0));
    const double y3 = yield_stress_mpa(e3, s);
    if (ratio > 1.5) EXPECT_NEAR(y3, 2.0, 1e-6);
    else EXPECT_TRUE(std::isnan(y3)) << y3;
  }
}
