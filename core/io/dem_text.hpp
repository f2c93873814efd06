// Sphere tables written by other DEM codes, read into the columns of a
// sphere table (core/sphere_table.hpp: x_m, y_m, z_m, r_m[, particle]), so
// that a packing or snapshot from them goes wherever ours go (`dem
// oedometer`'s packing, `synth --particles`, `compare --dem-snapshots`,
// `voxelise`):
//
// * LAMMPS / LIGGGHTS text dumps (`dump custom ... id type x y z radius`,
//   `write_dump all custom FILE id type radius x y z`): blocks of
//   "ITEM: TIMESTEP", "ITEM: NUMBER OF ATOMS", "ITEM: BOX BOUNDS" and
//   "ITEM: ATOMS <columns>". Positions from x y z, xu yu zu, or xs ys zs
//   (scaled by the orthogonal box); size from radius or diameter; the
//   particle from mol (rigid clusters) when present, else one per atom.
//   Rows are put in the order of the id column (MPI ranks write theirs in
//   any order), so a file gives the same table however it was written. A
//   file of several timesteps needs one named: "FILE:STEP".
// * YADE's export.text / export.textExt: a first line "#format x_y_z_r"
//   (or x_y_z_r_matId, x_y_z_r_attrs), comment lines with #, then one
//   sphere a line, x y z r first (further columns ignored).
//
// Units: metres, as LIGGGHTS and YADE write them (SI). A LAMMPS dump that
// states its units ("ITEM: UNITS", dump_modify units yes) is converted from
// cgs; any other unit style is refused. Other codes' coordinates are taken as
// they are: a packing for `dem oedometer` must be in its frame (cylinder
// axis through x = y = 0, bottom platen at z = 0).
//
// Errors: InputError("FILE:LINE: problem") for a truncated block, a missing
// column, a cell that is not a number, a duplicate id, an unknown timestep.
#pragma once
#include <optional>
#include <string>

#include "core/table.hpp"

namespace tg {

// The table of `spec` when it names a file in one of the formats above
// ("FILE", or "FILE:STEP" for a dump's timestep); std::nullopt when the
// file is in none of them (a CSV, for the caller to read).
std::optional<Table> read_dem_text(const std::string& spec);

}  // namespace tg
