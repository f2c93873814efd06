#include "data_synth/granule.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <set>

#include "data_synth/packing.hpp"
#include "data_synth/partial_volume.hpp"

using namespace tg::synth;

namespace {
double sphere_volume(double r) { return 4.0 / 3.0 * std::numbers::pi * r * r * r; }
}

TEST(Granule, FragmentsWithoutGapRebuildTheSphere) {
  // With gap 0 the pieces tile the sphere: their truth volumes sum to 4πR³/3.
  // Wedge volumes come from the partial-volume quadrature, caps from formulas.
  BreakageOptions o;
  o.gap = 0;
  const Particle g = make_grain(7, {20.3, 19.6, 21.2}, 9.4);
  for (Event e : {Event::split, Event::multi, Event::chip}) {
    const auto frags = fragment(g, e, 100, o);
    double v = 0;
    for (const Particle& f : frags) {
      EXPECT_EQ(f.parent, 7u);
      v += particle_truth(f).volume;
    }
    EXPECT_NEAR(v, sphere_volume(9.4), 1e-6 * sphere_volume(9.4)) << static_cast<int>(e);
    EXPECT_EQ(frags.front().id, 100u);
  }
}

TEST(Granule, SplitHalvesAreSeparatedByTheGap) {
  BreakageOptions o;
  o.gap = 1.5;
  const Particle g = make_grain(3, {0, 0, 0}, 10);
  const auto h = fragment(g, Event::split, 10, o);
  ASSERT_EQ(h.size(), 2u);
  EXPECT_NEAR(particle_truth(h[0]).volume, cap_volume(10, 10 - 0.75), 1e-9);
  EXPECT_NEAR(particle_truth(h[0]).dmin, 10 - 0.75, 1e-12);
  // Centroids lie on opposite sides, 2·(3(2R−h)²/(4(3R−h))) apart.
  const Vec3 a = particle_truth(h[0]).centroid, b = particle_truth(h[1]).centroid;
  const double d = std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
  EXPECT_NEAR(d, 2 * cap_centroid_offset(10, 9.25), 1e-9);
  // No point is in both: the planes' distance equals the gap.
  const HalfSpace &p = h[0].pieces[0].planes[0], &q = h[1].pieces[0].planes[0];
  EXPECT_NEAR(p.n[0] + q.n[0], 0, 1e-12);
  EXPECT_NEAR(-(p.d + q.d), 1.5, 1e-12);
}

TEST(Granule, PoresStayInsideAndFollowFragments) {
  Particle g = make_grain(4, {30, 30, 30}, 12);
  add_pores(g, 5, 0.1, 9);
  ASSERT_EQ(g.pores.size(), 5u);
  for (const Sphere& p : g.pores) {
    const double d = std::hypot(p.c[0] - 30, p.c[1] - 30, p.c[2] - 30);
    EXPECT_LE(d + p.r, 12 - 0.5);
  }
  const double vg = particle_truth(g).volume;
  EXPECT_NEAR(vg, sphere_volume(12) - 5 * sphere_volume(1.2), 1e-9);
  EXPECT_NEAR(particle_truth(g).fr, 1.0, 1e-12);  // pores do not change the shape metrics
  BreakageOptions o;
  o.gap = 0;
  size_t kept = 0;
  for (const Particle& f : fragment(g, Event::split, 50, o)) kept += f.pores.size();
  EXPECT_LE(kept, 5u);
}

TEST(Granule, StageSeriesIsNestedAndOverlapFree) {
  PackingOptions po;
  po.container = Container::box;
  po.height = po.box_y = po.box_x = 60;  // voxel units
  po.d50 = 12;
  po.cu = 1.1;
  const Packing pk = dense_packing(po);
  std::vector<Particle> grains;
  for (size_t q = 0; q < pk.spheres.size(); ++q)
    grains.push_back(make_grain(static_cast<uint32_t>(q + 1), pk.spheres[q].c, pk.spheres[q].r));
  StageOptions so;
  std::set<uint32_t> broken_before;
  double top_before = 1e300;
  for (int s = 0; s < 5; ++s) {
    const auto ps = stage_particles(grains, 0.0, s, so);
    std::set<uint32_t> broken;
    std::vector<Sphere> parents;
    std::set<uint32_t> ids;
    double top = 0;
    for (const Particle& p : ps) {
      EXPECT_TRUE(ids.insert(p.id).second);
      if (p.kind != Kind::grain) broken.insert(p.parent);
      top = std::max(top, p.pieces[0].sphere.c[0] + p.pieces[0].sphere.r);
    }
    // One parent sphere per grain (intact, or the first fragment of a broken one).
    for (const Particle& p : ps)
      if (p.kind == Kind::grain || p.id == static_cast<uint32_t>(grains.size()) + 4 * (p.parent - 1) + 1)
        parents.push_back(p.pieces[0].sphere);
    EXPECT_LE(max_overlap(parents), 1e-9) << "stage " << s;
    for (uint32_t b : broken_before) EXPECT_TRUE(broken.count(b)) << "broken sets must be nested";
    EXPECT_NEAR(static_cast<double>(broken.size()) / grains.size(), so.broken[s], 0.15);
    // Specimen height shrinks with the strain.
    EXPECT_LE(top, top_before + 1e-9);
    broken_before = broken;
    top_before = top;
  }
}
