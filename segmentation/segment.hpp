// The whole image pipeline, one function for both worlds (scans and
// voxelised DEM snapshots, ../shared/DESIGN.md "Data flow"):
//
//   grey u16 -> field of view, pre-masked zeros, saturation (field_of_view)
//            -> threshold (global Tsai, or local) -> graded mask (void, dim,
//               bright: the grey evidence below) -> pore filter (void pores,
//               then dim pockets) -> distance map to void or dim
//            -> h-maxima markers -> watershed (lines) -> merge repair
//               (bright interfaces, one best partner per label)
//            -> consecutive labels with a size filter
//            -> split repair (a label whose smoothed grey holds two bright
//               cores parted by a darker sheet: split_labels.hpp)
//            -> thin pieces (a chip pressed on a grain: split_labels.hpp
//               split_thin_pieces) -> face caps -> labels u32
//
// Each stage is its own header (threshold, pore_filter, distance_transform,
// markers, watershed, merge_labels, connected_components), with the method
// and its reference there; this file only chains them and records what was
// chosen, how long each stage took and the peak memory.
//
// Memory (why the stages are ordered and buffers reused this way): the grey
// volume (2 B/voxel) is needed only for the histograms, the mask and a
// one-byte code of it that the split repair reads after the watershed
// (split_labels.hpp GreyCode; not made with --no-split, --threshold local
// or a plain mask); the rvalue overload writes the u8 mask over the grey
// volume's own storage.
// The pore filter works on runs of void voxels (no label volume). Then the
// float distance map (4 B) is made; the mask goes (the map is 0 exactly
// on the void); the map becomes 16-bit fixed point over its own storage
// (distance_transform.hpp FixedDistance: 1/256 voxel, the spent 2 B given
// back), the u32 markers (4 B) come; the flood levels (u8) are written over
// the fixed-point map's storage; the watershed labels and the merge are in
// place in the markers' volume. At most 6 B/voxel at peak (markers beside
// the fixed-point map; 7 with the split repair's grey code), plus the frontier queue (4 B per queued voxel, a
// small fraction of the volume) and the process itself. Measured (peak RSS
// of the whole `tomograin segment` process): 7.4 B/voxel at 256^3 (the
// process is ~1 B/voxel at that size), 6.03 B/voxel on a 1220^3 zeolite
// scan (10.9 GB; 8.05 with the float map beside the markers, labels
// identical). A float map made the markers 8 B/voxel at peak.
// No 64-bit label or index volumes.
//
// Distances are in units of the smallest voxel edge (anisotropic voxels
// use the ratios of Geometry::voxel_size_m; unknown size = isotropic).
//
// Grey evidence (where the geometry alone is ambiguous). The two halves of
// a split grain lie a voxel or two apart; blur fills such a gap halfway and
// noise then bridges it above the threshold, so the solid mask alone joins
// the halves (one distance maximum, one marker, or a wide interface that
// the merge repair glues). The gap stays darker than solid even where it
// is bridged (partial volume), while an interface cut through one grain is
// as bright as its interior. So the mask is graded (threshold.hpp
// binarise_graded): solid voxels darker than
//   t_bright = t + bright_fraction * (mean solid grey - t)
// are *dim* (the partial-volume shell of every surface, blurred gaps,
// noise). Then
//   * the pores are filled twice: void pores (as before, filled bright,
//     and the dim voxels within pore_shell_vox of them: their
//     partial-volume shell, enclosed or not), then the dim pockets
//     enclosed by bright solid (shells of pores the first pass could not
//     reach, noise specks inside grains; up to twice the pore volume, any
//     shape), so that neither seeds a marker nor parts a grain;
//   * the distance map is the distance to the nearest void *or dim* voxel:
//     it dips to 0 in a bridged gap, so each half keeps its own maximum and
//     marker; dim solid voxels get the lowest solid level (a component made
//     of dim voxels only still gets its marker) and are flooded last, so the
//     watershed line runs through the gap;
//   * the merge repair counts only the bright part of an interface
//     (merge_labels.hpp).
// bright_fraction 0.5 puts the centre of a 1-voxel gap blurred with sigma
// 0.7 (grey ~0.48 of the contrast above void) among the dim voxels. Noise
// sets a floor: t_bright is also at most bright_sigmas (3) noise sigmas
// below the solid's peak (threshold.hpp solid_peak), so that a bright
// voxel is taken for dim with probability Phi(-3) = 0.13 % at most: specks
// that stay apart and that the second pore pass fills. (Halfway alone took
// 10 % of the solid for dim at CNR 5: the specks joined up, 26-connected,
// into a network reaching the void, and the distance map fell apart: F1
// 0.36 on an independent scan.) The trade, blind sweep seeds 1-3: a
// 2-sigma floor keeps a wider band on noisy scans (CNR 8: F1 0.96 vs 0.90)
// but under strong cupping (30 % of the contrast lost at the centre) the
// centre's grains fall into the band and over-segment (F1 0.80 vs 0.95);
// CNR 13 is the same at both. 3 is never worse than the plain mask's chain
// on the sweep; --bright-sigmas 2 suits noisy scans with even brightness.
// At CNR ~6 and below the floor reaches the threshold, nothing is dim and
// the chain runs as on the plain mask (noted in the summary). A plain 0/1
// mask (segment_mask: voxelised packings) has no grey evidence: the
// stages run as on a mask whose solid is all bright.
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/volume.hpp"
#include "segmentation/face_slivers.hpp"
#include "segmentation/field_of_view.hpp"
#include "segmentation/grain_levels.hpp"
#include "segmentation/local_threshold.hpp"
#include "segmentation/merge_labels.hpp"
#include "segmentation/noise_specks.hpp"
#include "segmentation/pore_filter.hpp"
#include "segmentation/split_labels.hpp"
#include "segmentation/threshold.hpp"
#include "segmentation/watershed.hpp"

namespace tg {

// A physical grain radius in the distance map's unit, the finest voxel edge
// (an anisotropic scan's z edge may be the finest, not x). UsageError when
// the geometry has no voxel size.
double grain_radius_in_voxels(double radius_m, const Geometry& geometry);

struct SegmentOptions {
  // Expected grain radius in voxels of the finest edge (grain_radius_in_voxels):
  // the scale the defaults below derive from.
  double grain_radius_vox = 20.0;

  // Tsai. ThresholdMethod::automatic (the phases' midpoint where the noise
  // allows it, threshold.hpp auto_threshold) is an option, not the default:
  // on held-out seeds 201-202 it did not beat Tsai (bench/segmentation/RESULTS.md).
  ThresholdMethod threshold = ThresholdMethod::moments;
  int manual_threshold = -1;  // grey level for ThresholdMethod::manual (voxels above are solid)
  int64_t local_window_vox = 0;  // ThresholdMethod::local: block edge; 0: 4 R (default_local_window)

  // Which voxels are data (field_of_view.hpp): the circular field of view
  // (detected from a constant outside, given, or none) and the input's top
  // grey level, whose saturation is screened (255 for 8-bit scans).
  FovOptions fov;
  int saturation_level = 65535;

  bool fill_pores = true;
  int64_t pore_max_volume_vox = -1;  // < 0: 2 % of the expected grain volume (PoreFilterOptions::from_grain_radius)
  double pore_min_sphericity = 0.5;

  // Marker depth (h-maxima dynamic), distance units; < 0: from the grain
  // radius, h = max(0.5, 0.035 R). 0.5 voxels: the staircase ripples of a
  // digital distance map stay below it, and fragments pressed on their
  // neighbours keep a marker: a half or a quarter of a grain has half its
  // grain's depth, and the neck of a contact rises within a voxel of it
  // (session 35, bench/segmentation/RESULTS.md "Marker depth for scans full
  // of fragments": at the last stage of stage series, 70 % of the grains
  // broken, floor 0.7 -> 0.5 gave F1 0.927 -> 0.944 on data_synth 256^3
  // [R 11.6], 0.900 -> 0.918 and 0.817 -> 0.855 on another generator's
  // R 12 and R 8 windows; its intact R 8 scenes -0.002 to -0.006). Bumps and
  // concavities of a grain's outline grow with the grain, and so do the
  // spurious maxima they leave, hence the share of R above R = 20. Measured
  // on blind_scene.py scans (dev seeds 1, 3, 4): R 40: h 0.7 -> F1 0.982,
  // 1.5 -> 0.994, 2.5 -> 0.988; R 20: h 0.7 -> 0.972, 1.0 -> 0.966;
  // R 12: 0.45 -> 0.960, 0.7 -> 0.963. (Earlier, data_synth zeolite stages
  // at R = 22.7: h = 0.7 -> F1 0.980/0.989 broken/intact; 2.3 -> 0.91/0.98.)
  double h = -1;
  int connectivity = 26;
  bool watershed_lines = true;
  double buckets_per_unit = 4.0;

  bool merge = true;
  double merge_ratio = 1.0;  // MergeOptions::ratio

  // Grey evidence (header): solid darker than t + bright_fraction (mean
  // solid grey - t) is dim. false: the plain solid mask decides alone.
  bool grey_evidence = true;
  double bright_fraction = 0.5;
  double bright_sigmas = 3.0;  // and t_bright <= solid peak - bright_sigmas * its noise sigma
  // Dim voxels within this many steps (6-connected, through dim voxels) of
  // a filled pore are bright: its partial-volume shell (pore_filter.hpp
  // brighten_pore_shells). 0: only enclosed shells are filled.
  int pore_shell_vox = 3;

  int64_t min_size_vox = 8;  // labels smaller than this become void (after merging)

  // Split repair (split_labels.hpp): grey scans with a global threshold.
  // depth = max(split_depth_sigmas x the smoothed solid's noise sigma,
  // split_min_depth_contrast x (solid peak - threshold)).
  // split_smoothing_vox 0 (default): chosen from the scan's noise, the
  // least of kSplitSmoothingLadder whose depth stays within
  // kSplitDepthShare of the solid's height above the threshold (below).
  bool split = true;
  double split_smoothing_vox = 0;
  double split_depth_sigmas = 6.0;
  // ... and this many (if fewer) where the noise is correlated (the void's
  // smoothed sigma over kCorrelatedNoiseRatio x white noise's): fewer
  // independent dips for noise to fake a gap with, and a gap's dip
  // smoothed as much.
  double split_depth_sigmas_correlated = 4.0;
  double split_min_depth_contrast = 0.1;  // floor for noiseless scans
  double split_min_piece_fraction = 0.005;
  // Face caps (split_labels.hpp split_face_caps): with the split repair.
  bool face_caps = true;
  // Thin pieces (split_labels.hpp split_thin_pieces): with the split repair.
  // thin_piece_radius_vox 0 (default): max(3, 0.15 grain_radius_vox).
  bool thin_pieces = true;
  double thin_piece_radius_vox = 0;
  // Their walls merged (merge_labels.hpp merge_thin_walls) only where grains
  // are deeper than r: a half of a grain of radius R is about R / 2 deep,
  // less the dim rim of about a voxel. Below R = 2 (r + 1) the grains are
  // thin throughout themselves, and the merge glued small grains pressed on
  // one another (blind scenes R 5-7: F1 -0.0004 to +0.05 without it; R 8 with
  // it: +0.0002 and +0.0016 on 36 sweep scenes). On resolved options.
  bool merges_thin_walls() const { return grain_radius_vox >= 2 * (thin_piece_radius_vox + 1); }

  // Face slivers (face_slivers.hpp): grains the scan's faces cut a voxel or
  // two from their edge keep their partial-volume voxels (grey scans with a
  // global threshold).
  bool face_slivers = true;

  // Noise specks (noise_specks.hpp): labels whose grey says "void noise
  // above the threshold" are cleared (grey scans with a global threshold).
  bool noise_specks = true;
  double speck_z = 5.0;

  // Grains of different brightness (grain_levels.hpp): each grain's grey
  // raised to the brightest grains' level before the threshold, where the
  // smoothed solid peak is >= GrainLevelsOptions::min_spread_ratio times as
  // wide as the grey varies inside a grain, or a darker population has a
  // peak of its own (dim_population) (with the split repair's histograms,
  // whole volumes and slab by slab).
  bool grain_levels = true;

  // Resolved values (derived defaults filled in), as the pipeline will use them.
  SegmentOptions resolved() const;
};

struct SegmentResult {
  Volume<uint32_t> labels;  // 0 void, 1..count particles, geometry of the input
  ThresholdResult threshold;
  double solid_fraction = 0;  // after thresholding, before pore filling; of the voxels inside the field of view
  FieldOfView fov;            // inactive when the whole volume is data
  LevelScreen levels;         // pre-masked zeros, saturation
  LocalThreshold local;       // ThresholdMethod::local only
  PoreFilterOptions pore_criteria;
  PoreFilterResult pores;
  bool graded = false;          // grey evidence used (a grey scan and grey_evidence)
  uint16_t bright_value = 0;    // graded: voxels above this grey level are bright
  double solid_noise_sigma = 0; // graded: the solid peak's noise sigma (threshold.hpp solid_peak)
  double dim_fraction = 0;      // graded: dim voxels / solid voxels, after the pore passes
  PoreFilterResult dim_pockets; // graded: the second pore pass (dim pockets enclosed by bright solid)
  int64_t pore_shell_voxels = 0;  // graded: dim voxels of the filled pores' shells made bright
  double h = 0;
  uint32_t markers = 0;
  double buckets_per_unit = 0;  // watershed levels per distance unit actually used (see quantise_levels)
  MergeResult merge;
  bool merge_own_levels = false;  // the merge's share test read each pair's own level (MergeOptions::grey)
  bool split_used = false;        // the split repair ran (a grey scan, a global threshold, split on)
  double smoothed_noise_sigma = 0;// the smoothed grey's noise sigma the depth is from, grey levels (split_labels.hpp)
  double smoothed_solid_sigma = 0;     // the smoothed solid peak's sigma
  double within_grain_sigma = 0;       // the smoothed grey's inside grains (0: too few pairs)
  int64_t within_grain_pairs = 0;
  bool split_noise_within_grains = false;  // the depth from the sigma inside grains (narrower than the solid's peak)
  double split_noise_correlation = 0;  // the void's smoothed sigma / white noise's (0: not measured)
  double split_depth_sigmas_used = 0;  // split_depth_sigmas, or ..._correlated where the noise is correlated
  double split_smoothing_vox = 0; // the Gaussian sigma the split repair read the grey with (chosen or given)
  double split_depth = 0;         // grey levels
  GreyCode split_code;
  SplitResult split;
  bool thin_pieces_used = false;     // the thin-piece repair ran (with the split repair, thin_pieces on)
  double thin_piece_radius_vox = 0;  // the opening's radius it used
  ThinPieceResult thin_pieces;
  bool thin_walls_used = false;    // the wall merge ran (thin pieces on, grains deep enough: segment.cpp)
  WallMergeResult thin_walls;      // with the thin-piece repair: walls put back together (merge_thin_walls)
  bool face_caps_used = false;  // the face-cap repair ran (with the split repair, face_caps on)
  FaceCapResult face_caps;
  GrainLevelsResult grain_levels;  // used: the scan was levelled before the threshold
  bool face_slivers_used = false;  // the face-sliver step ran
  FaceSliverResult face_slivers;   // the step's counts (whole runs; null in a chunked summary)
  double void_level = 0;           // the void's grey peak (0: not known)
  SpeckTest speck_test;     // grey levels (not the code's units)
  SpeckResult specks;
  uint32_t count = 0;       // final labels
  int64_t dropped = 0;      // labels removed by min_size_vox
  std::vector<std::pair<std::string, double>> stage_seconds;
  int64_t peak_rss_bytes = 0;
  std::vector<std::string> notes;  // special cases met (two grey levels, no void, ...)
};

// Runs the chain; the rvalue overload takes the grey volume and writes the
// mask over it (no second volume). Throws InputError for degenerate input
// (e.g. a constant volume) and UsageError for invalid options.
SegmentResult segment(const Volume<uint16_t>& grey, const SegmentOptions& opt);
SegmentResult segment(Volume<uint16_t>&& grey, const SegmentOptions& opt);

// From a solid mask on (threshold already applied; the mask is consumed).
SegmentResult segment_mask(Volume<uint8_t> solid, const SegmentOptions& opt);

// ---- The pieces of segment() that a scan larger than memory runs slab by
// slab (segment_chunked.hpp); segment() itself is made of them.

// The decisions that need the whole scan: which voxels are data (field of
// view, pre-masked zeros, saturation), the threshold chosen on the
// histogram of those voxels, and the grey level above which solid is
// bright (grey evidence; 0 when not graded).
struct GreyDecisions {
  FieldOfView fov;
  LevelScreen levels;
  ThresholdResult t;
  LocalThreshold local;  // ThresholdMethod::local only (segment() alone: it needs the volume)
  bool graded = false;
  uint16_t bright = 0;
  double noise_sigma = 0;  // the solid peak's (graded only)
  // Split repair: the smoothed solid's noise sigma (from the sample slices'
  // histogram, smoothed_sample_histogram) and the depth it sets; 0: off.
  double smoothed_sigma = 0;
  double split_depth = 0;
  double split_smoothing = 0;  // sigma_s, voxels, that smoothed_sigma and split_depth are for
  // The smoothed solid peak's sigma and the smoothed grey's inside grains
  // (split_labels.hpp within_grain_sigma); noise_within_grains: the peak
  // was wider than what varies inside a grain: the depth is from the latter.
  double smoothed_solid_sigma = 0, within_grain_sigma = 0;
  int64_t within_grain_pairs = 0;
  bool noise_within_grains = false;
  double noise_correlation = 0;  // the void's smoothed sigma / white noise's, at split_smoothing (0: not measured)
  double depth_sigmas = 0;       // the sigmas split_depth is
  GreyCode split_code;  // the one-byte grey it reads (0.1th..99.9th percentile of the histogram)
  double solid_level = 0;  // the solid's grey peak (split repair on): the face-cap repair's dip
  // Noise specks: the test in grey levels (sigma 0: off); it reads the same code.
  SpeckTest speck_test;
  double void_level = 0;  // the void's grey peak (noise specks or face slivers on; 0: unknown)
  // Grain levels (grain_levels.hpp), from the smoothest of the split
  // repair's sample histograms: its solid peak and void sigma (0: none).
  double levels_void = 0, levels_solid = 0, levels_void_sigma = 0;
  DimPopulation levels_dim;  // a population of darker grains in that histogram
};

// The split repair's smoothing, chosen from the noise when not given
// (split_smoothing_vox 0). Why: a chip or fragment 2-3 voxels thin keeps a
// bright core under 0.7 voxel of smoothing and loses it under 1 voxel
// (its peak sinks to the sheet's level), while the depth a piece must
// stand out by, 6 sigma of the smoothed noise, is 1.7x larger at 0.7 than
// at 1 (white noise falls as sigma_s^-3/2); once that depth passes half the
// solid's height above the threshold, the dip of a 1-voxel gap cannot
// reach it and the halves of split grains stay glued. So: the least sigma of
// the ladder whose depth is <= kSplitDepthShare x (solid peak - threshold),
// else the largest. Measured (bench/segmentation/RESULTS.md, "The split
// repair's smoothing from the noise"): 0.7 chosen from CNR ~7 up; on blind_scene
// scans (R 20, dev seeds 1-3) 0.7 against 1.0 keeps F1 within +0.003 at
// every gap, PSF, CNR >= 5, pore and R point, and loses halves at CNR 4
// (59 -> 44 of 61, seed 2), where the rule keeps 1.0.
inline constexpr double kSplitSmoothingLadder[] = {0.7, 1.0};
inline constexpr double kSplitDepthShare = 0.5;
// The split repair's noise: the smoothed grey's sigma inside grains where
// it is below the smoothed solid peak's (grains of different brightness
// widen the latter; segment.cpp threshold_from_histogram) and at least
// kWithinGrainMinPairs pairs measured it. The pairs counted are those
// whose level lies kWithinGrainClearShare of the way from the threshold to
// the solid's peak or above, clear of the partial volume round surfaces and
// pores (all pairs above the threshold where fewer than the minimum are).
// Partial volume widened the sigma most where grains are small: at R 8,
// grain contrast 0.85-1, 859 grey levels against 582 clear of it (the void's
// noise, smoothed as white noise, gives about 420), a depth of 5155 that a
// 1-voxel gap's dip could not pass, 70 of 108 halves (94 with the cut);
// bench/segmentation/RESULTS.md "The split repair's noise, clear of the
// partial volume".
inline constexpr int64_t kWithinGrainMinPairs = 500;
inline constexpr double kWithinGrainClearShare = 0.3;
// Grain levels raise every grain to this percentile of the smoothed solid's
// grey (grain_levels.hpp): the brightest grains' level. (The mode, where
// most grains happen to lie, gave F1 0.926 / 0.958 against 0.953 / 0.968 on
// the dev scenes: bench/segmentation/RESULTS.md "Grains of different
// brightness: each grain's own level".)
inline constexpr double kGrainLevelsSolidShare = 0.99;
// The noise is correlated (split_depth_sigmas_correlated) where the void's
// sigma after the split repair's smoothing is over this many times white
// noise's (split_labels.hpp white_noise_gain). blind_scene.py R 20 and the
// tests' split balls: white 1.0-1.2, correlated over 0.7 / 1.5 voxels
// 2.1-2.9 / 2.8-5.1. Session 26 measured 4 sigmas on correlated noise: no
// intact grain cut on 12 scenes (CNR 5-13, correlation 0.7-1.5), halves
// back at CNR 8 (white noise: 3 cut on 10); bench/segmentation/RESULTS.md
// "Correlated noise" and "Correlated noise: the depth from fewer sigmas".
inline constexpr double kCorrelatedNoiseRatio = 1.8;
// The sigmas whose smoothed sample histograms decide_grey needs: the given
// one, or the ladder.
std::vector<double> split_smoothing_candidates(const SegmentOptions& opt);

// From the field of view (FovScan or given_field_of_view) and the 65536-bin
// histogram of the voxels inside it (histogram_in_fov, summed over slabs),
// and those of the smoothed sample slices (smoothed_sample_histogram), one
// per split_smoothing_candidates(opt) in that order (empty when opt.split
// is off), with their pairs (none: the solid peak's sigma is the noise).
// UsageError for ThresholdMethod::local; InputError for an empty histogram
// or a saturated scan, as segment().
GreyDecisions decide_grey(FieldOfView fov, std::vector<int64_t> hist,
                          const std::vector<std::vector<int64_t>>& smoothed_hists, const SegmentOptions& opt,
                          const std::vector<std::vector<int64_t>>& pair_hists = {});

// Puts the decisions into a result: threshold, bright level, field of
// view, level screen, and their notes (segment() does the same).
void record_decisions(SegmentResult& r, GreyDecisions d, const SegmentOptions& opt, const Shape& whole);

// Grain levels (grain_levels.hpp): the smoothed solid peak's width over the
// grey's variation inside a grain (0: not measured), whether the scan is to
// be levelled (the option, the ratio, the levels known), and the levels.
double grain_spread_ratio(const GreyDecisions& d);
bool grain_levels_wanted(const GreyDecisions& d, const SegmentOptions& opt);
GrainLevelsInput grain_levels_input(const GreyDecisions& d);

// A slab: slices [core_begin, core_end) of it are its core (the rest its
// margins), and the watershed's levels per distance unit are the whole
// scan's, not derived from the slab's own deepest voxel.
struct SlabWindow {
  int64_t core_begin = 0, core_end = 0;
  double buckets_per_unit = 0;
  double fixed_units = 0;  // the whole scan's fixed_point_units (distance_transform.hpp)
  bool scan_bottom = false, scan_top = false;  // its first / last slice is the scan's
};

struct SlabOutcome {
  // labels 1..count of the slab, numbered in raster order of their first
  // voxel, *no* size filter (a particle cut by the slab's face is smaller
  // than it is); counts of the chain's stages over the whole slab.
  SegmentResult result;
  std::vector<int64_t> sizes;  // sizes[l]: voxels of label l in the slab (sizes[0] unused)
  int64_t core_solid = 0;      // solid voxels of the core after the threshold (inside the field of view)
  float core_dmax = 0;         // deepest distance-map value of the core, distance units
};

// The chain of segment() on one slab with the whole scan's decisions: the
// grey slab becomes the mask in its own storage.
SlabOutcome segment_slab(Volume<uint16_t>&& grey, const GreyDecisions& d, const SegmentOptions& opt,
                         const SlabWindow& w);

// The summary as JSON text (options, threshold, pores, markers, merges,
// labels, time per stage, peak memory).
std::string summary_json(const SegmentResult& r, const SegmentOptions& opt);

}  // namespace tg
