// Spheres as a structure of arrays (one std::vector per property), the layout
// LAMMPS' atom_vec_sphere uses: the hot loops stream x/y/z, v, omega and r
// without dragging unused fields through the cache.
//
// ONE declared field list, Particles::for_each_field(), drives everything that
// must touch every field: resize, append, copy of one sphere onto another,
// checkpoint write/read and the snapshot tables. A field added there can never
// be forgotten by a restart (STYLE.md §9; LAMMPS fields_grow/fields_restart).
//
// Extension points for breakage (issue 7):
//  * `particle` is the id of the grain a sphere belongs to. Intact grains are
//    one sphere; a fragment made of a 17-sphere bonded cluster gives all its
//    spheres the same id. `previous_particle` is the particle id the sphere
//    (or the sphere it was split from: copy_sphere inherits it) had at the
//    last snapshot (at the start before the first): the DEM's exact lineage
//    between snapshots (compare/dem_lineage.hpp); the oedometer resets it to
//    `particle` after writing each snapshot. `material` selects a material (only 0 exists today)
//    and `flags` carries bits (kFlagBreakable, kFlagClusterElement, ...).
//  * Replacing a sphere by fragments: copy_sphere()/append_sphere() + the
//    engine's request_rebuild(); the neighbour list and contact histories are
//    then rebuilt (histories of vanished pairs are dropped).
//
// Units: SI (m, kg, s, rad). Force/torque are state too: velocity Verlet
// needs F(t) at the start of the next step, so a restart must restore them.
#pragma once
#include <cstdint>
#include <string_view>
#include <utility>
#include <vector>

namespace tg::dem {

enum ParticleFlags : uint32_t {
  kFlagNone = 0,
  kFlagBreakable = 1u << 0,       // may split (breakage issue); set by the scene
  kFlagClusterElement = 1u << 1,  // sphere is part of a bonded fragment
  kFlagFixed = 1u << 2,           // not integrated (velocity held)
};

struct Particles {
  // Kinematics.
  std::vector<double> x, y, z;     // centre, m
  std::vector<double> vx, vy, vz;  // velocity, m/s
  std::vector<double> wx, wy, wz;  // angular velocity, rad/s
  // Dynamics state (last computed force and torque, N and N·m).
  std::vector<double> fx, fy, fz;
  std::vector<double> tx, ty, tz;
  // Properties.
  std::vector<double> r;        // radius, m
  std::vector<double> m;        // mass, kg (after any mass scaling)
  std::vector<double> inertia;  // moment of inertia 2/5 m r², kg·m²
  std::vector<int64_t> particle;  // grain id (clusters share one)
  std::vector<int64_t> previous_particle;  // particle id at the last snapshot (lineage, see above)
  std::vector<int32_t> material;  // material index
  std::vector<uint32_t> flags;    // ParticleFlags bits
  // Tangential displacement history of the sphere's contact with each wall
  // (bottom platen, top platen, cylinder), m; zero when not touching.
  std::vector<double> hbx, hby, hbz, htx, hty, htz, hcx, hcy, hcz;

  int64_t size() const { return static_cast<int64_t>(r.size()); }

  // The field list. f(name, vector&) is called once per field, in a fixed
  // order (the checkpoint format relies on it). Names carry units.
  template <class F>
  void for_each_field(F&& f) {
    f("x_m", x); f("y_m", y); f("z_m", z);
    f("vx_m_s", vx); f("vy_m_s", vy); f("vz_m_s", vz);
    f("wx_rad_s", wx); f("wy_rad_s", wy); f("wz_rad_s", wz);
    f("fx_N", fx); f("fy_N", fy); f("fz_N", fz);
    f("tx_Nm", tx); f("ty_Nm", ty); f("tz_Nm", tz);
    f("r_m", r); f("m_kg", m); f("inertia_kg_m2", inertia);
    f("particle", particle); f("previous_particle", previous_particle); f("material", material); f("flags", flags);
    f("hist_bottom_x_m", hbx); f("hist_bottom_y_m", hby); f("hist_bottom_z_m", hbz);
    f("hist_top_x_m", htx); f("hist_top_y_m", hty); f("hist_top_z_m", htz);
    f("hist_cyl_x_m", hcx); f("hist_cyl_y_m", hcy); f("hist_cyl_z_m", hcz);
  }
  template <class F>
  void for_each_field(F&& f) const {
    const_cast<Particles*>(this)->for_each_field([&](std::string_view n, auto& v) { f(n, std::as_const(v)); });
  }

  void resize(int64_t n) {
    for_each_field([n](std::string_view, auto& v) { v.resize(static_cast<size_t>(n)); });
  }
  // Copies every field of sphere `from` onto sphere `to` (fragment replacement).
  void copy_sphere(int64_t from, int64_t to) {
    for_each_field([=](std::string_view, auto& v) { v[static_cast<size_t>(to)] = v[static_cast<size_t>(from)]; });
  }
  // Appends a sphere at rest with mass and inertia from its radius and the
  // density; returns its index.
  int64_t append_sphere(double px, double py, double pz, double radius, double density, int64_t grain_id,
                        int32_t mat = 0, uint32_t fl = kFlagBreakable);
};

}  // namespace tg::dem
