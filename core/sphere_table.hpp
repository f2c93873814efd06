// Sphere tables: the one exchange format for packings and DEM snapshots
// between dem/ (which writes them), data_synth/ (`synth --particles`),
// compare/ (voxelise, compare) and outside tools (LIGGGHTS decks, scripts).
//
//   columns  x_m, y_m, z_m, r_m   sphere centre and radius, metres, DEM
//                                 coordinates (cylinder axis z through
//                                 x = y = 0, bottom platen at z = 0)
//            particle (optional)  integer id of the particle a sphere belongs
//                                 to: the spheres of a bonded DEM fragment
//                                 share one id and are ONE particle for every
//                                 reader. `cluster` is read as a synonym
//                                 (data_synth's older name). Without either
//                                 column each sphere is its own particle
//                                 (id = row index from 0).
//   other columns (velocities, forces …) are ignored on reading.
//
// Files: CSV (one header line), or an HDF5 table (a group of 1-D datasets,
// core/io/hdf5.hpp) named "snap.h5:/group"; "snap.h5" alone means the first
// group (in file order) that holds an x_m column — the DEM's snapshots keep
// theirs in /spheres (dem/snapshot.hpp). Other codes' files are read too,
// recognised by their first line (core/io/dem_text.hpp): LAMMPS/LIGGGHTS
// text dumps ("dump.txt", or "dump.txt:STEP" for one of several timesteps)
// and YADE's export.text ("#format x_y_z_r").
//
// Reading validates every row: finite positions, 0 < r_m < inf, integer ids;
// InputError("FILE: row N: problem") otherwise, and for a table with no rows.
#pragma once
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/table.hpp"

namespace tg {

struct SphereTable {
  std::vector<double> x_m, y_m, z_m, r_m;
  std::vector<int64_t> particle;  // particle id of each sphere
  std::string source;             // file (and group) it came from, for messages
  size_t size() const { return r_m.size(); }
  void push_back(double x, double y, double z, double r, int64_t id) {
    x_m.push_back(x);
    y_m.push_back(y);
    z_m.push_back(z);
    r_m.push_back(r);
    particle.push_back(id);
  }
};

// Validated conversion from a table with the columns above.
SphereTable spheres_from_table(const Table& t);
// The table written by write_spheres (x_m, y_m, z_m, r_m, particle).
Table spheres_to_table(const SphereTable& s);

// CSV or HDF5 (see above).
SphereTable read_spheres(const std::string& path);
// CSV, atomically; the particle column is always written.
void write_spheres(const SphereTable& s, const std::filesystem::path& path);

// Number of distinct particle ids.
int64_t particle_count(const SphereTable& s);

}  // namespace tg
