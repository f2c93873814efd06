// Noise specks (segmentation/noise_specks.hpp): the truncated normal's
// moments against a numerical integral; the z-score on labels of known grey;
// a noisy scan of balls whose void noise made specks comes out with one
// label per ball (and with more without the test); thread-count
// independence.
#include <gtest/gtest.h>

#include <cmath>
#include <omp.h>
#include <random>

#include "data_synth/imaging.hpp"
#include "segmentation/noise_specks.hpp"
#include "segmentation/segment.hpp"

namespace tg {
namespace {

// E[Z - z | Z > z] and its SD by the midpoint rule on [z, z + 40].
Excess integrate_excess(double z) {
  const int n = 400000;
  const double h = 40.0 / n;
  double m0 = 0, m1 = 0, m2 = 0;
  for (int k = 0; k < n; ++k) {
    const double x = z + (k + 0.5) * h, p = std::exp(-0.5 * x * x) * h;
    m0 += p, m1 += p * (x - z), m2 += p * (x - z) * (x - z);
  }
  Excess e;
  e.mean = m1 / m0;
  e.sigma = std::sqrt(m2 / m0 - e.mean * e.mean);
  return e;
}

TEST(NoiseSpecks, ExcessAboveTheThresholdIsTheTruncatedNormals) {
  for (const double z : {-1.0, 0.0, 1.0, 2.0, 3.5, 6.0}) {
    const Excess a = noise_excess_above(z), b = integrate_excess(z);
    EXPECT_NEAR(a.mean, b.mean, 1e-5) << "z " << z;
    EXPECT_NEAR(a.sigma, b.sigma, 1e-5) << "z " << z;
  }
  EXPECT_NEAR(noise_excess_above(0.0).mean, std::sqrt(2.0 / M_PI), 1e-12);  // the half-normal's mean
}

// On a code scale with t = 100, void = 80, sigma 10 (z_t = 2: mu0 =
// 0.37322, s0 = 0.33805), labels apart in void (code 80): a row of 10
// voxels at 104 (m = 0.4: z = 0.25, noise), a row of 10 at 130 (m = 3:
// z = 24.57, kept by its mean), a row of 4 at 110 (m = 1: z = 3.71 < 5,
// noise; with z_crit 3, kept). Rows have no core: the grey smoothed over a
// voxel stays under t along them (80 + 24 w0^2 (1 - w3 ...) < 100).
TEST(NoiseSpecks, ScoresLabelsByTheirMeanGrey) {
  const Shape s{7, 21, 16};
  auto lab = Volume<uint32_t>::filled(s, 0u);
  auto code = Volume<uint8_t>::filled(s, 80);
  for (int64_t i = 3; i < 13; ++i) lab(3, 3, i) = 1, code(3, 3, i) = i % 2 ? 103 : 105;
  for (int64_t i = 3; i < 13; ++i) lab(3, 10, i) = 2, code(3, 10, i) = 130;
  for (int64_t i = 3; i < 7; ++i) lab(3, 17, i) = 3, code(3, 17, i) = 110;
  SpeckTest t;
  t.threshold = 100, t.void_level = 80, t.sigma = 10;
  const SpeckResult r = find_noise_specks(lab, 3, code, t);
  EXPECT_TRUE(r.used);
  EXPECT_NEAR(r.mu0, 0.37322, 1e-4);
  EXPECT_NEAR(r.s0, 0.33805, 1e-4);
  EXPECT_EQ(r.tested, 3);
  ASSERT_EQ(r.keep.size(), 4u);
  EXPECT_EQ(r.keep[1], 0u);
  EXPECT_EQ(r.keep[2], 2u);
  EXPECT_EQ(r.keep[3], 0u);
  EXPECT_EQ(r.dropped, 2);
  EXPECT_EQ(r.dropped_voxels, 14);
  t.z_crit = 3;
  EXPECT_EQ(find_noise_specks(lab, 3, code, t).keep[3], 3u);
  t.sigma = 0;  // no noise measured: the test does not run
  EXPECT_FALSE(find_noise_specks(lab, 3, code, t).used);
}

// A body whose mean is at noise level but whose smoothed grey reaches t is
// kept: blocks at 104 in void 80 (t = 100, void 80, sigma 10). 3^3 voxels:
// z = 0.41, smoothed centre 80 + 24 (w-1 + w0 + w1)^3 = 96.53 < 100: noise.
// 5^3: z = 0.89, centre 80 + 24 (w-2 + ... + w2)^3 = 103.37 >= 100: a core.
TEST(NoiseSpecks, ABodyWithACoreIsKept) {
  const Shape s{13, 13, 26};
  auto lab = Volume<uint32_t>::filled(s, 0u);
  auto code = Volume<uint8_t>::filled(s, 80);
  for (int64_t k = 5; k < 8; ++k)
    for (int64_t j = 5; j < 8; ++j)
      for (int64_t i = 5; i < 8; ++i) lab(k, j, i) = 1, code(k, j, i) = 104;
  for (int64_t k = 4; k < 9; ++k)
    for (int64_t j = 4; j < 9; ++j)
      for (int64_t i = 15; i < 20; ++i) lab(k, j, i) = 2, code(k, j, i) = 104;
  SpeckTest t;
  t.threshold = 100, t.void_level = 80, t.sigma = 10;
  const SpeckResult r = find_noise_specks(lab, 2, code, t);
  EXPECT_EQ(r.keep[1], 0u);
  EXPECT_EQ(r.keep[2], 2u);
  t.threshold = 103.5;  // just above the 5^3 block's smoothed centre
  EXPECT_EQ(find_noise_specks(lab, 2, code, t).keep[2], 0u);
}

// Balls of radius 6 and (every fourth) 2.5 voxels on a grid 15 voxels
// apart, 4^3 supersampled, PSF 0.7, void 10000 / solid 30000, noise sigma
// 5000 (CNR 4: the threshold stands ~2 sigmas above the void).
struct BallScan {
  Volume<uint16_t> grey;
  Volume<uint8_t> solid;  // truth: voxels at least half inside a ball
};

BallScan ball_scan(uint64_t seed) {
  const int64_t n = 112;
  const Shape s{n, n, n};
  Volume<float> phi = Volume<float>::filled(s, 0.f);
  BallScan b;
  int idx = 0;
  for (int64_t cz = 9; cz + 8 < n; cz += 15)
    for (int64_t cy = 9; cy + 8 < n; cy += 15)
      for (int64_t cx = 9; cx + 8 < n; cx += 15, ++idx) {
        const double r = idx % 4 == 3 ? 2.5 : 6.0;
        for (int64_t k = cz - 7; k <= cz + 7; ++k)
          for (int64_t j = cy - 7; j <= cy + 7; ++j)
            for (int64_t i = cx - 7; i <= cx + 7; ++i) {
              int in = 0;
              for (int a = 0; a < 4; ++a)
                for (int c = 0; c < 4; ++c)
                  for (int d = 0; d < 4; ++d) {
                    const double z = double(k - cz) + (a + 0.5) / 4 - 0.5, y = double(j - cy) + (c + 0.5) / 4 - 0.5,
                                 x = double(i - cx) + (d + 0.5) / 4 - 0.5;
                    in += z * z + y * y + x * x <= r * r;
                  }
              phi(k, j, i) = float(in) / 64.f;
            }
      }
  b.solid = Volume<uint8_t>(s);
  for (int64_t q = 0; q < s.voxels(); ++q) b.solid[q] = phi[q] >= 0.5f;
  synth::ImagingOptions im;
  im.void_grey = 10000, im.solid_grey = 30000, im.psf_sigma = 0.7, im.noise_sigma = 5000;
  im.seed = seed;
  synth::apply_imaging(phi, im);
  b.grey = synth::to_u16(phi).volume;
  return b;
}

// Seed 1 was looked at while writing this. Seeds 31-32 were first run with
// an earlier rule (one voxel over void + k sigma), which failed on them and
// was replaced; 41-42 were run once, with the rule as it is.
// Without the test the labels are the balls (two may share one where the
// noise bridged their 3-voxel gap) plus specks, labels that hold no voxel
// of any ball: the test must clear exactly those. With the face slivers
// (face_slivers.hpp) the size floor spares the labels at the faces until
// they have grown, so the test also judges (and clears) the specks there
// under the floor; without it, some of them would grow past the floor.
TEST(NoiseSpecks, ANoisyScanOfBallsKeepsEveryBallAndNoSpeck) {
  for (const uint64_t seed : {31u, 32u, 41u, 42u})
    for (const bool slivers : {false, true}) {
      const BallScan b = ball_scan(seed);
      SegmentOptions o;
      o.grain_radius_vox = 6;
      o.face_slivers = slivers;
      const SegmentResult with = segment(b.grey, o);
      o.noise_specks = false;
      const SegmentResult without = segment(b.grey, o);
      std::vector<uint8_t> on_ball(size_t(without.count) + 1, 0);
      for (int64_t q = 0; q < b.solid.size(); ++q)
        if (b.solid[q]) on_ball[without.labels[q]] = 1;
      int64_t specks = 0;
      for (uint32_t l = 1; l <= without.count; ++l) specks += !on_ball[l];
      EXPECT_GT(specks, 100) << "seed " << seed << ": the scene should hold noise specks";
      EXPECT_TRUE(with.specks.used);
      if (slivers) {
        EXPECT_GT(with.specks.dropped, specks) << "seed " << seed;
      } else {
        EXPECT_EQ(with.specks.dropped, specks) << "seed " << seed;
      }
      EXPECT_EQ(int64_t(with.count), int64_t(without.count) - specks) << "seed " << seed << " slivers " << slivers;
      // Every ball voxel that had a label keeps one (a ball's centre may be
      // on a watershed line or under the threshold at this noise, with or
      // without the test).
      int64_t lost = 0;
      for (int64_t q = 0; q < b.solid.size(); ++q) lost += b.solid[q] && without.labels[q] && !with.labels[q];
      EXPECT_EQ(lost, 0) << "seed " << seed << " slivers " << slivers;
    }
}

TEST(NoiseSpecks, SameSpecksWithOneOrTwoThreads) {
  const BallScan b = ball_scan(33);
  SegmentOptions o;
  o.grain_radius_vox = 6;
  const int before = omp_get_max_threads();
  omp_set_num_threads(1);
  const SegmentResult one = segment(b.grey, o);
  omp_set_num_threads(2);
  const SegmentResult two = segment(b.grey, o);
  omp_set_num_threads(before);
  EXPECT_EQ(one.specks.dropped, two.specks.dropped);
  ASSERT_EQ(one.count, two.count);
  for (int64_t q = 0; q < one.labels.size(); ++q) ASSERT_EQ(one.labels[q], two.labels[q]) << "voxel " << q;
}

}  // namespace
}  // namespace tg
