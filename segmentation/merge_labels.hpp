// Over-segmentation repair: merge two labels whose shared interface is
// large compared with the cross-section of the smaller one.
//
// A grain cut in two by the watershed (a residual pore, an elongated or
// flattened shape) meets its other piece across a wide interface, about the
// grain's own cross-section; two distinct grains in contact meet across a
// small contact disc. Criterion, for labels a, b with voxel counts Va <= Vb:
//   interface(a, b) >= ratio * pi * r^2,   r = (3 Va / (4 pi))^(1/3),
// i.e. the interface exceeds `ratio` times the central cross-section of the
// equivalent sphere of the smaller label. Default ratio 1.0: the interface
// is at least the smaller piece's own central cross-section, which a
// contact between two grains never reaches (two equal balls of radius R
// joined by a neck of radius rn give interface/pi R^2 = (rn/R)^2 < 1) but a
// grain cut through its middle does. Split fragments have a void gap
// between them; where blur bridges it the bridges are a small fraction of
// the section. (0.5 merged such blur-bridged fragments of data_synth scans:
// F1 0.91 vs 0.98 at 1.0.)
//
// Interface area in voxel faces: with watershed lines, a line voxel whose
// 26-neighbours carry exactly two labels counts one unit for that pair
// (the line is one voxel thick); without lines, each face between voxels
// of two labels counts one.
//
// Grey evidence (segment.hpp): only the *bright* part of an interface
// counts (line voxels, or both voxels of a face, at level >= bright_level),
// and it must be at least min_bright_share of the whole interface. The gap
// between two fragments a voxel apart stays darker than solid even where
// blur and noise bridge it, so their interface is mostly dim and they stay
// apart however wide it is (bright only where a diagonal step of an oblique
// gap lets two bright voxels touch corner to corner: 20-30 % of a chip's
// face, which passed the area test of a small chip before the share test
// was added); an interface cutting through one grain is as bright as its
// interior but for its rim and counts in full. bright_level 1 counts every
// solid voxel (a plain mask: no grey evidence).
//
// Whole-graph decision: pairs are decided from the labels as the watershed
// left them (one pass, no cascade of re-evaluations), and each label joins
// at most one neighbour, its best partner: among the passing pairs in
// which it is the smaller label, the one with the largest interface. So a
// small piece in the neck between two grains joins one of them and never
// chains them together (deciding pair by pair joined both: one label held
// 26 % of a real scan's solid). Unions in label order; the line voxels
// between merged labels join them. Merged labels keep the smallest number
// of the group; segment() renumbers them 1..count afterwards
// (relabel_consecutive).
//
// Cost: one parallel pass over the volume (per-thread tables and interface
// counts, summed; the line voxels between two labels listed on the way, so
// joining them needs no second look), a hash map over touching pairs and
// one pass to renumber. Deterministic.
#pragma once
#include <cstdint>
#include <vector>

#include "core/volume.hpp"

namespace tg {

struct MergeOptions {
  double ratio = 1.0;  // merge when interface >= ratio * pi r^2 (r: smaller label's equivalent radius)
  uint8_t bright_level = 1;  // interface voxels with a lower level in `solid` do not count (grey evidence)
  double min_bright_share = 0.5;  // and the bright part must be at least this share of the interface
  // With `grey` (the scan's grey, any one-byte code of it, same shape) the
  // share test weighs each pair against its own solid: a voxel graded
  // bright counts bright for the share where its grey is at least
  // grey_floor + grey_fraction x (L - grey_floor), L the pair's level (the
  // mean grey of the two labels' voxels above grey_floor: the grain's,
  // were they one), or where it is at most grey_filled (the pore filling
  // made it bright). (The dimmer label's level, tried first, is the one a
  // small piece's rim lowers most: at R 8 it glued textured grains' halves,
  // 584 -> 573 of 724 on eight scenes; the brighter one's cut a textured
  // grain whose pieces differ by a few % in mean grey.) The area test still
  // counts every voxel graded bright (a cut through a textured grain runs
  // through its darker spots, and its area is what tells it from a
  // contact). One global level failed both ways: where grains differ in
  // brightness, halfway to the mean solid lies inside the dim grains (their
  // cuts read dim) while the grading's level lies under the bright grains'
  // gaps (their halves glued back: blind_scene.py --grain-contrast 0.7,1 at
  // R 8, 20 of 40 merges joined two particles, whose interfaces lie mostly
  // under halfway to their own level, and those inside one grain mostly
  // above it; bench/segmentation/RESULTS.md "Grains of different brightness:
  // each pair's own level"). A texture
  // inside the grains widens the solid's peak the same way (the grading's
  // level fell to the threshold and a bridged gap's partial-volume voxels
  // read bright: --grain-texture 0.1, R 12, 67 of 101 halves).
  const Volume<uint8_t>* grey = nullptr;
  uint8_t grey_floor = 0;     // the threshold, in the grey's units
  uint8_t grey_filled = 0;    // graded bright at or below it: brightened by the pore filling
  double grey_fraction = 0.5;  // of the way from grey_floor to the pair's level
  // false: the merged labels' voxels keep their old labels and `root` says
  // where each goes, for a caller that renumbers anyway (relabel_consecutive
  // takes it as its premap): one pass over the volume less.
  bool apply = true;
};

struct MergeResult {
  int64_t touching_pairs = 0;  // label pairs sharing an interface
  int64_t candidates = 0;      // pairs passing the criterion (before the best-partner choice)
  int64_t merges = 0;          // unions made
  std::vector<uint32_t> root;  // with apply = false and merges > 0: label l merges into root[l]
};

// `labels`: watershed output (0 on void and lines); `solid`: the mask it was
// computed on (solid voxels with label 0 are line voxels).
MergeResult merge_oversegmented(Volume<uint32_t>& labels, const Volume<uint8_t>& solid, const MergeOptions& opt = {});

// Thin walls put back together (a shell, a bioclast: walls 2-4 voxels
// thick). Where a wall touches a grain, the grain's marker floods into it
// (the wall's ridge is no deeper than the contact), and the thin-piece
// repair then cuts out the parts the grains took: one wall ends as a chain
// of thin labels parted by watershed lines (issue 19's real scan: "chains
// of short labels with unlabelled gaps"). Two labels that are both thin
// throughout (`thin`, from split_thin_pieces) and meet across an interface
// as bright as solid (line voxels between exactly the two of them, or
// faces) are one wall cut by the watershed: two pieces a gap or a contact
// parts meet across dim partial-volume voxels. A pair merges when its
// bright interface is at least min_area voxels and min_bright_share of the
// interface; chains merge whole (every passing pair is joined: a wall has
// no neck a third grain could hold). The line voxels between merged labels
// join them. Labels keep the smallest number of their group; the caller
// renumbers. Deterministic (integer counts, pairs joined in key order).
struct WallMergeOptions {
  double floor = 0;               // grey at or above which a line voxel is solid (the threshold)
  double bright = 0;              // grey at or above which an interface voxel is bright
  double min_bright_share = 0.5;
  int64_t min_area = 9;           // bright interface voxels: a cut across a wall t thick is >= t x t
};
struct WallMergeResult {
  int64_t thin_labels = 0;     // labels thin throughout
  int64_t touching_pairs = 0;  // pairs of them sharing an interface
  int64_t merges = 0;          // unions made
};
// thin_boxes: the boxes of the thin labels (only their voxels, grown by
// one, are looked at: at 256^3 a pass over the whole volume cost 3 % of a
// segmentation that had no wall).
WallMergeResult merge_thin_walls(Volume<uint32_t>& labels, const Volume<uint8_t>& grey,
                                 const std::vector<uint8_t>& thin, const std::vector<Box>& thin_boxes,
                                 const WallMergeOptions& opt);

}  // namespace tg
