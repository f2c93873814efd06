// Marker-controlled watershed of the inverted distance map inside the
// solid: each grain grows from its marker, downhill on the distance map,
// until it meets another grain at the "neck" between them.
//
// Method: priority flooding (Meyer 1991, "Un algorithme optimal de ligne de
// partage des eaux", 8e congres RFIA; Beucher and Meyer 1993, in
// Mathematical Morphology in Image Processing, doi:10.1201/9781482277234-12)
// with a bucket queue instead of a heap, which makes it O(N): the distance
// is quantised to integer levels, level = floor(d * buckets_per_unit), one
// FIFO per level. Levels are processed from the highest down. A voxel is
// queued once, at min(its level, the current level), so a bucket never
// receives work after it has been emptied; within a level, FIFO order
// means ties go to the earliest queued voxel (the marker that got there
// first), as skimage's (value, age) heap does. 26-connectivity by default.
//
// Watershed lines (default, as in the reference study: every particle is
// surrounded by void): a voxel takes its label when it leaves the queue,
// from its already-labelled neighbours; if they carry two or more labels it
// becomes a line voxel (label 0) and does not propagate. Without lines, a
// voxel takes the label of the voxel that queued it (label at push time;
// safe without lines, see scikit-image issue #2636 for why it is not with
// them). Solid voxels that no marker reaches (cut off by lines) stay 0.
//
// Levels live in one byte per voxel (0 = void, 1 + level on the solid):
// quantise_levels() rewrites the solid mask in place, or writes them over
// the float distance map's own storage, so the map is gone before the
// flood (peak memory: levels 1 B + labels 4 B per voxel + the frontier).
// At most 255 levels: when dmax * buckets_per_unit would exceed 254, the
// quantisation is coarsened to 254 / dmax levels per unit (returned and
// reported; grains of radius > 63 voxels at the default).
//
// Cost: O(N) time. The flood is bound by memory latency (it visits the 26
// neighbours of every solid voxel in frontier order), so its inner loop
// reads only the u32 label word of each neighbour: flags in its top bits
// (queued, line, volume border, so no index division for interior voxels;
// void voxels are pre-marked queued) and the level byte only for voxels it
// queues. Frontier entries are 4 B (8 B for volumes over 2^32 voxels), in
// blocks that flooded levels hand on to lower ones.
//
// Threads: each breadth-first round is shared by slabs of 8 slices, even
// slabs at once and then odd ones, so neighbours in one round are decided
// one after the other (lines stay one voxel thick) and the queue order is
// fixed by the shape: the labels do not depend on the thread count.
// Each slab's round is put in row order, or in slice order when it holds
// fewer entries than a quarter of its rows, decided from that slab's own
// entries: a slab's order, and so the flood's ties, do not depend on the
// rest of the volume, so slices segmented apart (segment_chunked.hpp,
// slabs starting at multiples of 16) flood as in the whole volume.
// Each slab queues into lists and buckets of its own, by the slab of the
// voxel queued, and sorts its own share of a round (no serial step between
// rounds; a counting sort of the whole round by every row of the volume
// took 0.08 s of 0.33 s at 256^3, 0.05 s as a partition by slab). 512^3 zeolite scan, 37.5 M solid voxels: 4.2 s serial
// (session 3), 2.0 s on 2 threads with the SSE2 neighbour test and the
// shared blocks (session 4); at 256^3 0.55 s (session 5) -> 0.30-0.40 s
// with rounds in row order, per-slab buckets and the OR/AND label test;
// 0.34 -> 0.30 s (median of 9, interleaved) with each slab sorting its own
// share and the label test on the masked words alone.
#pragma once
#include <cstdint>

#include "core/volume.hpp"
#include "segmentation/distance_transform.hpp"

namespace tg {

struct WatershedOptions {
  bool lines = true;               // separate touching grains by a 1-voxel void line
  int connectivity = 26;           // 6, 18 or 26
  double buckets_per_unit = 4.0;   // distance quantisation: levels per distance unit
};

// The levels per distance unit the flood uses for a map whose deepest value
// is dmax: buckets_per_unit, or 254 / dmax where that would pass level 255.
double levels_per_unit(float dmax, double buckets_per_unit);

// Rewrites `solid` (0 = void, non-zero = solid) in place into flooding
// levels: 0 on void, 1 + floor(d * q) on the solid, where q is
// buckets_per_unit, lowered when needed so that the top level is <= 255.
// Returns the q used. `dist` must be finite on the solid.
double quantise_levels(const Volume<float>& dist, Volume<uint8_t>& solid, double buckets_per_unit);

// The same levels written over the float map's own storage, which is
// taken (no second volume: 4 B/voxel at peak instead of 5): the solid is
// where the map is > 0, as for an EDT of a mask with some void. The map
// must be finite and >= 0; q_used is set to the q used.
Volume<uint8_t> quantise_levels(Volume<float>&& dist, double buckets_per_unit, double& q_used);

// The same from the 16-bit fixed-point map (segment's path; taken, its
// spent 1 B/voxel given back): q from the float map's deepest value
// (dist.dmax) exactly as above, level 1 + floor(value * q / per_unit),
// within 1/(2 per_unit) of a distance unit of the float map's levels.
Volume<uint8_t> quantise_levels(FixedDistance&& dist, double buckets_per_unit, double& q_used);

// The same at exactly q levels per unit (levels above 255 clamped to 255):
// a slab of a scan segmented slab by slab takes the whole scan's q.
Volume<uint8_t> quantise_levels_at(FixedDistance&& dist, double q);

// The flood on quantised levels (from quantise_levels). `labels` holds the
// markers on entry (1..2^29-2, 0 elsewhere) and the watershed labels on exit
// (0 on void and on line voxels). opt.buckets_per_unit is not used here.
void watershed_levels(const Volume<uint8_t>& levels, Volume<uint32_t>& labels, const WatershedOptions& opt = {});

// Convenience for callers that keep the distance map: quantises a copy of
// the mask, then floods. Returns the q used.
double watershed(const Volume<float>& dist, const Volume<uint8_t>& solid, Volume<uint32_t>& labels,
                 const WatershedOptions& opt = {});

}  // namespace tg
