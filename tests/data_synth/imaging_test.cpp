#include "data_synth/imaging.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstring>

using namespace tg::synth;

TEST(Imaging, BlurPreservesMassAndMatchesGaussianWidth) {
  // A single bright voxel: the blurred second moment along x equals σ².
  tg::Volume<float> v = tg::Volume<float>::filled(tg::Shape{21, 21, 21}, 0.0f);
  v(10, 10, 10) = 1.0f;
  gaussian_blur(v, 1.5);
  double sum = 0, m2 = 0;
  for (int64_t k = 0; k < 21; ++k)
    for (int64_t j = 0; j < 21; ++j)
      for (int64_t i = 0; i < 21; ++i) {
        sum += v(k, j, i);
        m2 += v(k, j, i) * (i - 10.0) * (i - 10.0);
      }
  EXPECT_NEAR(sum, 1.0, 1e-5);
  EXPECT_NEAR(m2 / sum, 1.5 * 1.5, 1e-3);
}

TEST(Imaging, NoiseStatisticsAndThreadIndependence) {
  ImagingOptions o;
  o.psf_sigma = 0;
  o.noise_sigma = 100;
  o.void_grey = 1000;
  o.solid_grey = 3000;
  auto make = [&] {
    tg::Volume<float> v = tg::Volume<float>::filled(tg::Shape{40, 50, 50}, 0.5f);
    apply_imaging(v, o);
    return v;
  };
  omp_set_num_threads(1);
  const auto a = make();
  omp_set_num_threads(2);
  const auto b = make();
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.bytes()), 0);
  double m = 0, s2 = 0;
  for (float x : a.span()) m += x;
  m /= a.size();
  for (float x : a.span()) s2 += (x - m) * (x - m);
  EXPECT_NEAR(m, 2000, 1.0);                           // 100/sqrt(1e5) ≈ 0.3 standard error
  EXPECT_NEAR(std::sqrt(s2 / a.size()), 100, 1.0);
}

TEST(Imaging, PoissonVarianceEqualsMeanInCounts) {
  ImagingOptions o;
  o.psf_sigma = 0;
  o.noise_sigma = 0;
  o.void_grey = 10;  // λ = 10 counts: the inversion sampler
  o.poisson_counts_per_grey = 1;
  tg::Volume<float> v = tg::Volume<float>::filled(tg::Shape{20, 50, 50}, 0.0f);
  apply_imaging(v, o);
  double m = 0, s2 = 0;
  for (float x : v.span()) m += x;
  m /= v.size();
  for (float x : v.span()) s2 += (x - m) * (x - m);
  EXPECT_NEAR(m, 10, 0.05);
  EXPECT_NEAR(s2 / v.size(), 10, 0.3);
}

TEST(Imaging, CuppingDarkensTheCentre) {
  ImagingOptions o;
  o.psf_sigma = 0;
  o.noise_sigma = 0;
  o.cupping = 0.1;
  tg::Volume<float> v = tg::Volume<float>::filled(tg::Shape{1, 64, 64}, 1.0f);
  apply_imaging(v, o);
  EXPECT_NEAR(v(0, 32, 32), o.solid_grey * 0.9, 0.01 * o.solid_grey);
  EXPECT_NEAR(v(0, 32, 0), o.solid_grey * (1 - 0.1 * (1 - std::pow(31.5 / 32, 2))), 1.0);
}

TEST(Imaging, U16ClipsAndCountsSaturation) {
  tg::Volume<float> v(tg::Shape{1, 1, 4});
  v[0] = -5;
  v[1] = 70000;
  v[2] = 1234.4f;
  v[3] = 65535.4f;
  const U16Result r = to_u16(v);
  EXPECT_EQ(r.volume[0], 0);
  EXPECT_EQ(r.volume[1], 65535);
  EXPECT_EQ(r.volume[2], 1234);
  EXPECT_EQ(r.volume[3], 65535);
  EXPECT_EQ(r.saturated_low, 1);
  EXPECT_EQ(r.saturated_high, 1);
}
