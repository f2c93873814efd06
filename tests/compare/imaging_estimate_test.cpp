// Grey levels and noise read back from a scan made by the imaging model with
// known settings.
#include "compare/imaging_estimate.hpp"

#include <gtest/gtest.h>

#include "core/errors.hpp"
#include "data_synth/imaging.hpp"
#include "data_synth/render.hpp"

namespace {
using namespace tg;

// Spheres filling ~30 % of a 64^3 box, imaged with the given options.
Volume<uint16_t> scan(const synth::ImagingOptions& im) {
  std::vector<synth::Particle> ps;
  uint32_t id = 1;
  for (double z : {16.0, 48.0})
    for (double y : {16.0, 48.0})
      for (double x : {16.0, 48.0}) ps.push_back(synth::make_grain(id++, {z + 0.3, y - 0.2, x + 0.1}, 12.5));
  synth::RenderOptions ro;
  ro.labels = false;
  auto r = synth::render(ps, Shape{64, 64, 64}, {}, ro);
  synth::apply_imaging(r.solid, im);
  return synth::to_u16(r.solid).volume;
}

TEST(ImagingEstimate, RecoversLevelsAndNoise) {
  for (double noise : {400.0, 900.0, 1500.0}) {
    synth::ImagingOptions im;
    im.void_grey = 9000;
    im.solid_grey = 38000;
    im.noise_sigma = noise;
    im.psf_sigma = 0.7;
    im.seed = 3;
    const auto sc = scan(im);
    const auto e = compare::estimate_grey_levels(sc);
    // Levels within 1 % of the contrast; noise within 5 %.
    EXPECT_NEAR(e.void_grey, 9000, 0.01 * 29000) << "noise " << noise;
    EXPECT_NEAR(e.solid_grey, 38000, 0.01 * 29000) << "noise " << noise;
    EXPECT_NEAR(e.noise_sigma, noise, 0.05 * noise) << "noise " << noise << " void " << e.sigma_void << " solid " << e.sigma_solid;
    EXPECT_GT(e.threshold, 9000);
    EXPECT_LT(e.threshold, 38000);
    const auto like = compare::imaging_like(e, im);
    EXPECT_EQ(like.void_grey, e.void_grey);
    EXPECT_EQ(like.psf_sigma, im.psf_sigma);  // not estimated: kept
  }
}

TEST(ImagingEstimate, RejectsOneClass) {
  std::vector<int64_t> h(65536, 0);
  h[100] = 1000;
  EXPECT_THROW(compare::estimate_grey_levels(h), InputError);
  EXPECT_THROW(compare::estimate_grey_levels(std::vector<int64_t>(10, 1)), UsageError);
}

}  // namespace
