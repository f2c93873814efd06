// Which voxels of a real scan are data: the reconstruction's circular field
// of view, pre-masked zeros, and saturated (clipped) grey levels. Voxels
// that are not data neither enter the threshold's histogram nor, outside
// the field of view, get labelled (issue 19, "tried on a real micro-CT
// scan": a zeroed outside moved the Tsai threshold from 11565 on a crop to
// 13107 on the full scan; a 2.7 % block at 65535 moved it to 21845).
//
// Field of view (a cylinder along z, the rotation axis of the scanner).
// Reconstructions set the outside of the circle they reconstruct to one
// constant (0, or another value). Detection, one cheap pass:
//   1. the outside constant c is the value of the slice corners; every
//      slice's four corners must hold the same c (else: no field of view);
//   2. for each slice and row y, the first and last voxel != c are found by
//      scanning in from both ends (only the outside voxels are read); their
//      envelope over all slices gives per row y the extent [xmin(y), xmax(y)]
//      of the union of the non-constant region (a pore of value c at the rim
//      of one slice is covered by the others), and from the rows the
//      extent of each column x;
//   3. a circle is fitted to these boundary points by algebraic least
//      squares (Kasa 1976, "A circle fitting procedure and its error
//      analysis", IEEE Trans. Instrum. Meas. IM-25:8-14,
//      doi:10.1109/TIM.1976.6312298), leaving out the points on the slice's
//      own border (there the circle is clipped by the slice, not seen);
//   4. the fit is accepted when at least 16 points remain, the slices'
//      middle rows hold at least 4 grey levels (a reconstruction's inside is
//      noisy; a binary, pre-thresholded image whose outside is its void has
//      no field of view to cut away: a 16^3 cube of 255 in 0 lost its
//      corners to a fitted circle), their RMS
//      distance to the circle is below 1.5 voxels and the circle leaves at
//      least 1 % of the slice outside; the inside is then the voxels whose
//      (y, x) centre lies within radius - 1 of the centre (the rim voxel
//      ring is left out: a reconstruction interpolates it with the constant).
// A given radius (`--fov-radius-vox`, centre default the slice centre)
// replaces the detection. The inside of each row is one span [x0, x1), so
// nothing of the volume's size is made: the histogram and the mask read
// the spans. Assumes square pixels in the slice (equal x and y voxel edges,
// as reconstructions are); the circle is in voxel units.
// Cost: O(nz * ny + outside voxels) to detect, O(ny) memory.
//
// Pre-masked zeros. A 16-bit reconstruction's void is noisy: where it is
// clipped at 0, its tail leaves many voxels at 1, 2, ... too. Zeros are a
// mask (background or pores set to 0 by whoever prepared the scan), not
// data, when (a) at least 1 % of the voxels inside the field of view are
// exactly 0 and (b) the first 1/256 of the grey range above 0 (levels
// 1..max(1, top/256): one level of an 8-bit scan) holds fewer than 1/100 as
// many voxels as level 0. They are left out of the histogram; being 0 they
// are never solid by the threshold (solid is > threshold >= 0; the pore
// filter may still fill a zeroed pore enclosed in a grain, as it should).
// An image of fewer than 4 grey levels (constant, binary, a few phases) is
// not screened at all: its zeros are void data.
//
// Saturation. The top level (65535 for 16-bit and normalised float
// input, 255 for 8-bit input) and, when the zeros are not a mask, the
// bottom level 0 are counted. A level holding more than 0.1 % of the
// voxels inside the field of view (normalisation clips 0.01 % at each end
// by design) is left out of the histogram: voxels at the top stay solid,
// at 0 stay void, and a note gives the fraction. More than half of the
// voxels saturated (top and bottom together) is an InputError: the
// threshold would be chosen on a minority of the scan.
// Cost: read from the histogram, O(65536).
#pragma once
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/volume.hpp"

namespace tg {

struct FovOptions {
  bool detect = true;                                           // look for a constant outside
  double radius_vox = -1;                                       // > 0: given (no detection)
  double centre_y = std::numeric_limits<double>::quiet_NaN();   // given centre, voxel-index coordinates;
  double centre_x = std::numeric_limits<double>::quiet_NaN();   // NaN: the slice centre
};

struct FieldOfView {
  bool active = false;       // false: every voxel is inside
  std::string source = "none";  // "none" | "detected" | "given"
  double centre_y = 0, centre_x = 0, radius = 0;  // voxel-index coordinates of the slice
  int outside_value = -1;    // detected outside constant (-1 unless detected)
  double fit_rms = 0;        // detection: RMS distance of the boundary points to the circle
  int64_t outside_voxels = 0;
  std::vector<int64_t> x0, x1;  // per row y: the inside is x in [x0[y], x1[y]) (empty when inactive)
  std::string note;          // why nothing was detected, when the detection was tried and failed

  int64_t inside_voxels(const Shape& s) const { return s.voxels() - outside_voxels; }
};

// The field of view of a scan: given, detected, or none (see above). UsageError for a bad radius.
FieldOfView find_field_of_view(const Volume<uint16_t>& grey, const FovOptions& opt);

// The detection above, fed slab by slab (a scan larger than memory, read in
// z order in slabs of any thickness): add() every slab of slices once, in
// z order, then finish() with the whole scan's shape. The result is the
// same as find_field_of_view on the whole volume, which runs it on one slab.
class FovScan {
 public:
  FovScan(int64_t ny, int64_t nx);
  void add(const Volume<uint16_t>& slab);
  FieldOfView finish(const Shape& whole) const;

 private:
  int64_t nx_ = 0, slices_ = 0;
  bool constant_ = true;  // every slice's corners so far hold c_
  uint16_t c_ = 0;
  std::vector<uint16_t> levels_;  // distinct grey levels of the middle rows, up to 4
  std::vector<int64_t> xmin_, xmax_;  // per row y: envelope of the first / last voxel != c_
};

// The given field of view (FovOptions radius_vox > 0) of a scan of shape
// s; inactive when none is given (nothing to detect: see FovScan).
// UsageError for a bad radius.
FieldOfView given_field_of_view(const FovOptions& opt, const Shape& s);

// The circle (centre, radius) as a field of view of a slice ny x nx.
FieldOfView circular_field_of_view(double centre_y, double centre_x, double radius, const Shape& s);

// 65536-bin histogram of the voxels inside the field of view (histogram_u16 when inactive).
std::vector<int64_t> histogram_in_fov(const Volume<uint16_t>& grey, const FieldOfView& fov);

// Sets the mask to 0 outside the field of view (touches the outside voxels only).
void clear_outside(Volume<uint8_t>& mask, const FieldOfView& fov);

struct LevelScreen {
  int top_level = 65535;
  int64_t voxels = 0;             // inside the field of view
  int64_t zero_count = 0, top_count = 0;
  bool zeros_premasked = false;   // zeros are a mask (left out, never solid)
  bool zeros_clipped = false;     // zeros are clipped void above 0.1 % (left out, stay void)
  bool top_saturated = false;     // the top level above 0.1 % (left out, stays solid)
  double zero_fraction() const { return voxels ? double(zero_count) / double(voxels) : 0.0; }
  double top_fraction() const { return voxels ? double(top_count) / double(voxels) : 0.0; }
  std::string action() const;     // one line: what was left out of the histogram and why
  std::vector<std::string> notes; // for the summary
};

inline constexpr double kSaturatedFraction = 0.001;  // a level above this share is clipping
inline constexpr double kPremaskedFraction = 0.01;   // zeros above this share may be a mask

// Screens a histogram (inside the field of view): decides pre-masked zeros
// and saturation and zeroes the bins left out. InputError when more than
// half of the voxels are saturated.
LevelScreen screen_levels(std::vector<int64_t>& hist, int top_level);

}  // namespace tg
