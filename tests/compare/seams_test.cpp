// Where the image world meets the DEM world: a snapshot written by the DEM
// (dem::write_snapshot / write_packing_csv; the spheres of a bonded fragment
// share one particle id) is read by `synth --particles`, `voxelise` and
// `compare` as the same particles — one sphere-table reader
// (core/sphere_table) and one spheres-to-particles mapping
// (synth::particles_from_spheres).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>

#include "compare/dem_stage.hpp"
#include "compare/voxelise.hpp"
#include "data_synth/scene.hpp"
#include "dem/packing_io.hpp"
#include "dem/snapshot.hpp"

namespace tg {
namespace {
namespace fs = std::filesystem;

dem::Particles snapshot_particles() {
  dem::Particles p;
  p.append_sphere(0, 0, 0.40e-3, 0.30e-3, 2180, 0);
  p.append_sphere(0.75e-3, 0, 0.40e-3, 0.30e-3, 2180, 1);
  p.append_sphere(0, 0.8e-3, 0.45e-3, 0.35e-3, 2180, 2);
  // A fragment: three tangent spheres with one id (as the replacement makes them).
  p.append_sphere(0.7e-3, 0.8e-3, 0.30e-3, 0.20e-3, 2180, 5);
  p.append_sphere(0.7e-3, 0.8e-3, 0.70e-3, 0.20e-3, 2180, 5);
  p.append_sphere(0.7e-3, 0.8e-3, 1.00e-3, 0.10e-3, 2180, 5);
  return p;
}

TEST(Seams, ADemSnapshotIsTheSameParticlesForSynthVoxeliseAndCompare) {
  const fs::path dir = fs::temp_directory_path() / ("tg_seams_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const dem::Particles p = snapshot_particles();
  dem::write_snapshot(p, dir / "snap.h5", "{}");
  dem::write_packing_csv(p, dir / "snap.csv");
  synth::Grid g;
  g.voxel_mm = 0.02;
  g.origin_mm = {-0.2, -0.6, -0.6};
  g.shape = Shape{80, 100, 100};
  g.geometry = Geometry::isotropic_m(g.voxel_mm * 1e-3);
  g.geometry.origin_m = {g.origin_mm[0] * 1e-3, g.origin_mm[1] * 1e-3, g.origin_mm[2] * 1e-3};
  for (const fs::path& f : {dir / "snap.h5", dir / "snap.csv"}) {
    SCOPED_TRACE(f.string());
    const SphereTable s = read_spheres(f.string());
    // synth --particles
    const std::vector<synth::Particle> a = synth::read_particles(f.string(), g);
    ASSERT_EQ(a.size(), 4u);
    EXPECT_EQ(a[3].kind, synth::Kind::cluster);
    ASSERT_EQ(a[3].pieces.size(), 3u);
    EXPECT_NEAR(a[3].pieces[2].sphere.r, 0.10 / 0.02, 1e-12);
    EXPECT_NEAR(a[0].pieces[0].sphere.c[0], (0.40 + 0.2) / 0.02, 1e-9);  // z in voxels of the grid
    // voxelise: one label per particle, the fragment labelled once
    compare::VoxeliseOptions vo;
    vo.voxel_m = 20e-6;
    vo.grey = false;
    const compare::Voxelised v = compare::voxelise(s, vo);
    EXPECT_EQ(v.particle_of_label, (std::vector<int64_t>{-1, 0, 1, 2, 5}));
    EXPECT_EQ(*std::max_element(v.labels.data(), v.labels.data() + v.labels.size()), 4u);
    // compare: the initial particle count and the segmentation scale
    const compare::ParticleScale sc = compare::particle_scale(s);
    EXPECT_EQ(sc.particles, 4);
    EXPECT_NEAR(sc.median_radius_m, 0.30e-3, 1e-15);  // radii 0.30, 0.30, 0.35, cbrt(0.2^3+0.2^3+0.1^3)=0.26
  }
  fs::remove_all(dir);
}

// The DEM's exact coordination, by hand: a chain of three touching particles
// (the middle one a two-sphere fragment) and a fourth 1 % of a radius away.
TEST(Seams, SphereCoordinationCountsParticleContactsOnce) {
  SphereTable s;
  s.push_back(0, 0, 0, 1e-3, 1);
  s.push_back(0, 0, 2e-3, 1e-3, 2);      // touches particle 1
  s.push_back(0, 0, 3.5e-3, 0.5e-3, 2);  // same fragment: no contact with itself
  s.push_back(0, 0, 5e-3, 1e-3, 3);      // overlaps particle 2's second sphere
  s.push_back(0, 0, 7.01e-3, 1e-3, 4);   // 10 um gap: not a contact
  auto coordination = [&](double tol) { return compare::mean_coordination(compare::exact_contact_series(s, tol).by_size); };
  EXPECT_DOUBLE_EQ(coordination(1e-3), 2.0 * 2 / 4);
  EXPECT_DOUBLE_EQ(coordination(0.02), 2.0 * 3 / 4);  // within 2 % of a radius
  // Contacts are sphere pairs: particle 2 touches 3 through one sphere, 1 through the other.
  EXPECT_EQ(compare::sphere_contacts(s).size(), 2u);
}

}  // namespace
}  // namespace tg
