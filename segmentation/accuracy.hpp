// Accuracy of a labelling against ground-truth labels (synthetic scans).
//
// Matching rule (as in the issue and common in instance-segmentation
// benchmarks): a true particle t is detected when some predicted label p has
// IoU(t, p) = |t & p| / |t | p| >= 0.5. With IoU > 0.5 a match is one-to-one
// (two labels cannot each cover more than half of the union), so
//   F1 = 2 TP / (n_true + n_pred).
// Over-segmented true particle: two or more predicted labels each hold
// >= 10 % of its voxels. Under-segmenting predicted label: two or more true
// particles each have >= 10 % of their voxels in it. Volume error of a
// matched particle: (|p| - |t|) / |t|.
//
// Particles and labels smaller than `min_voxels` are left out of the counts
// on both sides (e.g. the reference study's smallest measurable grain, 0.2 mm
// in diameter; slivers of grains cut by the field of view fall below it).
//
// Cost: one pass over the volumes with a hash map of overlapping pairs.
#pragma once
#include <cstdint>
#include <vector>

#include "core/volume.hpp"

namespace tg {

struct Accuracy {
  int64_t n_true = 0, n_pred = 0, matched = 0;
  double f1 = 0;
  int64_t over_segmented = 0;   // true particles split across >= 2 labels
  int64_t under_segmenting = 0; // predicted labels holding >= 2 true particles
  double median_volume_error = 0;      // signed, over matched particles
  double median_abs_volume_error = 0;
  // Per true label id (index = id, up to the largest id): best IoU and whether matched.
  std::vector<double> best_iou;
  std::vector<uint32_t> match_of;  // predicted label matched (0 = none)
};

struct AccuracyOptions {
  int64_t min_voxels = 1;  // smaller true particles and labels are not counted
};

Accuracy evaluate_labels(const Volume<uint32_t>& truth, const Volume<uint32_t>& pred,
                         const AccuracyOptions& opt = {});

}  // namespace tg
