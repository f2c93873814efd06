// Packings as sphere tables (core/sphere_table.hpp: x_m,y_m,z_m,r_m,particle,
// the exchange format between tomograin, LIGGGHTS and scripts) to and from
// the DEM's Particles.
#pragma once
#include <filesystem>

#include "core/sphere_table.hpp"
#include "dem/particles.hpp"

namespace tg::dem {

// Spheres at rest with mass and inertia from `density`, each with its
// particle id (the row index when the table has none).
Particles particles_from_spheres(const SphereTable& s, double density);
// A CSV or HDF5 sphere table (core/sphere_table.hpp validates every row).
Particles read_packing_csv(const std::filesystem::path& path, double density);
// The spheres and their particle ids (bonded fragments share one).
SphereTable spheres_of(const Particles& p);
// Atomic write (temporary + rename), with the particle column.
void write_packing_csv(const Particles& p, const std::filesystem::path& path);

}  // namespace tg::dem
