// Partial volumes against analytic volumes and an independent brute-force
// quadrature written here (2-D midpoint rule of exact sphere chords).
#include "data_synth/partial_volume.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

using namespace tg::synth;

namespace {
constexpr double kPi = std::numbers::pi;

// Sum of voxel coverages over the sphere's bounding box.
double voxel_sum(const Particle& p) {
  Vec3 lo, hi;
  bounding_box(p, lo, hi);
  double sum = 0;
  for (int64_t k = static_cast<int64_t>(std::floor(lo[0])); k < std::ceil(hi[0]); ++k)
    for (int64_t j = static_cast<int64_t>(std::floor(lo[1])); j < std::ceil(hi[1]); ++j)
      for (int64_t i = static_cast<int64_t>(std::floor(lo[2])); i < std::ceil(hi[2]); ++i)
        sum += voxel_coverage(p, k, j, i);
  return sum;
}

// Independent: midpoint rule, n×n lines along z, exact chord of the plain sphere.
double brute_sphere_box(const Sphere& s, const Vec3& lo, const Vec3& hi, int n) {
  double sum = 0;
  const double hy = (hi[1] - lo[1]) / n, hx = (hi[2] - lo[2]) / n;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      const double y = lo[1] + (a + 0.5) * hy - s.c[1], x = lo[2] + (b + 0.5) * hx - s.c[2];
      const double h2 = s.r * s.r - y * y - x * x;
      if (h2 <= 0) continue;
      const double h = std::sqrt(h2);
      sum += std::max(0.0, std::min(hi[0], s.c[0] + h) - std::max(lo[0], s.c[0] - h));
    }
  return sum * hy * hx;
}
}  // namespace

TEST(PartialVolume, SphereVoxelSumEqualsAnalyticVolume) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> frac(0.0, 1.0);
  for (double r : {1.0, 1.37, 2.5, 4.01, 7.77, 12.3, 25.6, 50.0}) {
    for (int rep = 0; rep < 3; ++rep) {
      const Vec3 c{60 + frac(rng), 60 + frac(rng), 60 + frac(rng)};
      const double exact = 4.0 / 3.0 * kPi * r * r * r;
      EXPECT_NEAR(voxel_sum(make_grain(1, c, r)), exact, 1e-9 * exact) << "r=" << r;
    }
  }
}

TEST(PartialVolume, SphereOnVoxelCornerAndCentre) {
  // Degenerate positions: breakpoints coincide with voxel faces.
  for (double r : {1.0, 3.0, 10.0}) {
    const double exact = 4.0 / 3.0 * kPi * r * r * r;
    EXPECT_NEAR(voxel_sum(make_grain(1, {20, 20, 20}, r)), exact, 1e-9 * exact);
    EXPECT_NEAR(voxel_sum(make_grain(1, {20.5, 20.5, 20.5}, r)), exact, 1e-9 * exact);
  }
}

TEST(PartialVolume, SphereBoxAnalyticPieces) {
  const Sphere s{{3.3, -1.7, 2.9}, 6.4};
  const double V = 4.0 / 3.0 * kPi * std::pow(s.r, 3);
  const double big = 100;
  // Half, octant, and a cap cut at height t above the centre.
  EXPECT_NEAR(sphere_box_volume(s, {s.c[0], -big, -big}, {big, big, big}), V / 2, 1e-10 * V);
  EXPECT_NEAR(sphere_box_volume(s, s.c, {big, big, big}), V / 8, 1e-10 * V);
  const double t = 2.2, h = s.r - t;
  EXPECT_NEAR(sphere_box_volume(s, {-big, s.c[1] + t, -big}, {big, big, big}), cap_volume(s.r, h), 1e-10 * V);
}

TEST(PartialVolume, SphereVoxelMatchesIndependentQuadrature) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> frac(0.0, 1.0);
  int checked = 0;
  for (int rep = 0; rep < 40; ++rep) {
    const double r = 1 + 20 * frac(rng);
    const Sphere s{{frac(rng), frac(rng), frac(rng)}, r};
    // A random voxel near the surface.
    const double th = kPi * frac(rng), ph = 2 * kPi * frac(rng);
    const Vec3 p{s.c[0] + r * std::cos(th), s.c[1] + r * std::sin(th) * std::cos(ph), s.c[2] + r * std::sin(th) * std::sin(ph)};
    const Vec3 lo{std::floor(p[0]), std::floor(p[1]), std::floor(p[2])}, hi{lo[0] + 1, lo[1] + 1, lo[2] + 1};
    const double ours = sphere_box_volume(s, lo, hi);
    const double ref = brute_sphere_box(s, lo, hi, 1500);
    EXPECT_NEAR(ours, ref, 2e-6) << "r=" << r;
    checked += ours > 1e-3 && ours < 0.999;
  }
  EXPECT_GT(checked, 20);  // the test really probes boundary voxels
}

TEST(PartialVolume, HalfspaceBoxClosedForms) {
  const Vec3 lo{0, 0, 0}, hi{1, 1, 1};
  const double s3 = 1 / std::sqrt(3.0);
  // Plane through the cube centre: half by symmetry.
  EXPECT_NEAR(halfspace_box_volume({{s3, s3, s3}, 1.5 * s3}, lo, hi), 0.5, 1e-14);
  EXPECT_NEAR(halfspace_box_volume({{0.6, 0.0, 0.8}, 0.7}, lo, hi), 0.5, 1e-6);  // degenerate normal
  // Corner tetrahedron x+y+z <= c (c <= 1): c³/6.
  EXPECT_NEAR(halfspace_box_volume({{s3, s3, s3}, 0.4 * s3}, lo, hi), 0.4 * 0.4 * 0.4 / 6, 1e-14);
  // Axis aligned: exact slab fraction.
  EXPECT_NEAR(halfspace_box_volume({{0, 1, 0}, 0.3}, lo, hi), 0.3, 1e-12);
  EXPECT_NEAR(halfspace_box_volume({{0, 0, -1}, -4.25}, {2, 2, 2}, {4, 4, 4}), 0.0, 1e-12);
  EXPECT_NEAR(halfspace_box_volume({{0, 0, -1}, -2.25}, {2, 2, 2}, {4, 4, 4}), 8 * 0.875, 1e-12);
}

TEST(PartialVolume, HalfSphereVoxelSumWithinBound) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> frac(0.0, 1.0);
  for (double r : {3.3, 10.7, 30.2}) {
    const Vec3 n{g(rng), g(rng), g(rng)};
    const Sphere s{{40 + frac(rng), 40 + frac(rng), 40 + frac(rng)}, r};
    const Particle half = make_cap(1, Kind::half, 1, s, n, 0.0);
    const double exact = cap_volume(r, r);
    EXPECT_NEAR(voxel_sum(half), exact, 1e-5 * exact) << "r=" << r;
    // Chip of thickness 0.3 R and the body left after a 1-voxel gap.
    const Particle chip = make_cap(2, Kind::chip, 1, s, n, 0.7 * r);
    EXPECT_NEAR(voxel_sum(chip), cap_volume(r, 0.3 * r), 1e-5 * cap_volume(r, 0.3 * r));
    const Particle body = make_cap(3, Kind::chipped, 1, s, {-n[0], -n[1], -n[2]}, -0.7 * r + 1);
    EXPECT_NEAR(voxel_sum(body), cap_volume(r, 1.7 * r - 1), 1e-5 * cap_volume(r, 1.7 * r - 1));
  }
}

TEST(PartialVolume, CutVoxelsWithinStatedBound) {
  // Per-voxel error on plane-cut surface voxels of a half-sphere, against an
  // independent midpoint rule of exact chords (sphere ∩ half-space along z).
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g;
  const Sphere s{{10.3, 10.6, 10.1}, 7.3};
  Vec3 n{g(rng), g(rng), g(rng)};
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (double& v : n) v /= len;
  const double off = 0.4;  // keeps n·(p − c) >= off
  const Particle half = make_cap(1, Kind::half, 1, s, n, off);
  auto brute = [&](int k, int j, int i, int m) {
    double sum = 0;
    for (int a = 0; a < m; ++a)
      for (int b = 0; b < m; ++b) {
        const double y = j + (a + 0.5) / m, x = i + (b + 0.5) / m;
        const double dy = y - s.c[1], dx = x - s.c[2], h2 = s.r * s.r - dy * dy - dx * dx;
        if (h2 <= 0) continue;
        double lo = std::max<double>(k, s.c[0] - std::sqrt(h2)), hi = std::min<double>(k + 1, s.c[0] + std::sqrt(h2));
        // n_z (z − cz) >= off − n_y dy − n_x dx
        const double rhs = off - n[1] * dy - n[2] * dx;
        if (n[0] > 0) lo = std::max(lo, s.c[0] + rhs / n[0]);
        else hi = std::min(hi, s.c[0] + rhs / n[0]);
        sum += std::max(0.0, hi - lo);
      }
    return sum / (double(m) * m);
  };
  double worst = 0, total_err = 0;
  int cut = 0;
  for (int k = 2; k < 19; ++k)
    for (int j = 2; j < 19; ++j)
      for (int i = 2; i < 19; ++i) {
        const double v = voxel_coverage(half, k, j, i);
        if (v <= 0 || v >= 1) continue;
        // Only voxels cut by both the sphere and the plane need the chord rule.
        const Vec3 lo{double(k), double(j), double(i)}, hi{k + 1.0, j + 1.0, i + 1.0};
        const double sv = sphere_box_volume(s, lo, hi);
        if (sv >= 1 || std::abs(sv - v) < 1e-12) continue;
        const double err = v - brute(k, j, i, 600);
        worst = std::max(worst, std::abs(err));
        total_err += err;
        ++cut;
      }
  EXPECT_GT(cut, 20);
  EXPECT_LT(worst, 1e-4);
  std::printf("cut voxels %d, worst %.2e, summed error %.2e\n", cut, worst, total_err);
}

TEST(PartialVolume, PoreIsSubtractedExactly) {
  Particle p = make_grain(1, {20.2, 20.7, 20.4}, 12.5);
  p.pores.push_back({{23.1, 19.0, 18.3}, 2.6});
  p.pores.push_back({{15.0, 22.2, 21.9}, 1.2});
  const double exact = 4.0 / 3.0 * kPi * (std::pow(12.5, 3) - std::pow(2.6, 3) - std::pow(1.2, 3));
  EXPECT_NEAR(voxel_sum(p), exact, 1e-9 * exact);
}

TEST(PartialVolume, ClusterUnionVolume) {
  // Two overlapping spheres: lens volume is analytic.
  const double r = 6.0, d = 7.0;
  const Particle c = make_cluster(1, 1, {{{20, 20, 20}, r}, {{20, 20, 20 + d}, r}});
  const double lens = kPi * (4 * r + d) * (2 * r - d) * (2 * r - d) / 12;
  const double exact = 2 * 4.0 / 3.0 * kPi * r * r * r - lens;
  EXPECT_NEAR(voxel_sum(c), exact, 1e-4 * exact);
  EXPECT_NEAR(particle_truth(c).volume, exact, 1e-6 * exact);
  // The plain chord rule (centroids) is coarser: sqrt singularity at silhouettes.
  EXPECT_NEAR(chord_volume(c, {10, 10, 10}, {30, 30, 40}, 48, 12), exact, 2e-5 * exact);
}
