// Under-segmentation repair from the grey levels: split a label whose
// smoothed grey holds two or more bright cores parted by a darker sheet.
//
// Why. Two fragments of a split grain lie a voxel or less apart; where the
// gap is under a voxel, the PSF is wide (σ 1.5 voxels) or the noise strong
// (CNR 8), blur and noise bridge it with voxels brighter than the dim band
// (segment.hpp "grey evidence"), the solid mask has no dip, and the
// watershed gives the two halves one label. The gap is still there in the
// grey levels: averaged over a few voxels, its sheet is darker than the
// solid on either side by much more than the averaged noise. Geometry
// cannot see it (two halves put back together are as convex as a grain:
// the convex-hull flag of SPAM's detectUnderSegmentation does not tell them
// apart, bench/segmentation/RESULTS.md), so the repair looks at the grey.
//
// Method (per label, in its bounding box):
//  1. Smooth the grey with a Gaussian of σ_s voxels (separable, kernel
//     radius ceil(3 σ_s), the volume's faces repeated), which divides white
//     noise by ~(4π σ_s²)^(3/4) (6.7x at σ_s = 1) and keeps a planar sheet's
//     dip.
//  2. Flood the label's voxels from the brightest down (union-find over
//     6-neighbours: the component tree of the smoothed grey restricted to
//     the label). When a voxel at level v joins two or more components that
//     are each *significant* — at least min_piece voxels, and a peak at
//     least `depth` above v (the dynamic of a regional maximum, Grimaud
//     1992) — they are kept apart: the voxel goes to the one its brightest
//     neighbour belongs to, lesser components touching it too. Otherwise
//     they merge. The voxels are taken in 4096 levels between the label's
//     extremes (a counting sort), in box order within a level.
//     This is a marker-controlled watershed of the smoothed grey whose
//     markers are the maxima of dynamic >= depth and size >= min_piece (an
//     area-and-dynamics filter), done in one sorted pass.
//  3. Two or more pieces: the largest keeps the label, each other piece
//     gets a new one. Voxels of components that never met a piece (parts of
//     the label not connected to it) keep the label.
// depth = depth_sigmas x the smoothed grey's noise sigma (measured, not
// assumed: smoothed_sample_histogram below), and at least min_depth (a
// share of the contrast, for noiseless scans; segment.hpp sets both).
// min_piece = max(
// min_piece_fraction x the label's voxels, min_piece_vox).
//
// Defaults, measured on blind_scene.py scans (160^3, R 16, dev seeds 1-2;
// bench/segmentation/RESULTS.md "Split repair"): depth 4 to 9 noise sigmas
// give the same F1 within 0.004 on gap 0.5 voxel, PSF 1.5 and CNR 8 (26-30
// halves of ~30 glued pairs rejoined per scene); 4 splits one intact grain
// of the middle setting, 6-9 none; 6 is the default. Smoothing 0.7, 1 and
// 1.5 voxels: F1 within 0.008 of each other on those scenes; thin chips
// (2-3 voxels) keep a core only under the least smoothing, so segment()
// takes 0.7 unless the noise needs 1 (segment.hpp kSplitSmoothingLadder:
// on data_synth's 256^3 stage series, r_eq 11.6 voxels, chipping events
// tracked 0.62 -> 0.71 recall, 0.71 -> 0.81 precision).
// min_piece_fraction 0.03 -> 0.01 -> 0.005: gap 0.5 F1 0.973 -> 0.977 ->
// 0.979, no false split at any; segment() takes 0.005 (a sphere of radius
// ~2.7 voxels in a grain of R 16; with 0.7 smoothing it adds chips of
// small grains that 0.01 left out: recall 0.70 -> 0.71, precision 0.78 ->
// 0.81 on the series above).
// The flood is 6-connected: the same labels as 26 on the dev scenes (one
// more split at gap 0.5) in 40 % of the time.
//
// Cost: each label is first screened: its box smoothed and flooded at
// every second voxel along each axis (half the depth, 1/24 of the piece:
// thin pieces show few voxels on that grid); only a label the screen finds
// two cores in is smoothed and flooded in full. The flood sorts by a
// counting sort (O(V)) and stops at the threshold when nothing was kept
// apart. Labels in parallel (dynamic
// schedule); each label's result depends only on its own box, so it is the
// same whatever the thread count and in a slab of a chunked run as in the
// whole volume. Measured (2 threads, data_synth zeolite stage 4): 0.135 s
// of 0.78 s at 256^3 (the label boxes 0.009 s, found by runs of a row; the
// screens' smoothing ~0.05 s and floods ~0.05 s; the renumbering 0.02 s),
// 0.80 s of 4.13 s at 512^3. Smoothing the whole scan once at its even
// voxels for the screens instead (0.02 s) saved 0.025 s but moved the
// screen's grid off the box's: on the blind sweep it lost one split in each
// gap-0.5 scene (F1 0.973 -> 0.969), so it was not kept. Labels whose box exceeds
// max_box_vox (2^28: a grain of radius ~300 voxels) are not tested and
// counted.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "core/volume.hpp"
#include "segmentation/field_of_view.hpp"

namespace tg {

struct SplitOptions {
  double smoothing_sigma_vox = 1.0;  // σ_s of the Gaussian, voxels (segment() chooses 0.7 or 1)
  double depth = 0;                  // grey levels a piece's peak must stand above the sheet between pieces
  double floor = 0;                  // grey level: a label not split above it is left whole (the threshold)
  double min_piece_fraction = 0.01;  // of the label's voxels (segment() passes its 0.005)
  int64_t min_piece_vox = 27;        // and at least this many voxels (3^3)
  int64_t max_box_vox = int64_t(1) << 28;
};

struct SplitResult {
  int64_t tested = 0;        // labels large enough to hold two pieces
  int64_t split = 0;         // labels split
  int64_t pieces_added = 0;  // new labels
  int64_t skipped_large = 0; // boxes over max_box_vox, not tested
};

// labels: 1..count (0 void); new pieces get count+1.. in the order of the
// labels they come from (renumber afterwards for raster order). grey: the
// scan the labels came from, same shape, as read (uint16) or as a GreyCode
// (uint8; depth and floor then in code units). *count is updated.
SplitResult split_by_grey(Volume<uint32_t>& labels, uint32_t* count, const Volume<uint16_t>& grey,
                          const SplitOptions& opt);
SplitResult split_by_grey(Volume<uint32_t>& labels, uint32_t* count, const Volume<uint8_t>& grey,
                          const SplitOptions& opt);

// Face caps: a grain cut by a face of the scan can show only a cap a few
// voxels deep. Its distance map peaks at its depth (2-4 voxels), on the
// slope of the grain it touches, so it seeds no marker and the watershed
// gives it to that neighbour (blind_scene.py windows: 5 of the 8 particles
// missed in a 160 x 187 x 120 crop, 4 of the 22 in three whole 192^3
// scenes; bench/segmentation/RESULTS.md "Face caps"). On the face itself the
// cap is a disc beside the neighbour's section, and a convex grain's
// section by a plane is convex, so its in-plane distance map has one
// maximum (the distance to the boundary of a convex set is concave).
// Method, per label touching a scan face:
//  1. Its footprint on the face (its voxels in the face slice, enclosed
//     holes filled: pores cut by the face), the 2-D distance map of it,
//     its h-maxima (markers.hpp) of dynamic >= h; a footprint with two or
//     more maxima at least min_peak deep is a candidate.
//  1b. A footprint with one maximum is a candidate when the label goes on
//     behind it into a neighbour whose pole the cap is pressed on (that
//     neighbour has no footprint of its own): the cylinder over the
//     footprint's core, bright at the face, thins out or darkens by
//     min_dip within half the footprint's radius and is the label's, as bright
//     as solid, again deeper (R 16 dev scenes: 1-2 such caps a scene,
//     35-375 voxels, glued to a grain behind them). Seeds: the face core
//     with the cylinder above the dim layer, and the bright layer below;
//     step 3 then asks a contact's dip, min_dip_in_front (a pore in one
//     grain's cylinder dims the sheet to 0.25-0.27).
//  2. The footprint is parted among those maxima (a watershed of its
//     distance map); the core of each part (its pixels at least half as
//     deep as its maximum) seeds a marker-controlled watershed of the
//     label's own 3-D distance map in its box (watershed.hpp, no lines):
//     the pieces meet at the neck between the cap and its neighbour.
//     (On the dev scenes the caps came out with IoU 0.56-0.88 so. Flooding
//     the grey instead gave 0.69-0.91 but put one of seven pieces on the
//     wrong grain: the bright neighbour's front takes a thin, partial-volume-
//     dim cap, or the cap's seed a part of the neighbour. Seeded at the
//     maxima alone: 0.35-0.74.)
//  3. A piece other than the largest leaves the label when it has at least
//     min_piece_vox voxels and the raw grey on the sheet between it and the
//     largest (its voxels touching the other's, both sides) is darker than
//     the solid by at least min_dip of the solid's height above the
//     threshold: a contact between two grains is partial-volume dim, a cut
//     through one grain (a footprint notched by a pore, say) is as bright
//     as solid. Measured on the dev scenes (blind_scene.py R 20, seeds
//     1-3 and a window of seed 1): contacts 0.35-0.50, cuts through one
//     grain 0.10-0.19. A cap cut by the circular field of view instead of
//     a face is not looked for.
// Each label's outcome depends only on its box: the same in a slab of a
// chunked run (whose cut faces are not scan faces) as in the whole scan.
struct FaceCapOptions {
  // Which faces of the volume are the scan's: z lo, z hi, y lo, y hi, x lo,
  // x hi (a slab's cut faces are not).
  std::array<bool, 6> faces{true, true, true, true, true, true};
  std::array<double, 3> spacing{1.0, 1.0, 1.0};  // voxel edges (z, y, x) over the finest
  double h = 1.0;                    // dynamic of a footprint's distance maximum, voxels
  double min_peak = 2.0;             // its depth (inscribed radius), voxels
  int64_t min_piece_vox = 27;
  double solid = 0, floor = 0;       // the solid's grey peak and the threshold, in the grey's units
  double min_dip = 0.25;             // (solid - sheet) / (solid - floor)
  bool caps_in_front = true;         // step 1b: one-maximum footprints with a grain behind the cap
  // The sheet's dip step 1b asks for: with one footprint maximum only the
  // grey says two grains, and a pore in the cylinder dims the sheet the
  // flood draws through one grain to 0.25-0.27 (dev scenes' false
  // candidates, R 16 seeds 302, 403); caps pressed on a neighbour 0.37-0.59
  // there, 0.35-0.39 in the unit test's layout.
  double min_dip_in_front = 0.30;
};

struct FaceCapResult {
  int64_t candidates = 0;    // labels whose footprint on a face has two maxima
  int64_t split = 0;         // labels a cap left
  int64_t pieces_added = 0;  // new labels
};

// labels 1..count; new pieces get count+1.. in label order; *count updated.
// grey: the split repair's one-byte code of the scan, same shape.
FaceCapResult split_face_caps(Volume<uint32_t>& labels, uint32_t* count, const Volume<uint8_t>& grey,
                              const FaceCapOptions& opt);

// Thin pieces: a chip a few voxels thick pressed on a grain (its own, or a
// neighbour it touches) has no distance maximum of its own (its deepest
// voxel is 2-3 voxels from the void, as deep as the neck where it touches),
// so it seeds no marker and the watershed gives it to the grain; where it
// is pressed on a neighbour the contact is as bright as solid, so the grey
// shows no sheet either (blind_scene.py R 16-20: most of the particles
// missed, bench/segmentation/RESULTS.md "Thin pieces glued to a grain").
// Its shape still tells: it is thinner than any part of a grain, and joined
// to the grain by a contact much smaller than itself.
// Method, per label (in its box, its own voxels only):
//  1. The morphological opening of the label by a ball of radius r: its
//     voxels within r of a voxel deeper than r (two exact distance maps,
//     distance_transform.hpp; the volume's faces are not void, as for
//     segment()'s map). A grain's body is its own opening but for a thin
//     skin at sharp edges; a piece thinner than 2r is not in it.
//  2. What the opening leaves, in 6-connected components. A component is a
//     thin piece when it holds at least min_piece voxels (max(27, 0.005 of
//     the label), as the split repair's), at most max_share of the label,
//     touches no face of the volume unless it holds at least (3 r)^3 voxels
//     (a grain the face cuts thin leaves slivers there, the face caps'
//     business: 70-90 voxels on the dev scenes, and a 284-voxel cap of a
//     small face-cut grain on test seed 101, which (2 r)^3 cut off; a
//     shell's wall the face cuts is larger: blind shell scenes,
//     bench/segmentation/RESULTS.md "Thin walls"), and
//     fewer than max_contact of its voxels touch the
//     opening (a chip touches the grain by a small contact, 4-19 % of its
//     voxels on the dev scenes; the skin of an edge lies along the body).
//  3. Each thin piece gets a new label; the rest keeps the label.
// Defaults, from the grain radius R the user gives: r = max(3, 0.15 R)
// voxels (the chips of blind_scene.py R 16-20 are 2.8-6 voxels thick, their
// deepest voxels 1.4-3.0 from the void; at R 40, r 4 cut the skin of two
// small fragments, 6 nothing), max_contact 0.2 (chips 0.04-0.19), max_share
// 0.2 (chips 1-13 % of the label they were glued to; the skins cut at R 40
// 25 %). Dev scenes (a Python prototype, then this code): R 16 seeds
// 411-414, R 20 511-512, angular (0.15, 0.3) and elongated (1.6, 2) R 20
// seed 1, R 8, 12 and 40 sweep seed 1, data_synth 256^3 stage 4 (seed 12):
// 36 pieces, each another particle's, none of them face-cut, before the
// face and share rules 2 false (bench/segmentation/RESULTS.md).
// Cost: each label is screened first on every second voxel of its box (a
// radius one voxel larger, looser size, share and contact); only a label
// the screen finds a piece in is read in full. Each label's result depends
// only on its own box: labels in parallel, the same whatever the thread
// count.
struct ThinPieceOptions {
  double radius_vox = 3.0;          // r, the opening's ball, voxels
  double max_contact = 0.2;         // share of a piece's voxels touching the opening
  double max_share = 0.2;           // a piece is at most this share of its label
  double min_piece_fraction = 0.005;
  int64_t min_piece_vox = 27;
  std::array<double, 3> spacing{1.0, 1.0, 1.0};  // voxel edges (z, y, x) over the finest, as segment()'s map
  int64_t max_box_vox = int64_t(1) << 28;
};

struct ThinPieceResult {
  int64_t tested = 0;        // labels large enough to hold a piece and a body
  int64_t screened_in = 0;   // of those, the ones the screen (every second voxel) sent to the full test
  int64_t split = 0;         // labels a thin piece left
  int64_t pieces_added = 0;  // new labels
  // Per label after the step (0..*count): 1 where no voxel lies deeper than
  // the radius (a piece, or a label thin throughout: a shell's wall, a
  // chip); merge_thin_walls reads it, and looks only inside their boxes.
  std::vector<uint8_t> thin;
  std::vector<Box> thin_boxes;
};

ThinPieceResult split_thin_pieces(Volume<uint32_t>& labels, uint32_t* count, const ThinPieceOptions& opt);

// The grey the split repair keeps beside the markers, one byte a voxel:
// code c stands for grey lo + c step (rounded, clipped to 0..255). segment()
// takes lo and hi (step = (hi - lo) / 255) as the 0.1th and 99.9th
// percentiles of the scan's histogram: a step is ~0.5 % of the contrast,
// its rounding noise (step / sqrt(12)) a few % of the smoothed noise the
// depth is measured in. 1 B/voxel instead of the scan's 2 at the peak.
struct GreyCode {
  double lo = 0, step = 1;
  static GreyCode from_histogram(const std::vector<int64_t>& hist);  // 0.1th..99.9th percentile
};
Volume<uint8_t> quantise_grey(const Volume<uint16_t>& grey, const GreyCode& code);

// The smoothed grey's noise: adds to `hist` (65536 bins) the smoothed grey
// (the same Gaussian as split_by_grey) of the sample slices z = 8 (mod 16)
// of the scan (slice nz / 2 when nz <= 8) that lie in `slab` (the scan's
// slices [z0, z0 + slab.nz)), inside the field of view. A sample slice
// needs its neighbours within 3 σ_s: a slab starting at a multiple of 16
// slices and ending at one or at the scan's end holds them (a chunked
// run's pass 1 reads such slabs), so the histogram is the same read whole
// or by slabs. solid_peak() of it gives the smoothed solid's noise sigma.
// With `pairs`, also the grey's variation inside the grains: for pixels i
// (every other one) and i + kPairStepVox of a sample row, the difference of their smoothed
// greys, counted by the least smoothed grey of the pixels from i - 2 to
// i + kPairStepVox + 2 in the row, 2 rows above and below either one, and
// of the raw grey 2 slices below and above either one (the pair's "level":
// above the threshold, both lie two voxels inside one solid body).
// within_grain_sigma() reads it.
inline constexpr int64_t kPairStepVox = 5;  // past the smoothed noise's correlation (correlated noise 1.5 voxels included)
inline constexpr size_t kPairLevelBins = 64, kPairDiffBins = 1024;  // level: grey / 1024; |difference|: 16 grey a bin
inline constexpr int kPairLevelShift = 10;
inline constexpr double kPairDiffStep = 16;
void smoothed_sample_histogram(const Volume<uint16_t>& slab, int64_t z0, int64_t nz_scan, const FieldOfView& fov,
                               double smoothing_sigma_vox, std::vector<int64_t>& hist,
                               std::vector<int64_t>* pairs = nullptr);

// The smoothed grey's sigma inside the grains: the median |difference| of
// the pairs whose level is above t, / (0.6745 sqrt 2) (two independent
// draws); what a solid's grey peak holds beyond it is the spread between
// grains (of different brightness). {0, n} when fewer than min_pairs pairs.
struct WithinGrain {
  double sigma = 0;
  int64_t pairs = 0;
};
WithinGrain within_grain_sigma(const std::vector<int64_t>& pairs, uint16_t t, int64_t min_pairs);

// The sigma of white noise of sigma 1 after the split repair's smoothing
// (the separable kernel w of sigma_s voxels: (sum of w_k^2)^(3/2)).
double white_noise_gain(double smoothing_sigma_vox);

// Normalised Gaussian weights w[0..2r], r = ceil(3 sigma) (the split
// repair's smoothing, its sample histograms, grain_levels.hpp's S).
std::vector<float> gaussian_kernel(double sigma);

}  // namespace tg
