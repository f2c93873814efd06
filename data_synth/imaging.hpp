// Imaging model: turns a solid-fraction volume into what a CT reconstruction
// looks like, in this order:
//   1. grey  g = void_grey + (solid_grey − void_grey) · φ        (linear partial volume)
//   2. blur  separable Gaussian point-spread function, σ = psf_sigma voxels,
//            kernel truncated at 4σ, borders replicated
//   3. cupping (beam hardening): g *= 1 − cupping · (1 − (r/r_edge)²), r the
//            distance from the rotation axis (z axis at the slice centre),
//            so the centre is darker by `cupping` (relative) than the edge
//   4. rings: `rings` concentric rings of width 1 voxel at radii drawn from the
//            seed, each adding ±ring_amplitude grey levels
//   5. noise: Poisson (photon counting: g → Poisson(g·k)/k with
//            k = poisson_counts_per_grey; 0 = off; normal approximation above
//            λ = 50) then additive Gaussian of σ = noise_sigma grey levels.
// Every random number is a pure function of (seed, voxel index), so the output
// does not depend on the thread count. Float output is the "reconstruction";
// to_u16() rounds and clips to [0, 65535] (saturated voxels are counted).
// Cost: O(N) per step; the blur is 3 passes of O(N·(8σ+1)).
#pragma once
#include <cstdint>

#include "core/volume.hpp"

namespace tg::synth {

struct ImagingOptions {
  double void_grey = 9000;            // grey level of void (air)
  double solid_grey = 38000;          // grey level of solid
  double psf_sigma = 0.7;             // Gaussian PSF σ, voxels (0 = none)
  double noise_sigma = 900;           // additive Gaussian noise σ, grey levels (0 = none)
  double poisson_counts_per_grey = 0; // Poisson noise: photons per grey level (0 = none)
  double cupping = 0;                 // relative darkening at the axis (0 = none)
  int rings = 0;                      // number of ring artefacts
  double ring_amplitude = 0;          // grey levels per ring
  uint64_t seed = 1;
};

// In place: `solid` (φ in [0, 1]) becomes the grey "reconstruction".
void apply_imaging(Volume<float>& solid, const ImagingOptions& options);

// Separable Gaussian blur, in place (exposed for tests).
void gaussian_blur(Volume<float>& v, double sigma);

struct U16Result {
  Volume<uint16_t> volume;
  int64_t saturated_low = 0, saturated_high = 0;  // voxels clipped at 0 / 65535
};
U16Result to_u16(const Volume<float>& grey);

}  // namespace tg::synth
