// Per-label statistics of a label volume in one pass: voxel count, volume,
// centroid, bounding box, inertia tensor and principal axes, equivalent-sphere
// diameter, border and detection-limit flags, and each label's boundary
// voxels (the input of the convex hull, measure/feret.hpp).
//
// Method: the z slices are split into one contiguous slab per thread
// (OpenMP, static); each thread accumulates integer moments (count, sums of
// k, j, i and of their products) and bounding boxes into its own array
// indexed by label, and lists its boundary voxels in scan order. Partials are
// merged in thread order; integer sums are exact, and the boundary lists
// concatenated in slab order are the serial scan order, so the result is
// bit-identical for any thread count. A voxel is a boundary voxel when one of
// its 6 face neighbours holds another label, void (0) or lies outside the
// volume. Cost O(V) time for V voxels, O(L * T) memory for L labels and T
// threads, plus the boundary lists (~ the particles' surface area in voxels).
//
// Moments: with voxel centres x_v and voxel volume dv, volume V = n dv,
// centroid c = mean x_v, second moment C = sum_v [(x_v - c)(x_v - c)^T dv] +
// n dv diag(h^2)/12 (each voxel is a cube of edges h, not a point), inertia
// tensor (unit density) I = tr(C) 1 - C, principal moments = eigenvalues of
// I ascending with their unit axes (Eigen's SelfAdjointEigenSolver). The
// equivalent-sphere diameter is d_eq = (6 V / pi)^(1/3); the equivalent
// ellipsoid's semi-axes are sqrt(5 eigenvalues of C / V) (a solid ellipsoid
// of semi-axis a has variance a^2/5 along it; skimage's
// axis_major_length uses the same moments). One voxel has semi-axes
// sqrt(5/12) h = 0.645 h (a cube's moments), never 0. Anisotropic voxels
// are handled: every position is origin + h * (index + 0.5) per axis.
//
// Coordinates are in metres, (z, y, x) order, as everywhere in tomograin.
#pragma once
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "core/volume.hpp"
#include "measure/feret.hpp"

namespace tg::measure {

struct LabelStatsOptions {
  // Particles whose equivalent diameter is below this are flagged
  // below_limit (reported, not dropped). 0.2 mm: the smallest grain the
  // reference study's segmentation resolves (its section 3.2).
  double detection_limit_m = 0.2e-3;
  bool collect_surface = true;  // gather boundary voxels for hulls
  int threads = 0;              // OpenMP threads; 0 = the OpenMP default
};

struct LabelStats {
  uint32_t label = 0;
  int64_t voxels = 0;
  double volume_m3 = 0;
  std::array<double, 3> centroid_m{0, 0, 0};   // (z, y, x)
  std::array<int64_t, 3> box_lo{0, 0, 0};      // first voxel index, (k, j, i)
  std::array<int64_t, 3> box_hi{0, 0, 0};      // one past the last voxel index
  Eigen::Matrix3d inertia_m5 = Eigen::Matrix3d::Zero();  // about the centroid, unit density, (z, y, x)
  Eigen::Vector3d principal_moments_m5 = Eigen::Vector3d::Zero();  // ascending
  Eigen::Matrix3d principal_axes = Eigen::Matrix3d::Identity();   // columns, matching the moments
  // Equivalent ellipsoid: the solid ellipsoid with the same second moments,
  // semi-axes a_i = sqrt(5 lambda_i) for the eigenvalues lambda_i of the
  // covariance C / V (a solid ellipsoid's covariance along an axis is a^2/5),
  // descending, with their unit axes as columns (z, y, x).
  Eigen::Vector3d ellipsoid_semi_axes_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d ellipsoid_axes = Eigen::Matrix3d::Identity();
  double d_eq_m = 0;
  bool touches_border = false;
  bool below_limit = false;
};

struct LabelStatsResult {
  std::vector<LabelStats> labels;  // one per non-zero label present, ascending label
  // Boundary voxels of labels[n]: surface[surface_offset[n] .. surface_offset[n+1]),
  // in scan order (z, then y, then x). Empty when collect_surface is false.
  std::vector<int64_t> surface_offset;
  std::vector<SurfaceVoxel> surface;
  std::span<const SurfaceVoxel> surface_of(size_t n) const {
    return {surface.data() + surface_offset[n], static_cast<size_t>(surface_offset[n + 1] - surface_offset[n])};
  }
};

// Statistics of every non-zero label. Needs the view's voxel size
// (UsageError otherwise). label_sums over the whole volume, then
// label_stats_from_sums.
LabelStatsResult label_stats(const VolumeView<const uint32_t>& labels, const LabelStatsOptions& opt = {});

// The exact integer sums behind one label's statistics. Sums of two parts
// of a label merged in any order are the sums of the whole, which is what
// lets a volume larger than memory be measured slab by slab
// (measure_chunked.hpp) with the numbers of the whole volume.
struct LabelMoments {
  int64_t n = 0, sk = 0, sj = 0, si = 0, skk = 0, sjj = 0, sii = 0, skj = 0, ski = 0, sji = 0;
  std::array<int64_t, 3> lo{INT64_MAX, INT64_MAX, INT64_MAX};  // first voxel index (k, j, i)
  std::array<int64_t, 3> hi{-1, -1, -1};                      // one past the last
  bool border = false;
  void merge(const LabelMoments& o);
};

// The sums of the labels with a voxel in slices [core_begin, core_end) of
// `window`. The window is a slab of a volume whose slice k_offset + w is
// the window's slice w, and must hold the slices just below and above the
// core unless the core reaches the volume's own first or last slice: then
// the boundary voxels and border flags are those of the whole volume. k is
// the whole volume's index everywhere (moments, boxes, surface voxels).
// Boundary lists are in scan order, so slabs taken in z order and
// concatenated per label give label_stats' lists.
struct LabelSums {
  std::vector<uint32_t> labels;        // ascending
  std::vector<LabelMoments> moments;   // aligned with labels
  std::vector<int64_t> surface_offset; // as LabelStatsResult (all 0 without collect_surface)
  std::vector<SurfaceVoxel> surface;
};
LabelSums label_sums(const VolumeView<const uint32_t>& window, int64_t core_begin, int64_t core_end, int64_t k_offset,
                     const LabelStatsOptions& opt = {});

// Statistics from the sums of the whole volume; `geometry` is the whole
// volume's (origin and voxel size).
LabelStatsResult label_stats_from_sums(LabelSums sums, const Geometry& geometry, const LabelStatsOptions& opt = {});

}  // namespace tg::measure
