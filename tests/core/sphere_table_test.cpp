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

// Writes body to `file` and expects read_spheres to refuse it with an
// InputError naming the file and holding `needle`.
void expect_error(const std::string& file, const std::string& body, const std::string& needle) {
  { std::ofstream(scratch(file)) << body; }
  try {
    read_spheres(scratch(file).string());
    ADD_FAILURE() << "no error for " << body;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(file), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
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
  expect_error("b.csv", "x_m,y_m,z_m,r_m\n0,0,1,0.5\n0,0,1,-1\n", "row 3: r_m must be > 0");
  expect_error("b.csv", "x_m,y_m,z_m,r_m\n0,nan,1,0.5\n", "row 2: sphere position must be finite");
  expect_error("b.csv", "x_m,y_m,z_m,r_m,particle\n0,0,1,0.5,1.5\n", "row 2: particle id must be an integer");
  expect_error("b.csv", "x_m,y_m,z_m,r_m\n", "no spheres");
  expect_error("b.csv", "x_m,y_m,r_m\n0,0,1\n", "missing column 'z_m'");
}

// A LAMMPS/LIGGGHTS text dump as `dump custom` writes it from two MPI ranks
// (rows in rank order, not id order), two timesteps.
const char* kDump =
    "ITEM: TIMESTEP\n100\nITEM: NUMBER OF ATOMS\n3\nITEM: BOX BOUNDS ff ff ff\n"
    "-0.0075 0.0075\n-0.0075 0.0075\n0 0.03\n"
    "ITEM: ATOMS id type x y z radius mol vx\n"
    "3 1 0.001 0.002 0.003 0.0007 9 0.5\n1 1 -0.001 0 0.0007 0.00068 4 0\n2 1 0 0.001 0.002 0.0006 4 0\n"
    "ITEM: TIMESTEP\n200\nITEM: NUMBER OF ATOMS\n3\nITEM: BOX BOUNDS ff ff ff\n"
    "-0.0075 0.0075\n-0.0075 0.0075\n0 0.03\n"
    "ITEM: ATOMS id type x y z radius mol vx\n"
    "2 1 0 0.001 0.0019 0.0006 4 0\n3 1 0.001 0.002 0.0029 0.0007 9 0.5\n1 1 -0.001 0 0.0006 0.00068 4 0\n";

TEST(SphereTable, LammpsDumpTimestepInIdOrderWithMolAsParticle) {
  { std::ofstream(scratch("a.dump")) << kDump; }
  const std::string f = scratch("a.dump").string();
  const SphereTable t = read_spheres(f + ":200");
  EXPECT_EQ(t.x_m, (std::vector<double>{-0.001, 0, 0.001}));  // ids 1, 2, 3
  EXPECT_EQ(t.z_m, (std::vector<double>{0.0006, 0.0019, 0.0029}));
  EXPECT_EQ(t.r_m, (std::vector<double>{0.00068, 0.0006, 0.0007}));
  EXPECT_EQ(t.particle, (std::vector<int64_t>{4, 4, 9}));
  EXPECT_EQ(read_spheres(f + ":100").z_m, (std::vector<double>{0.0007, 0.002, 0.003}));
  // Several timesteps and none named, or one that is not there: say which exist.
  try {
    read_spheres(f);
    ADD_FAILURE() << "no error for a dump of two timesteps";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("2 timesteps (100 to 200): name one as"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_spheres(f + ":300"), InputError);
  { std::ofstream(scratch("b.csv")) << "x_m,y_m,z_m,r_m\n0,0,1,0.5\n"; }
  EXPECT_THROW(read_spheres(scratch("b.csv").string() + ":5"), InputError);  // a timestep of a CSV
}

TEST(SphereTable, LammpsDumpScaledPositionsDiameterAndUnits) {
  // xs ys zs in the box [0, 0.01] x [0, 0.02] x [-0.01, 0.03]; diameter; no id, no mol.
  { std::ofstream(scratch("s.dump")) << "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS pp pp ff\n"
                                        "0 0.01\n0 0.02\n-0.01 0.03\nITEM: ATOMS type diameter xs ys zs\n"
                                        "1 0.002 0.5 0.25 0.5\n1 0.001 0 1 0\n"; }
  const SphereTable t = read_spheres(scratch("s.dump").string());
  EXPECT_DOUBLE_EQ(t.x_m[0], 0.005);
  EXPECT_DOUBLE_EQ(t.y_m[0], 0.005);
  EXPECT_DOUBLE_EQ(t.z_m[0], 0.01);
  EXPECT_DOUBLE_EQ(t.y_m[1], 0.02);
  EXPECT_DOUBLE_EQ(t.z_m[1], -0.01);
  EXPECT_EQ(t.r_m, (std::vector<double>{0.001, 0.0005}));
  EXPECT_EQ(t.particle, (std::vector<int64_t>{0, 1}));  // one particle per sphere
  // A dump that states cgs units (dump_modify units yes: once, at the top;
  // and time yes: before each timestep): centimetres to metres.
  { std::ofstream(scratch("c.dump")) << "ITEM: UNITS\ncgs\nITEM: TIME\n0.5\nITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\n"
                                        "ITEM: BOX BOUNDS ff ff ff\n0 1\n0 1\n0 1\nITEM: ATOMS id x y z radius\n"
                                        "1 0.5 0.25 2 0.07\n"; }
  const SphereTable c = read_spheres(scratch("c.dump").string());
  EXPECT_DOUBLE_EQ(c.z_m[0], 0.02);
  EXPECT_DOUBLE_EQ(c.r_m[0], 0.0007);
}

TEST(SphereTable, YadeTextExport) {
  { std::ofstream(scratch("y.txt")) << "#format x_y_z_r_matId\n# packing from YADE\n"
                                       "0.001 -0.002 0.0007 0.00068 1\n\n0 0 0.002 0.0006 1\n"; }
  const SphereTable t = read_spheres(scratch("y.txt").string());
  EXPECT_EQ(t.x_m, (std::vector<double>{0.001, 0}));
  EXPECT_EQ(t.r_m, (std::vector<double>{0.00068, 0.0006}));
  EXPECT_EQ(t.particle, (std::vector<int64_t>{0, 1}));
}

TEST(SphereTable, BadDumpsNameFileAndLine) {
  const std::string head = "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS ff ff ff\n0 1\n0 1\n0 1\n";
  expect_error("bad.dump", head + "ITEM: ATOMS id x y z radius\n1 0 0 0 0.1\n", "truncated dump");
  expect_error("bad.dump", head + "ITEM: ATOMS id x y z\n1 0 0 0\n2 0 0 1\n", "no radius or diameter column");
  expect_error("bad.dump", head + "ITEM: ATOMS id x y radius\n1 0 0 0.1\n2 0 0 0.1\n", "no z column");
  expect_error("bad.dump", head + "ITEM: ATOMS id x y z radius\n1 0 0 0 0.1\n1 0 0 1 0.1\n", "atom id 1 appears twice");
  expect_error("bad.dump", head + "ITEM: ATOMS id x y z radius\n1 0 0 0 0.1\n2 0 0 1 -0.1\n", ":11: radius must be > 0");
  expect_error("bad.dump", head + "ITEM: ATOMS id x y z radius\n1 0 0 0 0.1\n2 0 zz 1 0.1\n", ":11: position is not a number");
  expect_error("bad.dump", head + "ITEM: ATOMS id x y z radius\n1 0 0 0 0.1\n2 0 0\n", ":11: atom row has 3 values");
  expect_error("bad.dump", "ITEM: UNITS\nlj\nITEM: TIMESTEP\n0\n", "unit style 'lj'");
  expect_error("bad.dump", head + "ITEM: ATOMS id x y z radius\n1 0 0 0 0.1\n2 0 0 1 0.1\nnot an item\n", ":12: expected an 'ITEM:' line");
  expect_error("bad.dump", "ITEM: TIMESTEP\nten\n", ":2: the timestep is not an integer");
}

}  // namespace
}  // namespace tg
