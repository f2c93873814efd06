// Voxelising DEM spheres: the grid, the metres -> voxel mapping, exact
// partial volumes (data_synth's bound), one label per particle (clusters),
// the ideal path's measured volumes, and the shape of half fragments.
#include "compare/voxelise.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <unistd.h>

#include "core/errors.hpp"
#include "core/io/hdf5.hpp"
#include "data_synth/render.hpp"
#include "dem/breakage/fragment_template.hpp"
#include "measure/hull.hpp"
#include "measure/particles.hpp"
#include "segmentation/connected_components.hpp"
#include "segmentation/segment.hpp"

namespace {
using namespace tg;
using tg::SphereTable;
constexpr double kPi = std::numbers::pi;

SphereTable table(std::vector<std::array<double, 5>> rows) {  // x, y, z, r, particle
  SphereTable s;
  s.source = "test";
  for (const auto& r : rows) {
    s.x_m.push_back(r[0]);
    s.y_m.push_back(r[1]);
    s.z_m.push_back(r[2]);
    s.r_m.push_back(r[3]);
    s.particle.push_back(static_cast<int64_t>(r[4]));
  }
  return s;
}

double sphere_volume(double r) { return 4.0 / 3.0 * kPi * r * r * r; }
// Two spheres of radii a, b at distance d (|a-b| < d < a+b): union volume.
double union_volume(double a, double b, double d) {
  const double lens = kPi * (a + b - d) * (a + b - d) * (d * d + 2 * d * (a + b) - 3 * (a - b) * (a - b)) / (12 * d);
  return sphere_volume(a) + sphere_volume(b) - lens;
}

TEST(Voxelise, GridCoversSpheresWithMargin) {
  const double v = 20e-6;
  const SphereTable s = table({{0, 0, 0.5e-3, 0.2e-3, 1}, {0.6e-3, -0.1e-3, 0.9e-3, 0.25e-3, 2}});
  compare::VoxeliseOptions o;
  o.voxel_m = v;
  o.margin_vox = 2;
  const auto [shape, g] = compare::voxel_grid(s, o);
  // x: [-0.2, 0.85] mm, y: [-0.35, 0.2] mm, z: [0.3, 1.15] mm, + 2 voxels each side.
  EXPECT_EQ(shape.nx, static_cast<int64_t>(std::ceil((1.05e-3 + 4 * v) / v - 1e-9)));
  EXPECT_EQ(shape.ny, static_cast<int64_t>(std::ceil((0.55e-3 + 4 * v) / v - 1e-9)));
  EXPECT_EQ(shape.nz, static_cast<int64_t>(std::ceil((0.85e-3 + 4 * v) / v - 1e-9)));
  EXPECT_LE(g.origin_m[2], -0.2e-3 - 2 * v + 1e-12);
  EXPECT_GE(g.origin_m[2] + shape.nx * v, 0.85e-3 + 2 * v - 1e-12);
  o.field = compare::FieldOfView::cylinder;
  o.cylinder_diameter_m = 2e-3;
  const auto [cs, cg] = compare::voxel_grid(s, o);
  EXPECT_EQ(cs.nx, 104);  // 2 mm / 20 um + 2 x 2 margin
  EXPECT_NEAR(cg.origin_m[2], -1e-3 - 2 * v, 1e-12);
  EXPECT_LE(cg.origin_m[0], -2 * v + 1e-12);  // bottom platen z = 0 inside
}

// Exact partial volumes: the solid fraction summed over the grid is each
// sphere's (or cluster's) analytic volume, within data_synth's stated bound
// (spheres: < 1e-10 per voxel), so the mapping metres -> voxels is exact.
TEST(Voxelise, PartialVolumeSumsAreExactVolumes) {
  const double v = 10e-6;
  // A lone sphere and a two-sphere cluster whose members overlap (counted once).
  const double a = 0.11e-3, b = 0.08e-3, d = 0.12e-3;
  const SphereTable s = table({{0.013e-3, -0.007e-3, 0.2e-3, 0.1e-3, 7},
                               {0.5e-3, 0.0, 0.2e-3, a, 3},
                               {0.5e-3 + d, 0.0, 0.2e-3, b, 3}});
  compare::VoxeliseOptions o;
  o.voxel_m = v;
  const auto [shape, g] = compare::voxel_grid(s, o);
  std::vector<int64_t> ids;
  const auto ps = synth::particles_from_spheres(s, g, &ids);
  ASSERT_EQ(ps.size(), 2u);
  EXPECT_EQ(ids, (std::vector<int64_t>{-1, 7, 3}));
  EXPECT_EQ(ps[1].kind, synth::Kind::cluster);
  // Render each particle alone and sum its partial volume.
  const double v3 = v * v * v;
  const double expect[2] = {sphere_volume(0.1e-3), union_volume(a, b, d)};
  for (size_t p = 0; p < 2; ++p) {
    synth::RenderOptions ro;
    ro.labels = false;
    const auto r = synth::render({ps[p]}, shape, g, ro);
    double sum = 0;
    for (float f : r.solid.span()) sum += f;
    // float voxels: 6e-8 relative per voxel; spheres 1e-10, lens cut 1e-4 per surface voxel.
    EXPECT_NEAR(sum * v3, expect[p], 2e-5 * expect[p]) << "particle " << p;
  }
}

// The ideal path: measure the truth labels. One label per particle, the
// voxel-count volume within 1 % of the exact volume (threshold 0.5 on the
// exact partial volume: the error is a sum of ± half voxels over the surface).
TEST(Voxelise, IdealPathGivesBackVolumes) {
  const double v = 12.3e-6;
  const SphereTable s = table({{0, 0, 0.3e-3, 0.16e-3, 1},
                               {0.4e-3, 0.05e-3, 0.3e-3, 0.14e-3, 2},
                               {-0.2e-3, 0.35e-3, 0.3e-3, 0.12e-3, 5},
                               {-0.2e-3 + 0.15e-3, 0.35e-3, 0.3e-3, 0.10e-3, 5}});
  compare::VoxeliseOptions o;
  o.voxel_m = v;
  o.grey = false;
  o.truth = true;
  o.cluster_body = compare::ClusterBody::members;  // the exact union of the members, not their hull
  const compare::Voxelised x = compare::voxelise(s, o);
  EXPECT_TRUE(x.grey.empty());
  EXPECT_EQ(x.clusters_union, 1);  // its members overlap: rendered as the exact union
  measure::ParticleOptions po;
  po.oriented_box = false;
  const auto m = measure::measure_particles(x.labels.view(), po);
  ASSERT_EQ(m.size(), 3u);
  const double expect[3] = {sphere_volume(0.16e-3), sphere_volume(0.14e-3), union_volume(0.12e-3, 0.10e-3, 0.15e-3)};
  for (size_t p = 0; p < 3; ++p) {
    EXPECT_EQ(m[p].stats.label, p + 1);
    EXPECT_NEAR(m[p].stats.volume_m3, expect[p], 0.01 * expect[p]) << "label " << p + 1;
    EXPECT_NEAR(x.truth.num("volume_mm3")[p], expect[p] * 1e9, 1e-6 * expect[p] * 1e9);
  }
  EXPECT_EQ(x.truth.num("particle"), (std::vector<double>{1, 2, 5}));
}

TEST(Voxelise, GreyUsesImagingLevels) {
  const SphereTable s = table({{0, 0, 0, 0.2e-3, 1}});
  compare::VoxeliseOptions o;
  o.voxel_m = 10e-6;
  o.margin_vox = 6;
  o.imaging.noise_sigma = 0;
  o.imaging.psf_sigma = 0;
  o.imaging.void_grey = 1000;
  o.imaging.solid_grey = 30000;
  const compare::Voxelised x = compare::voxelise(s, o);
  const Shape sh = x.grey.shape();
  EXPECT_EQ(x.grey(sh.nz / 2, sh.ny / 2, sh.nx / 2), 30000);
  EXPECT_EQ(x.grey(0, 0, 0), 1000);
  EXPECT_EQ(x.grey.geometry(), x.labels.geometry());
}

// A half fragment, 36 voxels per mother diameter. The study's Dmin/Dmed/Dmax
// are the smallest box's edges: a half sphere's box is 2R x 2R x R, so
// FR = Dmin/Dmed = 0.5 and AR = Dmax/Dmin = 2. Checked for a 17-sphere
// cluster built like the DEM replacement (1 central sphere + 16 smaller ones,
// all tangent to the mother from inside, none crossing the plane): 12 small
// spheres on the rim, 4 at 45 degrees.
// TODO(breakage): repeat with dem/breakage's template when it lands.
SphereTable half_fragment(double R, double tilt) {
  // Plane normal n (unit), fragment on the side n.(p - c) >= 0; c at the origin.
  const double nz = std::cos(tilt), nx = std::sin(tilt);
  // Orthonormal frame (e1, e2, n) in (x, y, z).
  const std::array<double, 3> n{nx, 0, nz}, e1{nz, 0, -nx}, e2{0, 1, 0};
  SphereTable s;
  s.source = "fragment";
  auto add = [&](double h, double rho, double phi, double r) {
    for (int a = 0; a < 3; ++a) {
      const double p = h * n[a] + rho * (std::cos(phi) * e1[a] + std::sin(phi) * e2[a]);
      (a == 0 ? s.x_m : a == 1 ? s.y_m : s.z_m).push_back(p);
    }
    s.r_m.push_back(r);
    s.particle.push_back(1);
  };
  add(0.5 * R, 0, 0, 0.5 * R);  // central: touches the plane and the mother's pole
  const double r1 = 0.1 * R, rho1 = std::sqrt((R - r1) * (R - r1) - r1 * r1);
  for (int k = 0; k < 12; ++k) add(r1, rho1, k * kPi / 6, r1);
  const double r2 = 0.28 * R, d2 = R - r2;
  for (int k = 0; k < 4; ++k) add(d2 * std::sin(kPi / 4), d2 * std::cos(kPi / 4), kPi / 4 + k * kPi / 2, r2);
  for (auto& z : s.z_m) z += 2 * R;
  return s;
}

TEST(Voxelise, HalfFragmentShapeAtThirtySixVoxelsPerDiameter) {
  const double R = 0.5e-3, v = 2 * R / 36;
  for (double tilt : {0.0, 0.5}) {
    const SphereTable s = half_fragment(R, tilt);
    ASSERT_EQ(s.size(), 17u);
    compare::VoxeliseOptions o;
    o.voxel_m = v;
    o.grey = false;
    o.cluster_body = compare::ClusterBody::members;  // the spheres' shape (their hull: AR 1.90 at tilt 0.5)
    const compare::Voxelised x = compare::voxelise(s, o);
    measure::ParticleOptions po;
    po.sizing = measure::Sizing::obb;
    const auto m = measure::measure_particles(x.labels.view(), po);
    ASSERT_EQ(m.size(), 1u);  // one cluster = one particle
    EXPECT_NEAR(m[0].fr, 0.5, 0.03) << "tilt " << tilt;
    EXPECT_NEAR(m[0].ar, 2.0, 0.1) << "tilt " << tilt;
  }
}

// The DEM's fragment template (dem/breakage/fragment_template.hpp) for a
// mother of radius R centred at (0, 0, 2R), the plane normal tilted about y.
SphereTable template_fragment(double R, double tilt) {
  const auto& t = dem::breakage::fragment_template();
  const double ct = std::cos(tilt), st = std::sin(tilt);
  SphereTable s;
  s.source = "template";
  for (const auto& sp : t.spheres) {
    s.x_m.push_back(R * (ct * sp.c.x + st * sp.c.z));
    s.y_m.push_back(R * sp.c.y);
    s.z_m.push_back(R * (-st * sp.c.x + ct * sp.c.z) + 2 * R);
    s.r_m.push_back(R * sp.r);
    s.particle.push_back(1);
  }
  return s;
}

// The template's member spheres voxelised at 36 voxels per mother diameter
// and measured by the ideal path with the study's box sizing.
TEST(Voxelise, DemFragmentTemplateShape) {
  const double R = 0.5e-3, v = 2 * R / 36;
  for (double tilt : {0.0, 0.5}) {
    const SphereTable s = template_fragment(R, tilt);
    compare::VoxeliseOptions o;
    o.voxel_m = v;
    o.grey = false;
    o.cluster_body = compare::ClusterBody::members;
    const compare::Voxelised x = compare::voxelise(s, o);
    EXPECT_EQ(x.clusters_split, 1);  // tangent members
    measure::ParticleOptions po;
    po.sizing = measure::Sizing::obb;
    const auto m = measure::measure_particles(x.labels.view(), po);
    ASSERT_EQ(m.size(), 1u);
    measure::Particle f = m[0];
    measure::fill_sizing(f, measure::Sizing::feret);
    std::printf("template tilt %.1f: box FR %.4f AR %.4f (edges %.1f %.1f %.1f vox); feret FR %.4f AR %.4f\n", tilt,
                m[0].fr, m[0].ar, m[0].d_max_m / v, m[0].d_med_m / v, m[0].d_min_m / v, f.fr, f.ar);
    EXPECT_NEAR(m[0].fr, 0.5, 0.03) << "tilt " << tilt;
    EXPECT_NEAR(m[0].ar, 2.0, 0.1) << "tilt " << tilt;
  }
}

// Clusters of tangent spheres render as separate spheres relabelled to one
// particle: the same labels as the exact union except in a few rim voxels.
TEST(Voxelise, DisjointClusterFastPathMatchesUnion) {
  const double R = 0.5e-3, v = 2 * R / 30;
  const SphereTable s = template_fragment(R, 0.5);
  compare::VoxeliseOptions o;
  o.voxel_m = v;
  o.grey = false;
  o.cluster_body = compare::ClusterBody::members;
  const compare::Voxelised fast = compare::voxelise(s, o);
  o.member_overlap = -1;
  const compare::Voxelised exact = compare::voxelise(s, o);
  EXPECT_EQ(fast.clusters_split, 1);
  EXPECT_EQ(exact.clusters_union, 1);
  int64_t solid = 0, differ = 0;
  for (int64_t q = 0; q < exact.labels.size(); ++q) {
    solid += exact.labels[q] != 0;
    differ += exact.labels[q] != fast.labels[q];
  }
  ASSERT_GT(solid, 1000);
  // Union and sum differ only where members overlap (here: tangent points) and the
  // voxel's solid fraction is within that difference of 0.5.
  EXPECT_LE(differ, solid / 500) << differ << " of " << solid;
}

// Volume of the convex hull of points sampled on every template sphere (in
// mother radii): CGAL's hull (measure/hull.hpp) of 2000 Fibonacci points per
// sphere, a polytope inscribed in the hull of the spheres, so a lower bound
// that converges like 1/points (500: 1.6947, 2000: 1.6991, 8000: 1.7000).
double template_hull_volume_inscribed() {
  const auto& t = dem::breakage::fragment_template();
  constexpr int n = 2000;
  const double golden = kPi * (3 - std::sqrt(5.0));
  std::vector<measure::Vec3> pts;
  for (const auto& sp : t.spheres)
    for (int i = 0; i < n; ++i) {
      const double z = 1 - (2 * i + 1.0) / n, rho = std::sqrt(1 - z * z);
      pts.emplace_back(sp.c.x + sp.r * rho * std::cos(i * golden), sp.c.y + sp.r * rho * std::sin(i * golden),
                       sp.c.z + sp.r * z);
    }
  const measure::ConvexHull h = measure::convex_hull(pts);
  double vol = 0;  // divergence theorem over the outward triangles
  for (const auto& f : h.faces) vol += h.vertices[f[0]].dot(h.vertices[f[1]].cross(h.vertices[f[2]])) / 6;
  return vol;
}

// cluster_body = hull: the template fragment (R = 15 voxels, tilted) is one
// connected label, and its rendered solid volume is the hull's: at least the
// inscribed polytope's (minus the renderer's float sums) and at most 0.5 %
// above it (the outer polytope: +0.19 % for the template; inscribed bound:
// -0.07 %). The same volume against the DEM's sphere sum and the nominal half
// sphere (the numbers docs/compare.md quotes).
TEST(Voxelise, FragmentHullIsOneBodyWithTheHullsVolume) {
  const double R = 0.5e-3, v = R / 15;
  const double hull = template_hull_volume_inscribed();  // mother radii^3
  const auto& t = dem::breakage::fragment_template();
  double spheres = 0;
  for (const auto& sp : t.spheres) spheres += sphere_volume(sp.r);
  EXPECT_NEAR(hull / (2 * kPi / 3), 0.812, 0.001);  // of the half sphere
  EXPECT_NEAR(hull / spheres, 1.502, 0.002);        // of the DEM's member spheres
  for (double tilt : {0.0, 0.5, 1.3}) {
    const SphereTable s = template_fragment(R, tilt);
    compare::VoxeliseOptions o;
    o.voxel_m = v;
    o.grey = false;
    const compare::Voxelised x = compare::voxelise(s, o);
    EXPECT_EQ(x.clusters_hull, 1);
    const double solid = x.solid_fraction * static_cast<double>(x.labels.size());  // voxels
    const double expect = hull * 15 * 15 * 15;
    EXPECT_GE(solid, expect * (1 - 1e-5)) << "tilt " << tilt;
    EXPECT_LE(solid, expect * 1.005) << "tilt " << tilt;
    // One label, one 6-connected piece.
    Volume<uint8_t> mask(x.labels.shape());
    int64_t n = 0;
    for (int64_t q = 0; q < x.labels.size(); ++q) {
      ASSERT_LE(x.labels[q], 1u);
      mask[q] = x.labels[q] != 0;
      n += mask[q];
    }
    Volume<uint32_t> cc;
    ComponentsOptions co;
    co.connectivity = 6;
    EXPECT_EQ(connected_components(mask, cc, co).count, 1u) << "tilt " << tilt;
    std::printf("hull body tilt %.1f: solid %.1f vox^3 = %.5f x inscribed hull; %lld labelled voxels\n", tilt, solid,
                solid / expect, static_cast<long long>(n));
  }
}

// Imaged and segmented like a scan (data_synth's default grey, PSF and noise;
// segment's defaults at the mother's radius, R = 15 voxels, the compare
// default's scale for the first stage's grains): the hull body is one label.
// The member spheres are printed beside it (their necks: several labels).
TEST(Voxelise, ImagedFragmentHullSegmentsAsOneLabel) {
  const double R = 0.5e-3, v = R / 15;
  for (double tilt : {0.0, 0.5, 1.3}) {
    const SphereTable s = template_fragment(R, tilt);
    uint32_t count[2] = {0, 0};
    for (int body = 0; body < 2; ++body) {
      compare::VoxeliseOptions o;
      o.voxel_m = v;
      o.margin_vox = 8;
      o.cluster_body = body == 0 ? compare::ClusterBody::hull : compare::ClusterBody::members;
      compare::Voxelised x = compare::voxelise(s, o);
      SegmentOptions so;
      so.grain_radius_vox = 15;
      count[body] = segment(std::move(x.grey), so).count;
    }
    std::printf("imaged template tilt %.1f: %u label(s) as hull, %u as member spheres\n", tilt, count[0], count[1]);
    EXPECT_EQ(count[0], 1u) << "tilt " << tilt;
  }
}

// The exact half sphere (data_synth cap) measured through the same path, Feret sizing:
// Dmax = 2R, Dmin = R, Dmed = 6V/(pi Dmax Dmin) = 2R.
TEST(Voxelise, HalfSphereFeretShape) {
  const double R = 16;  // voxels: 32 per diameter
  const Shape sh{40, 40, 40};
  const Geometry g = Geometry::isotropic_m(10e-6);
  const auto p = synth::make_cap(1, synth::Kind::half, 1, synth::Sphere{{12.3, 20.1, 19.7}, R}, {1, 0, 0}, 0);
  const auto r = synth::render({p}, sh, g);
  measure::ParticleOptions po;
  po.oriented_box = false;
  const auto m = measure::measure_particles(r.labels.view(), po);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_NEAR(m[0].fr, 0.5, 0.03);
  EXPECT_NEAR(m[0].ar, 2.0, 0.1);
}

TEST(Voxelise, ReadsCsvAndHdf5Tables) {
  const auto dir = std::filesystem::temp_directory_path() / ("tg_vox_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  Table t;
  t.add("x_m", {0, 1e-3, 1.1e-3});
  t.add("y_m", {0, 0, 0});
  t.add("z_m", {1e-3, 1e-3, 1e-3});
  t.add("r_m", {1e-4, 1e-4, 1e-4});
  t.add("particle", {4, 9, 9});
  write_csv(t, dir / "snap.csv");
  const SphereTable a = tg::read_spheres((dir / "snap.csv").string());
  EXPECT_EQ(a.particle, (std::vector<int64_t>{4, 9, 9}));
  {
    H5Writer w((dir / "snap.h5").string());
    w.write_table("/spheres", t);
    w.commit();
  }
  const SphereTable b = tg::read_spheres((dir / "snap.h5").string());
  EXPECT_EQ(b.x_m, a.x_m);
  EXPECT_EQ(b.particle, a.particle);
  // A table whose radius column is misnamed is refused, naming the column
  // it lacks; so is a particle id that is not an integer.
  Table misnamed;
  misnamed.add("x_m", {0});
  misnamed.add("y_m", {0});
  misnamed.add("z_m", {0});
  misnamed.add("r_bad", {1e-4});
  misnamed.source = "misnamed.csv";
  try {
    tg::spheres_from_table(misnamed);
    ADD_FAILURE() << "a table without r_m was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("r_m"), std::string::npos) << e.what();
  }
  Table fractional;
  fractional.add("x_m", {0, 1e-3});
  fractional.add("y_m", {0, 0});
  fractional.add("z_m", {0, 0});
  fractional.add("r_m", {1e-4, 1e-4});
  fractional.add("particle", {4, 9.5});  // not an id
  fractional.source = "fractional.csv";
  EXPECT_THROW(tg::spheres_from_table(fractional), InputError);
  Table neg;
  neg.add("x_m", {0});
  neg.add("y_m", {0});
  neg.add("z_m", {0});
  neg.add("r_m", {-1});
  neg.source = "neg.csv";
  EXPECT_THROW(tg::spheres_from_table(neg), InputError);
  std::filesystem::remove_all(dir);
}

TEST(Voxelise, RejectsBadOptions) {
  const SphereTable s = table({{0, 0, 0, 1e-4, 1}});
  compare::VoxeliseOptions o;
  EXPECT_THROW(compare::voxelise(s, o), UsageError);  // no voxel size
  o.voxel_m = 1e-9;                                   // 200000 voxels across
  EXPECT_THROW(compare::voxelise(s, o), InputError);
}

}  // namespace
