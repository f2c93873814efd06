// Ring artefacts: their removal from a reconstructed scan.
//
// A detector element whose gain is off shifts one radius of every slice
// about the rotation axis by the same grey offset: a ring. Through a grain
// a dark ring reads as the dim sheet of a gap (the split repair cuts the
// grain along it), a bright one bridges gaps (blind_scene.py --rings 0.2,0.3:
// F1 0.60-0.96 as scanned, 0.96-0.99 corrected; bench/segmentation/RESULTS.md "Ring
// artefacts").
//
// Method (the radial-profile correction of reconstructed slices, as in
// Sijbers & Postnov 2004, Phys. Med. Biol. 49 N247, on the mean over all
// slices rather than per slice): every voxel belongs to the radius bin
// floor(hypot(y + 0.5 - cy, x + 0.5 - cx)) (voxel centres, cy, cx the axis
// in voxel-edge coordinates: ny / 2, nx / 2 by default, the centre of a
// slice reconstructed about its middle). The mean grey M(b) of each bin over
// all slices is smooth in b but for rings: the packing's own radial
// structure varies over a grain's size, a ring over one bin. The offset of
// bin b is M(b) minus the median of M over the `window` bins around it
// (exact on a linear profile, blind to one bin's ring); it is removed where it
// exceeds min_z standard errors of M(b) (sqrt(var / n) of the bin's grey
// values), elsewhere left alone: on 8 ring-free blind scenes the largest
// offset was 5.3 standard errors, on scenes with rings up to 260. Bins
// within window / 2 of a bin of one grey throughout (outside a field of
// view set to a constant) are left alone: the median would read that step
// as a ring.
//
// What it does not do: rings that change from slice to slice (a defect of
// one detector row), partial arcs, an axis off the slice's centre unless
// given (a crop off the axis: the profile shows no ring, nothing changes).
//
// Cost: two passes over the volume, OpenMP over slices; per-slice sums
// reduced in slice order, so the result does not depend on the thread
// count.
#pragma once
#include <cstdint>
#include <vector>

#include "core/volume.hpp"

namespace tg {

struct RingOptions {
  double centre_y = -1, centre_x = -1;  // the rotation axis, voxel-edge coordinates; < 0: the slice's centre
  int window = 7;                       // bins of the median the profile is compared with (odd, >= 3)
  double min_z = 8;                     // remove an offset over this many standard errors of its bin's mean
};

struct RingResult {
  double centre_y = 0, centre_x = 0;
  int64_t bins = 0;          // radius bins
  int64_t rings = 0;         // bins whose offset was removed
  double max_offset = 0;     // the largest |offset| removed, grey levels
  std::vector<double> offset;  // per bin, removed (0 where not)
};

// Finds and removes rings in place (u16: rounded, clipped to 0..65535).
RingResult remove_rings(Volume<uint16_t>& v, const RingOptions& o = {});
RingResult remove_rings(Volume<float>& v, const RingOptions& o = {});

}  // namespace tg
