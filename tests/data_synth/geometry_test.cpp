#include "data_synth/geometry.hpp"
#include "data_synth/partial_volume.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace tg::synth;
constexpr double kPi = std::numbers::pi;

TEST(Geometry, GrainTruth) {
  const Truth t = particle_truth(make_grain(3, {1, 2, 3}, 5));
  EXPECT_NEAR(t.volume, 4.0 / 3.0 * kPi * 125, 1e-9);
  EXPECT_DOUBLE_EQ(t.dmax, 10);
  EXPECT_DOUBLE_EQ(t.dmin, 10);
  EXPECT_NEAR(t.dmed, 10, 1e-12);
  EXPECT_NEAR(t.fr, 1, 1e-12);
  EXPECT_NEAR(t.ar, 1, 1e-12);
  EXPECT_EQ(t.centroid, (Vec3{1, 2, 3}));
}

TEST(Geometry, HalfSphereTruthMatchesIssue) {
  // Half-sphere of radius R: Dmax = 2R, Dmin = R, Dmed = 2R, FR = 0.5, AR = 2.
  const double R = 4;
  const Truth t = particle_truth(make_cap(2, Kind::half, 1, {{0, 0, 0}, R}, {0, 0, 1}, 0.0));
  EXPECT_NEAR(t.volume, 2.0 / 3.0 * kPi * R * R * R, 1e-12);
  EXPECT_NEAR(t.dmax, 2 * R, 1e-12);
  EXPECT_NEAR(t.dmin, R, 1e-12);
  EXPECT_NEAR(t.dmed, 2 * R, 1e-12);
  EXPECT_NEAR(t.fr, 0.5, 1e-12);
  EXPECT_NEAR(t.ar, 2, 1e-12);
  EXPECT_NEAR(t.centroid[2], 3 * R / 8, 1e-12);  // hemisphere centroid
}

TEST(Geometry, CapTruthAgainstChordQuadrature) {
  // Analytic cap volume/centroid vs the independent chord quadrature path.
  const Sphere s{{10.2, 9.7, 10.9}, 6.3};
  const Particle cap = make_cap(5, Kind::chip, 1, s, {0.3, -0.5, 0.8}, 3.1);
  const Truth t = particle_truth(cap);
  Vec3 lo, hi, m;
  bounding_box(cap, lo, hi);
  const double v = chord_volume(cap, lo, hi, 48, 12, &m);
  // Tolerances are those of the chord rule (sqrt singularity at the silhouette).
  EXPECT_NEAR(t.volume, v, 2e-5 * v);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(t.centroid[a], m[a] / v, 1e-4);
}

TEST(Geometry, WedgeVolumeIsAQuarter) {
  // Two perpendicular planes through the centre: a quarter sphere.
  Particle p;
  p.id = 1;
  p.kind = Kind::multi;
  const Sphere s{{5.5, 6.1, 4.9}, 4.2};
  p.pieces.push_back({s, {HalfSpace{{0, 1, 0}, s.c[1]}, HalfSpace{{0, 0, 1}, s.c[2]}}});
  const Truth t = particle_truth(p);
  const double V = kPi * std::pow(s.r, 3) / 3;
  EXPECT_NEAR(t.volume, V, 1e-6 * V);
  EXPECT_NEAR(t.centroid[0], s.c[0], 1e-4);
  // Wedge of dihedral angle π/2: centroid 3√2R/8 from the axis on the bisector, i.e. 3R/8 in y and x.
  EXPECT_NEAR(t.centroid[1], s.c[1] - 3 * s.r / 8, 1e-4);
  EXPECT_NEAR(t.centroid[2], s.c[2] - 3 * s.r / 8, 1e-4);
  EXPECT_TRUE(std::isnan(t.dmax));
}

TEST(Geometry, KindNamesRoundTrip) {
  for (Kind k : {Kind::grain, Kind::half, Kind::multi, Kind::chip, Kind::chipped, Kind::cluster})
    EXPECT_EQ(kind_from_name(kind_name(k)), k);
  EXPECT_THROW(kind_from_name("rock"), std::exception);
}
