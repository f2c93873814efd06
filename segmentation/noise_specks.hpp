// Noise specks: labels that the void's noise lifted above the threshold,
// not particles.
//
// Why. On a noisy scan a global threshold a couple of noise sigmas above
// the void lets through a few per cent of the void's voxels, and now and
// then a handful of them touch: a label of 8-20 voxels that no grain made.
// Their number grows with the volume, not with the grains: data_synth's
// zeolite stage at CNR 5 (threshold 2.0 sigmas above the void) gave 33 such
// labels at 256^3 and 781 beside 789 grains at 512^3, and the tracker then
// counted every one as a grain lost at the next stage (% intact broken
// 57.5 against 70.9). A size floor cannot tell them from real chips of the
// same size; their grey can: a speck's voxels are void voxels that happened
// to exceed t, so its mean lies only a fraction of a sigma above t, while
// any real particle has a core at the solid's grey.
//
// Test (per label of n voxels, grey code values g): under the hypothesis
// "void noise", each voxel is void + sigma Z with Z > z_t = (t - void) /
// sigma, whose excess over t has mean mu0 = lambda - z_t and variance
// s0^2 = 1 + z_t lambda - lambda^2 (lambda = phi(z_t) / Q(z_t), the
// inverse Mills ratio: the truncated normal's moments). The label's mean
// excess m = (mean g - t) / sigma is scored as
//     z = (m - mu0) / (s0 / sqrt(n))
// and the label is noise when z < z_crit (default 5) and it has no core: no
// voxel where the grey smoothed over a voxel (Gaussian sigma 1, as the split
// repair smooths) reaches t. The smoothing averages ~45 voxels, so a speck's
// few bright voxels among the void around them stay near the void level
// (~void + 0.5 sigma for 10 voxels at 2 sigmas), while a particle of radius
// 2 voxels keeps ~0.7 of the contrast at its centre. The second condition
// keeps a real particle whose label the noise padded: where the threshold
// lies only a sigma or so above the void (a noisy scan with little solid),
// a small grain's label gathers a halo of void voxels that pulls its mean
// down to noise level, but its core is still bright. (A first version asked
// for one voxel over void + k sigma instead, k for one false alarm a scan:
// at CNR 4 it cleared 6 of 86 balls of radius 2.5.) void and sigma come from the
// histogram (threshold.hpp phase_levels: the void peak's mode and its lower
// side's sigma, with the voxels a noisy scan clipped at 0 counted there).
// Limit: the n voxels are taken as independent. Noise correlated over a few
// voxels (a reconstruction filter) makes larger, smoother specks whose mean
// varies more than that: their z is overstated and they are kept, as
// without the test (a correction from the smoothed noise's sigma was tried:
// on a scan with 6 % solid that estimate failed and real grains were
// cleared, so it was dropped). Real particles are never at risk from it.
//
// Measured (data_synth zeolite-stages series, 256^3 and 512^3, stages 0
// and 4, every label matched to the truth by majority overlap; CNR 5 to 32,
// PSF 0.5-1.5, gaps 0.5-2.5): noise specks z <= 3.3 (2 500 of them), real
// particles z >= 3.2 for one 8-voxel piece and >= 5.4 for all others (the
// smallest, dim pieces of 8-16 voxels at PSF 1.5); particles of 100 voxels
// and more z >= 28. z_crit = 5 leaves 1.7 above the largest noise score
// seen, for the extreme of many more specks (a 1220^3 scan has 14x the
// voxels of 512^3).
//
// Cost: one pass over the labels and the grey code, by runs of one label
// along x (per-thread integer sums: the result does not depend on the
// thread count); where labels fail the mean test, one more pass to list
// their voxels and the smoothed grey at them (7^3 weights a voxel) until a
// core is found. The caller clears the specks in its renumbering pass.
#pragma once
#include <cstdint>
#include <vector>

#include "core/volume.hpp"

namespace tg {

struct SpeckTest {
  double threshold = 0;     // t, in the grey code's units
  double void_level = 0;    // the void peak's mode, same units
  double sigma = 0;         // the noise sigma, same units
  double z_crit = 5.0;
  int64_t max_candidate_vox = int64_t(1) << 20;  // larger labels are kept without the core test
};

struct SpeckResult {
  bool used = false;
  double mu0 = 0, s0 = 0;  // the noise hypothesis' mean excess and its sigma, in noise sigmas
  int64_t tested = 0;      // labels scored
  int64_t dropped = 0;     // labels cleared as noise
  int64_t dropped_voxels = 0;
  std::vector<uint32_t> keep;  // per label 0..count: itself, or 0 for a speck (a relabel_consecutive premap)
};

// The truncated normal's excess over z_t (header): {mu0, s0}.
struct Excess {
  double mean = 0, sigma = 0;
};
Excess noise_excess_above(double z_t);

// labels 1..count (0 void) and the grey code they were segmented from,
// same shape: scores every label; `keep` maps the specks to 0 (apply it with
// relabel_consecutive's premap; empty when the test could not run).
SpeckResult find_noise_specks(const Volume<uint32_t>& labels, uint32_t count, const Volume<uint8_t>& grey_code,
                              const SpeckTest& test);

}  // namespace tg
