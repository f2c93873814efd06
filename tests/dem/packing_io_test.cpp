#include "dem/packing_io.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "core/errors.hpp"

namespace tg::dem {
namespace {
namespace fs = std::filesystem;

TEST(PackingIO, RoundTripIsExact) {
  Particles p;
  p.append_sphere(1e-3, -2e-3, 0.68e-3, 0.68e-3, 2180, 0);
  p.append_sphere(0.1 / 3, 2e-3 / 7, 5e-3, 0.6123456789e-3, 2180, 1);
  const fs::path f = fs::temp_directory_path() / ("tg_pack_" + std::to_string(::getpid()) + ".csv");
  write_packing_csv(p, f);
  std::ifstream is(f);
  std::string header;
  std::getline(is, header);
  EXPECT_EQ(header, "x_m,y_m,z_m,r_m,particle");
  const Particles q = read_packing_csv(f, 2180);
  EXPECT_EQ(q.x, p.x);
  EXPECT_EQ(q.y, p.y);
  EXPECT_EQ(q.z, p.z);
  EXPECT_EQ(q.r, p.r);
  EXPECT_EQ(q.particle, p.particle);
  EXPECT_NEAR(q.m[0], 2180 * 4.0 / 3.0 * std::numbers::pi * std::pow(0.68e-3, 3), 1e-18);
  EXPECT_NEAR(q.inertia[0], 0.4 * q.m[0] * 0.68e-3 * 0.68e-3, 1e-24);
  fs::remove(f);
}

TEST(PackingIO, RejectsBadRadiusAndMissingColumns) {
  const fs::path f = fs::temp_directory_path() / ("tg_packbad_" + std::to_string(::getpid()) + ".csv");
  { std::ofstream(f) << "x_m,y_m,z_m,r_m\n0,0,0.001,0.0005\n0,0,0.003,-1\n"; }
  try {
    read_packing_csv(f, 2180);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("row 3"), std::string::npos) << e.what();  // names the line
  }
  { std::ofstream(f) << "x_m,y_m,r_m\n0,0,0.001\n"; }
  EXPECT_THROW(read_packing_csv(f, 2180), InputError);
  fs::remove(f);
}

}  // namespace
}  // namespace tg::dem
