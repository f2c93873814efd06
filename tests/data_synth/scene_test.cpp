#include "data_synth/scene.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <variant>

#include "core/errors.hpp"
#include "core/io/hdf5.hpp"

using namespace tg::synth;
namespace fs = std::filesystem;

namespace {
fs::path temp_dir() {
  const fs::path d = fs::temp_directory_path() / ("tg_synth_test_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}
}  // namespace

TEST(Scene, PresetsAndStrictKeys) {
  EXPECT_THROW(preset_scene("granite"), tg::InputError);
  for (const auto& n : preset_names()) EXPECT_NO_THROW(preset_scene(n));
  Scene s = preset_scene("zeolite");
  EXPECT_DOUBLE_EQ(s.packing.d50, 1.36);
  EXPECT_DOUBLE_EQ(s.packing.cu, 1.07);
  tg::Config ok = tg::Config::from_string("seed = 9\n[imaging]\nnoise_sigma = 5.0\n[stages]\nstrains = [0.0, 0.1]\nbroken = [0.0, 0.5]\n", "t.toml");
  apply_config(s, ok);
  EXPECT_EQ(s.seed, 9u);
  EXPECT_DOUBLE_EQ(s.imaging.noise_sigma, 5.0);
  EXPECT_EQ(s.stage.strains.size(), 2u);
  tg::Config typo = tg::Config::from_string("[imaging]\nnoise_sigmaa = 5.0\n", "t.toml");
  EXPECT_THROW(apply_config(s, typo), tg::InputError);
  Scene fresh = preset_scene("zeolite");  // 5 default broken fractions vs 2 strains
  tg::Config bad = tg::Config::from_string("[stages]\nstrains = [0.0, 0.1]\n", "t.toml");
  EXPECT_THROW(apply_config(fresh, bad), tg::InputError);
}

TEST(Scene, GridSizeVoxelAndCrop) {
  Scene s = preset_scene("zeolite");
  const double field = 1220 * 0.0123;
  s.size = 256;
  Grid g = make_grid(s);
  EXPECT_NEAR(g.voxel_mm * 256, field, 1e-12);
  EXPECT_NEAR(g.origin_mm[1], -0.5 * field, 1e-12);
  s.size = 0;
  s.voxel_um = 12.3;
  g = make_grid(s);
  EXPECT_EQ(g.shape.nx, 1220);
  s.size = 100;  // crop at full resolution, centred on the axis
  g = make_grid(s);
  EXPECT_EQ(g.shape.nx, 100);
  EXPECT_NEAR(g.origin_mm[2], -50 * 0.0123, 1e-12);
  EXPECT_NEAR(g.origin_mm[0], 0.5 * 12.25 - 50 * 0.0123, 1e-12);
}

TEST(Scene, ReadsDemAndVoxelSphereLists) {
  const fs::path d = temp_dir();
  {
    std::ofstream f(d / "dem.csv");
    f << "x_m,y_m,z_m,r_m,cluster\n0,0,0.001,0.0002,5\n0.0001,0,0.001,0.0002,5\n0.0005,0,0.001,0.0001,6\n";
  }
  Grid g;  // as make_grid lays it: millimetres and the same grid in metres
  g.voxel_mm = 0.01;
  g.origin_mm = {0, -1, -1};
  g.geometry = tg::Geometry::isotropic_m(1e-5);
  g.geometry.origin_m = {0, -1e-3, -1e-3};
  const auto ps = read_particles((d / "dem.csv").string(), g);
  ASSERT_EQ(ps.size(), 2u);
  EXPECT_EQ(ps[0].kind, Kind::cluster);
  EXPECT_EQ(ps[0].pieces.size(), 2u);
  EXPECT_EQ(ps[1].kind, Kind::grain);
  EXPECT_NEAR(ps[1].pieces[0].sphere.c[0], 100, 1e-9);  // z = 1 mm / 0.01 mm
  EXPECT_NEAR(ps[1].pieces[0].sphere.c[2], 150, 1e-9);  // x = (0.5 + 1) mm / 0.01 mm
  EXPECT_NEAR(ps[1].pieces[0].sphere.r, 10, 1e-9);
  {
    std::ofstream f(d / "bad.csv");
    f << "a,b\n1,2\n";
  }
  EXPECT_THROW(read_particles((d / "bad.csv").string(), g), tg::InputError);
  fs::remove_all(d);
}

TEST(Scene, WritesConsistentFilesIndependentOfThreads) {
  const fs::path d = temp_dir();
  Scene s = preset_scene("spheres");
  s.size = 40;
  s.packing.height = s.packing.box_y = s.packing.box_x = 1.6;
  s.imaging.seed = 3;
  const Grid g = make_grid(s);
  const Grains gr = make_grains(s, g);
  ASSERT_GT(gr.particles.size(), 10u);
  const std::string a = (d / "a.h5").string(), b = (d / "b.h5").string();
  omp_set_num_threads(1);
  render_and_write(gr.particles, g, s, a, true, "{}");
  omp_set_num_threads(2);
  render_and_write(gr.particles, g, s, b, true, "{}");
  ASSERT_TRUE(fs::exists(d / "a_truth.csv"));
  tg::H5Reader ra(a), rb(b);
  for (const char* ds : {"/volume", "/labels", "/reconstruction"}) {
    const tg::AnyVolume va = ra.read_volume(ds), vb = rb.read_volume(ds);
    std::visit(
        [&](const auto& x) {
          using V = std::decay_t<decltype(x)>;
          const V& y = std::get<V>(vb);
          ASSERT_EQ(x.bytes(), y.bytes());
          EXPECT_EQ(std::memcmp(x.data(), y.data(), x.bytes()), 0) << ds;
        },
        va);
  }
  EXPECT_TRUE(std::holds_alternative<tg::Volume<uint16_t>>(ra.read_volume("/volume")));
  EXPECT_TRUE(std::holds_alternative<tg::Volume<uint32_t>>(ra.read_volume("/labels")));
  const tg::Table t = ra.read_table("/truth");
  EXPECT_EQ(t.rows(), static_cast<int64_t>(gr.particles.size()));
  EXPECT_TRUE(t.has("volume_mm3"));
  fs::remove_all(d);
}
