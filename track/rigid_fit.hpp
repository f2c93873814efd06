// Rotation (and refined shift) of one particle between two stages, by rigid
// registration of its grey levels: `track --scans` (issue #20: "optionally
// refine a particle's motion by a rigid registration of its grey levels, as
// SPAM's discrete DIC does"; the lineage's rotation columns).
//
// Method: the particle's region at the later stage B (its label's voxels and
// their one-voxel rim in the void, so the surface's gradient counts; not
// within 2 + smoothing_vox / 2 voxels of another particle: a contact does not
// turn with it, and the PSF and the smoothing carry the neighbour's grey
// there; other particles are
// blanked to the void's grey in both scans) is mapped into the
// earlier stage A by x_A = R (x_B - c) + c + t (c: the region's centroid)
// and the grey sum of squares sum_x (A(x_A) - B(x))^2 is minimised over the
// six parameters by Gauss-Newton, as in SPAM's `register` (Tudisco et al.
// 2017, "An extension of digital volume correlation for multimodality image
// registration", Meas. Sci. Technol. 28 095401; the Gauss-Newton DVC of Bay
// et al. 1999, Exp. Mech. 39 217). Both scans are smoothed about the particle
// by a Gaussian (smoothing_vox; the same kernel on both leaves a rigid
// motion's optimum where it was, and damps the noise); A is sampled by
// cubic convolution (Keys 1981, IEEE Trans. ASSP 29 1153): trilinear
// interpolation's error at the surface follows the grid and biased the turn
// by ~0.2 degree on the test's grain, cubic by ~0.05. The Jacobian uses B's
// gradient (central differences) turned by R, [R grad B, R (p x grad B)],
// p = x - c: it equals A's at the solution and, unlike the interpolated
// gradient of A, does not jump from cell to cell (which kept the iteration
// cycling). It starts from the translation the tracker predicts (the
// parent's moved centroid) and no rotation. The particle's own rotation
// A -> B is R^T: reported as a rotation vector (axis times angle, degrees, in
// (z, y, x) voxel axes) with its standard error from the fit's covariance
// sigma^2 (J^T J)^-1 (the largest standard deviation over the rotation's
// directions), sigma^2 the residual variance times the smoothing's
// correlation volume (2 sqrt(pi) sigma)^3 (so many smoothed voxels make one
// independent sample): it says where the grey holds too little to turn on
// (a featureless ball: large).
//
// A fit that does not converge in max_iterations, moves the particle more
// than max_correction_vox from the start, or has too few voxels, reports no
// rotation (NaN). Grey scales of the two stages are taken as they are (one
// scanner, one calibration).
//
// Cost: per iteration one 64-sample interpolation and a 6 x 6 accumulation
// per region voxel (every second voxel per axis in boxes over
// dense_box_voxels: the smoothed grey is correlated over ~45 voxels),
// converging in 3-6 iterations; plus the two smoothed boxes. Measured in
// bench/track/RESULTS.md ("Rotation from the grey levels").
#pragma once
#include <array>
#include <cstdint>
#include <limits>

#include <Eigen/Dense>

#include "core/dtype.hpp"
#include "core/volume.hpp"

namespace tg::track {

struct RigidFitOptions {
  int max_iterations = 30;
  double tolerance_vox = 1e-3;       // converged when the update moves no region voxel more than this
  double max_correction_vox = 3.0;   // a fit that moves the particle further than this from the start fails
  int64_t min_voxels = 27;
  double smoothing_vox = 1.0;  // Gaussian sigma (voxels) of both scans about the particle
  int64_t dense_box_voxels = 8000;  // particles whose box holds more are sampled on every 2nd voxel per axis
  // Larger boxes are not fitted (NaN): a label spanning the scan (a matrix, a mislabelled
  // background) would copy it twice as floats per thread. 2^24 voxels: a grain of radius ~120.
  int64_t max_box_voxels = int64_t{1} << 24;
};

struct RigidFit {
  bool ok = false;
  Eigen::Vector3d rotation_deg = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  double rotation_se_deg = std::numeric_limits<double>::quiet_NaN();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();  // x_A = R (x_B - c) + c + t
  int iterations = 0;
  int64_t voxels = 0;
  double rms = std::numeric_limits<double>::quiet_NaN();  // residual grey RMS
};

// Fits particle `label` of `labels_b` (box [lo, hi) in voxel indices) between
// grey volumes `a` and `b` (b the same shape as labels_b; a may differ), from
// x_A = x_B + t0. Positions are voxel centres (k + 0.5, j + 0.5, i + 0.5).
// `labels_a` (optional): A's labels, where every label but `label_a` (the parent) is blanked like
// B's other labels.
RigidFit fit_rigid(const AnyVolume& a, const AnyVolume& b, const Volume<uint32_t>& labels_b, uint32_t label,
                   const std::array<int64_t, 3>& lo, const std::array<int64_t, 3>& hi, const Eigen::Vector3d& t0,
                   const RigidFitOptions& o = {}, const Volume<uint32_t>* labels_a = nullptr, uint32_t label_a = 0);

// Rotation vector (radians) of a rotation matrix, and back.
Eigen::Vector3d rotation_vector(const Eigen::Matrix3d& R);
Eigen::Matrix3d rotation_matrix(const Eigen::Vector3d& w);

}  // namespace tg::track
