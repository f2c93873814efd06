// Summary statistics of a volume, one parallel pass (for `tomograin info`
// and for choosing normalisation ranges): min, max, mean, standard deviation,
// NaN/Inf count, and a histogram from which percentiles are read.
// Integer volumes of up to 16 bits get an exact histogram (one bin a value);
// float and 32-bit volumes a 4096-bin histogram over [min, max].
#pragma once
#include <cstdint>
#include <vector>

#include "core/dtype.hpp"

namespace tg {

struct VolumeStats {
  int64_t voxels = 0, finite = 0, nonfinite = 0;
  double min = 0, max = 0, mean = 0, stddev = 0;
  // Histogram: bin b covers [lo + b*width, lo + (b+1)*width).
  double hist_lo = 0, hist_width = 1;
  std::vector<int64_t> hist;
  int64_t count_at_min = 0, count_at_max = 0;  // saturation check for 16-bit data
  int64_t distinct_nonzero = -1;               // u32 labels: number of distinct labels (-1 if not counted)

  // Value below which `p` percent of the finite voxels lie (bin-centre accuracy).
  double percentile(double p) const;
};

VolumeStats compute_stats(const AnyVolume& v);

}  // namespace tg
