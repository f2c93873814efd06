// Particle / packing CSV tables (header x_m,y_m,z_m,r_m and friends), and
// every sphere file read_spheres recognises by its first line: LAMMPS /
// LIGGGHTS dumps and YADE text (core/io/dem_text.hpp; seeds in the corpus).
#include "core/sphere_table.hpp"
#include "core/table.hpp"
#include "tests/fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string file = tg::fuzz::scratch("in.csv");
  tg::fuzz::write_file(file, data, size);
  tg::fuzz::expect_clean([&] {
    const tg::Table t = tg::read_csv(file, {"x_m", "y_m", "z_m", "r_m"});
    (void)tg::to_csv(t);
  });
  tg::fuzz::expect_clean([&] { (void)tg::read_spheres(file); });
  tg::fuzz::expect_clean([&] { (void)tg::read_spheres(file + ":100"); });
  return 0;
}
