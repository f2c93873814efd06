// Slivers at the scan's faces: grains the field of view cuts a voxel or two
// from their edge.
//
// Why. A grain whose centre lies outside the scan shows, where it crosses a
// face, a sliver one or two voxels deep and a few to a few dozen voxels
// wide. Every voxel of it is an edge voxel. Where the scan was imaged as
// one piece with the grain beyond the face (a window of a larger scan),
// the blur brings that grain's grey in and the sliver is as bright as any
// grain's edge. Where the volume was imaged alone (a generator that blurs
// with the border voxels replicated, as blind_scene.py does, or a scanner
// whose field ends there), a sliver under a voxel deep keeps its partial
// volume: its brightest voxel lies well below the solid, and the global
// threshold keeps a few of its voxels, often in pieces: labels under the
// size floor (dropped), or one holding a third of the sliver (IoU < 0.5: a
// particle missed and a label that matches nothing). On blind_scene.py
// scans (middle setting) such slivers were the largest share of the
// particles missed: 25 of 52 at R 20 (bench/segmentation/RESULTS.md
// "Slivers at the faces").
//
// Rule. The size floor (segment.hpp min_size_vox) spares the labels in the
// shell of voxels within `depth` (2) of a scan face until this step has
// run, and the noise-speck test (noise_specks.hpp) has judged every label
// on its voxels above the threshold t before it. A *thin* label lies
// wholly in the shell (it never reaches depth + 1: a 26-step changes the
// depth by at most one). Then
//   0. a thin label under the size floor that meets a label reaching
//      deeper across a watershed line voxel above t is a piece of that
//      grain the watershed cut off, and is left to the floor (at PSF 1.5,
//      blind_extremes seed 103, such crumbs grew into 10-11-voxel labels
//      that matched nothing: F1 0.948 -> 0.942 without this);
//   1. thin labels that meet across a watershed line voxel above t join
//      when together they hold fewer than `crumbs` (6) x the size floor: a
//      small sliver's distance map is ragged, and the watershed cuts it
//      into crumbs. Larger thin labels meeting so are caps of two grains
//      touching right at the face as often as pieces of one: on the dev
//      scenes 14 such pairs, the 5 of one sliver joined by the rule holding
//      14-26 voxels together, the 7 of two grains 118-743, the 2 of one
//      sliver left apart 189 and 291;
//   2. each thin label grows, `rounds` (3) times, into the unlabelled shell
//      voxels brighter than its own half level, void + `half` (0.5) x (its
//      brightest voxel - void), where that lies below t, and whose labelled
//      26-neighbours are all that label; two labels never claim
//      neighbouring voxels in one round (a void line stays between grains).
// The half level is the edge of an object at half its own contrast (a
// thin object blurred keeps its edge where its grey is half its peak): a
// bright sliver's lies at t or above and it does not grow; a dim one's
// lies lower. A fixed level t - 0.3 (t - void) scored the same on the dev
// scenes (F1 0.9808 against 0.9800 / 0.9802 at 0.2 / 0.45) but grew bright
// slivers past their grain (IoU 0.87 -> 0.73: face_slivers_test). Labels
// reaching deeper are untouched: their grey inside is solid.
//
// Slabs of a chunked run pass their cut faces as not the scan's (faces[0],
// faces[1]) and apply the size floor to whole particles afterwards, as
// always; the rule reads a voxel's 26-neighbourhood only, so slab by slab
// gives the whole run's labels.
//
// Cost: serial, two passes over the shell (and the layer behind it), then
// the growth from the thin labels' own voxels: 0.007-0.008 s of 0.70 s at
// 256^3 (data_synth stage, 4 labels grown; the whole run as fast as
// without it, within its noise). A first version that re-read the whole
// shell in every pass and round took 0.09 s.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "core/volume.hpp"

namespace tg {

struct FaceSliverOptions {
  // Which faces of the volume are the scan's: z lo, z hi, y lo, y hi, x lo, x hi.
  std::array<bool, 6> faces{true, true, true, true, true, true};
  double threshold = 0;   // t, in the grey code's units (solid: code > t)
  double void_level = 0;  // the void's grey, same units
  double half = 0.5;      // a thin label's level: void + half (its peak - void), at most t
  int depth = 2;          // the shell: voxels at most this many voxels from a scan face
  int rounds = 3;
  int64_t min_size_vox = 8;  // the size floor
  int64_t crumbs = 6;        // thin labels meeting across a line join when together < crumbs x the floor
};

struct FaceSliverResult {
  int64_t slivers_joined = 0; // thin labels joined to a thin neighbour across a line
  int64_t labels_grown = 0;   // thin labels that gained voxels
  int64_t voxels_added = 0;
};

// Labels with a voxel in the shell, read through premap (or as they are):
// flags over 0..nl-1 (nl: premap's size, else the largest label + 1), for
// the size floor to spare (segment.cpp).
std::vector<uint8_t> labels_in_shell(const Volume<uint32_t>& labels, const FaceSliverOptions& opt,
                                     const std::vector<uint32_t>* premap);

// labels 1..count; grey: the split repair's one-byte code (split_labels.hpp
// GreyCode), same shape. Adds its counts to *result.
void grow_face_slivers(Volume<uint32_t>& labels, uint32_t count, const Volume<uint8_t>& grey,
                       const FaceSliverOptions& opt, FaceSliverResult* result);

}  // namespace tg
