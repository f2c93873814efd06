// 32-bit float -> 16-bit normalisation of a reconstructed scan (reference
// study section 2.2: the float reconstructions were rescaled to 16 bits
// before thresholding).
//
// Method: a linear map of the grey range [lo, hi] onto [0, 65535],
//   u = round(65535 * (x - lo) / (hi - lo)),  clipped to [0, 65535],
// so values below lo become 0 and values above hi become 65535.
//
// The range is either given (LO,HI) or `auto`: the 0.01 % and 99.99 %
// percentiles of the finite voxel values. Percentiles rather than min/max
// because a reconstruction has a few extreme voxels (ring and streak
// artefacts, hot pixels); mapping min..max would squeeze the real materials
// into a few hundred grey levels. The percentiles are read from a histogram
// of 2^20 bins spanning [min, max] and interpolated linearly inside the bin,
// so they are exact to (max - min) / 2^20, far below one output grey level.
//
// Cost: auto_range is two passes over the volume (min/max, histogram), O(N)
// time and 8 MiB per thread; normalise_to_u16 is one pass. Both OpenMP,
// results independent of the thread count (integer histogram counts).
// NaN voxels (only present if the reader was told to allow them) map to 0
// and are ignored by auto_range.
#pragma once
#include <cstdint>
#include <string>

#include "core/volume.hpp"

namespace tg {

struct NormaliseRange {
  double lo = 0, hi = 0;  // grey values mapped to 0 and 65535
  std::string how;        // human-readable origin of the range, for logs and summaries
};

// Lower and upper percentiles used by auto_range, in percent.
inline constexpr double kAutoLowPercent = 0.01;
inline constexpr double kAutoHighPercent = 99.99;

// Robust range of a float volume: the 0.01 % / 99.99 % percentiles of its
// finite values. Throws InputError for an empty volume, one without finite
// values, or a constant one (nothing to map).
NormaliseRange auto_range(const Volume<float>& v);

// Linear map of [range.lo, range.hi] to [0, 65535] with clipping; geometry is
// kept. Throws UsageError unless lo < hi and both are finite.
Volume<uint16_t> normalise_to_u16(const Volume<float>& v, NormaliseRange range);

}  // namespace tg
