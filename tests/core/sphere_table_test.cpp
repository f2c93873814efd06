// core/sphere_table: the one reader and writer of DEM sphere tables.
#include "core/sphere_table.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "core/errors.hpp"
#include "core/io/hdf5.hpp"

namespace tg {
namespace {
namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("tg_spheres_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d / name;
}

TEST(SphereTable, CsvAndHdf5RoundTripKeepParticleIds) {
  SphereTable s;
  s.push_back(1e-3, -2e-3, 0.68e-3, 0.68e-3, 7);
  s.push_back(0.1 / 3, 2e-3 / 7, 5e-3, 0.6123456789e-3, 7);  // one fragment: two spheres, one id
  s.push_back(0, 0, 1e-2, 1e-4, 9);
  write_spheres(s, scratch("s.csv"));
  const SphereTable c = read_spheres(scratch("s.csv").string());
  EXPECT_EQ(c.x_m, s.x_m);
  EXPECT_EQ(c.z_m, s.z_m);
  EXPECT_EQ(c.r_m, s.r_m);
  EXPECT_EQ(c.particle, s.particle);
  EXPECT_EQ(particle_count(c), 2);
  {
    H5Writer w(scratch("s.h5").string());
    w.write_table("spheres", spheres_to_table(s));
    w.commit();
  }
  const SphereTable h = read_spheres(scratch("s.h5").string());  // the group found by its x_m column
  EXPECT_EQ(h.particle, s.particle);
  EXPECT_EQ(h.y_m, s.y_m);
  EXPECT_NE(h.source.find("spheres"), std::string::npos);
}

TEST(SphereTable, ClusterIsASynonymAndNoIdMeansOneParticlePerSphere) {
  { std::ofstream(scratch("c.csv")) << "x_m,y_m,z_m,r_m,cluster\n0,0,1,0.5,4\n0,0,2,0.5,4\n"; }
  EXPECT_EQ(read_spheres(scratch("c.csv").string()).particle, (std::vector<int64_t>{4, 4}));
  { std::ofstream(scratch("n.csv")) << "x_m,y_m,z_m,r_m,vx_m_s\n0,0,1,0.5,3\n0,0,2,0.5,3\n"; }
  EXPECT_EQ(read_spheres(scratch("n.csv").string()).particle, (std::vector<int64_t>{0, 1}));
}

TEST(SphereTable, BadRowsNameFileAndRow) {
  auto expect_error = [&](const std::string& body, const std::string& needle) {
    { std::ofstream(scratch("b.csv")) << body; }
    try {
      read_spheres(scratch("b.csv").string());
      ADD_FAILURE() << "no error for " << body;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("b.csv"), std::string::npos) << e.what();
    }
  };
  expect_error("x_m,y_m,z_m,r_m\n0,0,1,0.5\n0,0,1,-1\n", "row 3: r_m must be > 0");
  expect_error("x_m,y_m,z_m,r_m\n0,nan,1,0.5\n", "row 2: sphere position must be finite");
  expect_error("x_m,y_m,z_m,r_m,particle\n0,0,1,0.5,1.5\n", "row 2: particle id must be an integer");
  expect_error("x_m,y_m,z_m,r_m\n", "no spheres");
  expect_error("x_m,y_m,r_m\n0,0,1\n", "missing column 'z_m'");
}

}  // namespace
}  // namespace tg
