// Grey-level (partial-volume) volume of every label: the particle volume the
// scan's grey levels imply, not the count of labelled voxels.
//
// Why: the label volume is a biased volume estimate. The watershed's void
// lines (../shared/DESIGN.md: "separating voxels are set to void") take a
// 1-1.7 voxel layer off every contact: ~0.8 % of an intact grain's voxels at
// radius 20 voxels, ~2.7 % of a split half's (its whole cut face is a line);
// and a global threshold a little above the half-contrast level shifts the
// whole surface inwards on blurred data (~0.9 % at R 20). Both grow as 1/R.
// The grey levels still hold that volume: a voxel whose grey value is g
// holds the solid fraction f = (g - void) / (solid - void) of its volume
// (the linear two-material mixture model of partial volume, e.g. Laidlaw,
// Fleischer & Barr 1998, IEEE Trans. Med. Imaging 17(1):74-86; on the
// threshold-driven systematic error of voxel counts, growing with surface
// over volume: Lin et al. 2015, Computers & Geosciences 77:1-7,
// doi:10.1016/j.cageo.2014.12.008), and a point-spread
// function moves grey between neighbouring voxels but keeps its sum, so
// summing f over a band around a surface returns the solid volume inside it
// whatever the blur, as long as the band is wider than the blur.
//
// Method. For label L (scaled by its own solid level: below),
//   V_L = #(interior voxels of L)
//       + sum over boundary voxels v of L of f(g_v)
//       + sum over unlabelled voxels v touching L of f(g_v) * n_L(v) / n(v)
// where a boundary voxel has a face neighbour (6-neighbourhood) that is not L
// or lies outside the volume (label_stats.hpp's definition), an unlabelled
// voxel touches L when one of its 26 neighbours is L, n_L(v) counts those
// and n(v) counts its labelled 26-neighbours of any label: a void-line voxel
// between two grains is shared between them by how much of it each one
// wraps, a gap voxel between two fragments likewise (its f is low), and an
// unlabelled voxel touching one particle only gives it all of its f.
// Interior voxels count 1, not f: they carry no partial volume, and under
// cupping (beam hardening darkens a scan's centre by up to 30 % of the
// contrast) f of deep solid would be far from 1 (blind sweep, cupping 0.3:
// median |dV/V| 9.6 % with f everywhere, 2.6 % with interior 1; the labels
// alone 5.7 %). Filled pores are interior: the volume is the envelope's, as
// the label's (segmentation/pore_filter.hpp fills them on purpose).
// (Those figures: the blind sweep's prototype on dev seed 1; the sweep's
// own figures are in bench/segmentation/RESULTS.md.)
// f is not clamped to [0, 1]: noise (sigma 0.08 of the contrast at CNR 13)
// then averages out over the band instead of biasing it upwards (clamping at
// 0 adds ~0.03 per shell voxel, +0.5 % at R 20); it is clamped to [-1, 2]
// so that a stray saturated or zeroed voxel cannot dominate, and grey 0
// counts as void (pre-masked voxels, docs/real_scans.md).
// The band is one voxel on each side of the labelled surface: enough for a
// PSF sigma up to ~1 voxel (blind sweep, PSF 1.5: 1.11 % vs 3.38 % for the
// labels; a wider band would need each far voxel's nearest label).
//
// Levels: the void and solid grey levels are the modes of the two phases'
// histogram peaks (segmentation/threshold.hpp phase_levels); the scan's own
// levels, not the threshold: a threshold away from half-contrast would bias
// every f.
// Local solid level: where the contrast varies across the scan (beam
// hardening darkens its centre; grains of another density or inner
// porosity), the scan's one solid level reads a dim grain's band as partly
// void. So each label's band is read against its own level:
// V_L = inner + band_L x (solid - void) / (M_L - void), where M_L is the
// mean grey of L's core voxels (all 26 neighbours L's and at least half way
// from void to solid: two voxels from its surface, where the blur hardly
// dims, and off the walls of its filled pores); a label with fewer than
// min_solid_voxels such voxels keeps the scan's level (scale 1), and the
// scale stays within [kMinBandScale, kMaxBandScale]. The core is sampled
// on every kCoreRowStride-th row of each slice (the level needs hundreds of
// voxels, not all). Measured
// (bench/segmentation/RESULTS.md "Local solid level"; blind_scene.py 192^3
// R 20, seeds 1-2, median |dV/V|): cupping 0.15 / 0.3 1.3-1.4 / 2.8-3.0 % ->
// 0.3 / 0.31-0.34 %; middle setting 0.42 / 0.47 -> 0.33 / 0.36 %; CNR 8
// 0.35 -> 0.29 %, PSF 1.0 0.73 -> 0.61 %; but CNR 5 0.33 / 0.36 -> 0.81 /
// 0.77 % (the histogram's solid mode sits 2.5 % of the contrast low there,
// which had made up for what the one-voxel band misses), PSF 1.5 1.21 / 1.22
// -> 1.25 / 1.31 %, R 8 1.60 / 1.60 -> 1.90 / 1.58 %. A ratio to the mean of
// all labels' cores instead of the scan's level was tried: neutral at CNR 5,
// but a scan with some grains dimmer than the rest then moves the others
// (two balls, one at 0.7 of the contrast: the bright one -3.7 %).
// Cost: `measure --grey` at 256^3 0.76 -> 0.78 s (the core test on every
// row: 0.08 s).
//
// Determinism: each voxel's contribution is rounded to a fixed point of
// 2^-24 voxel and summed as integers, so the volumes are bit-identical for
// any thread count (per-thread sums over z slabs, merged in any order).
// Cost: one pass, O(V) with a 26-neighbour look-up per unlabelled voxel next
// to a label; O(L * T) memory for L labels and T threads.
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "core/volume.hpp"

namespace tg::measure {

struct GreyVolumeOptions {
  double void_grey = 0;   // grey level of pure void (the void peak's mode)
  double solid_grey = 0;  // grey level of pure solid (the solid peak's mode); must exceed void_grey
  int threads = 0;        // OpenMP threads; 0 = the OpenMP default
  // Local solid level (header): each label's band scaled by the contrast of
  // all labels' inner solid over its own; labels with fewer inner solid
  // voxels than min_solid_voxels keep the scan's levels.
  bool local_solid = true;
  int64_t min_solid_voxels = 256;
};

// The band's scale is kept within these (a label whose inner solid is
// under half the typical contrast is not solid the levels describe).
inline constexpr double kMinBandScale = 0.5, kMaxBandScale = 2.0;
// The core is sampled on every kCoreRowStride-th row (y) of each slice;
// min_solid_voxels counts the core voxels those stand for.
inline constexpr int64_t kCoreRowStride = 4;

// Volume in voxels of each label of `ids` (ascending, as label_stats lists
// them; the result is aligned with it), from the grey scan the labels were
// segmented from. Labels not in `ids` are ignored. The two volumes must have
// the same shape (UsageError otherwise, and when solid_grey <= void_grey or
// `ids` is not ascending).
std::vector<double> grey_volumes(const VolumeView<const uint32_t>& labels, const VolumeView<const uint16_t>& grey,
                                 const std::vector<uint32_t>& ids, const GreyVolumeOptions& opt);

// What the volumes are made of, per label of ids, as exact integers that
// add up over slabs (measure_chunked.hpp): inner voxels and the band's f in
// fixed point (grey_volume_units per voxel; f from the scan's levels), and
// the grey sum and count of the inner voxels at least half way to solid.
struct GreyVolumeSums {
  std::vector<int64_t> inner, band, solid_grey, solid_count;
  void resize(size_t n);                                    // n labels, all zero
  size_t append();                                          // one more label, zero; its row
  void add(size_t to, const GreyVolumeSums& o, size_t from);  // label `from` of o into label `to`
};

// The sums of the voxels of slices [core_begin, core_end) of two windows:
// slabs of larger volumes that hold the slices just below and above the
// core unless it reaches a face of the volume (as label_sums).
GreyVolumeSums grey_volume_sums(const VolumeView<const uint32_t>& labels, const VolumeView<const uint16_t>& grey,
                                const std::vector<uint32_t>& ids, const GreyVolumeOptions& opt, int64_t core_begin,
                                int64_t core_end);
// Volumes in voxels from the sums of every slab (header: inner + band x the
// label's scale). The reference contrast is that of all the labels summed.
std::vector<double> grey_volumes_from_sums(const GreyVolumeSums& sums, const GreyVolumeOptions& opt);
inline constexpr double grey_volume_units = 16777216.0;  // 2^24 per voxel

// A grey scan read slab by slab: slices [z0, z0 + nz) of it, valid until
// the next call (a source keeps one buffer and reads into it, so a pass
// over the scan touches no fresh pages after its first slab).
using GreySlabSource = std::function<const Volume<uint16_t>&(int64_t z0, int64_t nz)>;

// grey_volumes with the scan read window by window (a core of slices and
// the slice on either side, `window_slices` in all, at least 3): only a
// window of the scan is ever in memory, and the volumes are the same (the
// windows' integer sums add up to the whole volume's). InputError when the
// source gives a window of another shape.
std::vector<double> grey_volumes(const VolumeView<const uint32_t>& labels, const GreySlabSource& grey,
                                 const std::vector<uint32_t>& ids, const GreyVolumeOptions& opt,
                                 int64_t window_slices);
// The window for a scan of this shape: about 256 MiB of grey, >= 3 slices.
int64_t grey_window_slices(const Shape& s);

}  // namespace tg::measure
