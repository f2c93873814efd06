// Snapshots: the spheres at one instant as an HDF5 table (group /spheres,
// one 1-D dataset per column: x_m y_m z_m r_m vx_m_s vy_m_s vz_m_s
// wx_rad_s wy_rad_s wz_rad_s particle
// previous_particle: the particle id at the previous snapshot, dem/particles.hpp) plus root attributes (time, strain),
// and an XDMF sidecar (same name, .xmf) describing them as a point cloud
// (Polyvertex, X_Y_Z geometry) so ParaView opens it directly; use a Glyph
// filter scaled by r_m to see spheres.
#pragma once
#include <filesystem>
#include <string>

#include "dem/particles.hpp"

namespace tg::dem {

// Writes PATH (.h5) and PATH with extension .xmf, both atomically.
// `attributes_json` goes to the root attribute "snapshot".
void write_snapshot(const Particles& p, const std::filesystem::path& path, const std::string& attributes_json);

}  // namespace tg::dem
