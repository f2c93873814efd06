// Packings as CSV, the exchange format between tomograin, LIGGGHTS and
// scripts: header `x_m,y_m,z_m,r_m`, one sphere a row, SI units, cylinder
// axis along z with its centre at x = y = 0 and the bottom platen at z = 0.
// Extra columns are ignored on reading; a `particle` column, if present,
// gives grain ids (else the row number).
#pragma once
#include <filesystem>

#include "dem/particles.hpp"

namespace tg::dem {

// Spheres at rest with mass and inertia from `density`. Throws InputError
// naming the file and row for a non-positive radius or non-finite value.
Particles read_packing_csv(const std::filesystem::path& path, double density);
// Atomic write (temporary + rename).
void write_packing_csv(const Particles& p, const std::filesystem::path& path);

}  // namespace tg::dem
