// Watershed markers from the distance map: the h-maxima, one marker per
// grain and per fragment.
//
// Definition (Soille, "Morphological Image Analysis", 2nd ed. 2003, sect.
// 6.3.4; Vincent 1993, doi:10.1109/83.217222): a regional maximum of the
// distance map d is kept when its dynamic is at least h, i.e. no higher
// voxel can be reached from it along a path that descends by h or more.
// The marker is the whole cap of such a maximum: the connected part of
// {d >= top - h} that holds it (the regional maximum of the h-maxima
// transform R_d(d - h)). Maxima of equal height joined above top - h share
// one marker. h is a depth in distance units (voxels of the finest axis):
// two touching balls of radius R joined by a neck of radius r stay two
// markers while R - r >= h; ripples of the distance map caused by voxel
// staircases, noise and residual pores, of depth < h, do not seed a grain.
//
// Why not the usual "peak_local_max(min_distance ~ R)": the minimum
// distance suppresses a peak closer than R to a higher one whether or not
// the two are connected, so the two halves of a split grain, one or two
// voxels apart, lose one of their markers and the watershed hands one half
// to the other's label (or leaves it out). Here the cap flood runs inside
// the solid only, so a separate solid component can never be dominated by
// a peak of another one: every connected component keeps at least its
// highest cap as a marker, and 1-voxel grains get one too.
//
// Method: each voxel that has no strictly higher 26-neighbour starts a
// breadth-first flood over the solid voxels with d >= d0 - h; the flood
// stops as soon as it meets a voxel higher than d0 (not a marker), or ends
// having visited the whole cap (a new marker, written over the cap). Every
// visited voxel of height d0 shares the outcome and is never started from
// again, so a plateau is flooded once. Cost: the sum of the cap sizes, in
// practice a small multiple of the solid voxel count (caps are balls of
// radius ~h around each peak); memory: the u32 marker volume (two high
// bits serve as flags during the search) and a queue the size of one cap.
// The candidates are found in parallel (26-connectivity: a separable
// 3x3x3 maximum), the caps grown serially from them in raster order:
// deterministic, markers numbered in raster order.
#pragma once
#include <cstdint>

#include "core/volume.hpp"
#include "segmentation/distance_transform.hpp"

namespace tg {

struct MarkerOptions {
  double h = 2.0;         // dynamic (depth) a maximum needs to seed a grain, distance units
  int connectivity = 26;  // neighbourhood of the cap flood: 6, 18 or 26
};

// Writes marker labels 1..count over each kept cap into `markers`
// (reallocated if its shape differs), 0 elsewhere. `dist` is the distance
// map of `solid` (any monotone function of it works). Returns count.
uint32_t find_markers(const Volume<float>& dist, const Volume<uint8_t>& solid, Volume<uint32_t>& markers,
                      const MarkerOptions& opt = {});

// The same with the solid where dist > 0: the distance map of a mask with
// some void is 0 exactly on the void, so the mask need not be kept.
uint32_t find_markers(const Volume<float>& dist, Volume<uint32_t>& markers, const MarkerOptions& opt = {});

// The same on the 16-bit fixed-point map (segment's path: 2 B/voxel
// instead of 4); opt.h stays in distance units.
uint32_t find_markers(const FixedDistance& dist, Volume<uint32_t>& markers, const MarkerOptions& opt = {});

}  // namespace tg
