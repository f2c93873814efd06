// The global map between two loading stages of an oedometer test, estimated
// from the particles themselves: y = M x + t (voxel coordinates, (z, y, x)).
//
// Method (one RANSAC fit, then a least-squares polish):
//  0. Where to look sideways, when the whole specimen moved (a cell remounted
//     or a scan recentred between stages): the mode of the (y, x) offsets of
//     all grain-sized pairs of similar volume, voted in bins of the lateral
//     radius; kept only when it gathers 25 % more pairs than a zero offset,
//     else (0, 0). When under a quarter of the grain-sized particles agree
//     even so, the specimen may have been turned about its axis: A is turned
//     in steps that move the scan's rim by half a bin, the offset voted
//     again at each angle (with up to 100 of A's grains and offsets within a
//     quarter of the scan's radius), and the best angle kept when it gathers
//     half as many pairs again as no turn (cost: angles x 100 x nB, only
//     then: ~2 s for 256 grains here). Step 1 searches
//     around the prior; the affine fit takes the rotation in. Measured on a
//     blind scene (truth labels, 256 grains, R 16), stage 1 against stage 0:
//     5 % strain plus a shift of (7, 12) voxels, and a turn of 30 degrees,
//     went from failed fits (52.7 % and 43.7 % of grains "broken") to every
//     grain intact with its right parent.
//  1. Candidate centroid matches. Between two stages the specimen shortens
//     along z (the top platen moves, the bottom one is fixed) and grains move
//     little sideways, so every "grain-sized" particle of stage A (volume
//     >= 0.3 x the median) is paired with the particles of stage B whose
//     centroid lies within `lateral_radius_vox` in (y, x), within
//     `max_axial_vox` in z, and whose volume is within a factor
//     `volume_ratio` of its own; the `candidates` nearest in (y, x) are kept.
//  2. cv::estimateAffine3D (RANSAC over 4-point samples, OpenCV's fixed seed,
//     so deterministic) fits the 12-parameter affine to these pairs; the
//     inliers are the pairs within `ransac_threshold_vox` of the fit.
//  3. Polish: every A particle is moved by the fit, its nearest B particle of
//     similar volume within the threshold is taken when the pairing is mutual,
//     and M, t are refitted by least squares (Eigen, normal equations of the
//     12 unknowns) on those pairs. Repeated twice.
//  When fewer than `min_matches` pairs support the fit (few grains, a stage
//  emptied, everything broken), the map falls back to identity plus uniform
//  axial compression about the fixed platen: z' = z_fix + (1 - e)(z - z_fix),
//  with the strain increment e and z_fix given by the caller (method
//  "fallback").
//
// The axial scale M_zz is 1 - (strain increment): M_zz > 1 means the specimen
// got longer, i.e. stages given out of order (track.hpp checks it).
//
// Reference: M. A. Fischler, R. C. Bolles (1981), Random sample consensus,
// Commun. ACM 24(6) 381-395, doi:10.1145/358669.358692.
// Cost: O(nA nB) for the offset vote and the candidate search (a few thousand particles per
// stage: milliseconds), RANSAC <= 2000 iterations (OpenCV's cap), polish
// O(nA nB) per round.
#pragma once
#include <Eigen/Core>
#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

namespace tg::track {

// Radius of the sphere of this volume (any unit cubed -> that unit).
inline double r_eq(double volume) { return std::cbrt(3 * volume / (4 * std::numbers::pi)); }

struct Point {
  std::array<double, 3> c{0, 0, 0};  // centroid, voxel coordinates (z, y, x)
  double volume = 0;                  // voxels
};

struct MapOptions {
  double lateral_radius_vox = 0;  // 0: 0.5 x the median equivalent radius, at least 3 voxels
  double max_axial_vox = 0;       // 0: 25 % of the z extent given to estimate_map
  double volume_ratio = 1.5;      // candidate pairs differ in volume by at most this factor
  int candidates = 4;             // kept per A particle
  double ransac_threshold_vox = 0;  // 0: 0.3 x the median equivalent radius, at least 1.5 voxels
  int min_matches = 8;            // fewer supporting pairs -> fallback map
  double fallback_strain = 0;     // strain increment of the fallback map
  double fixed_plane_vox = 0;     // z of the fixed platen (voxel coordinate) for the fallback
};

struct StageMap {
  Eigen::Matrix3d M = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  int matches = 0;           // pairs the final fit rests on
  double rms_vox = 0;        // RMS residual of those pairs
  std::string method = "identity";  // "ransac" | "fallback" | "identity" (no particles)
  double axial_scale() const { return M(0, 0); }
  Eigen::Vector3d apply(const std::array<double, 3>& x) const { return M * Eigen::Vector3d(x[0], x[1], x[2]) + t; }
};

// A, B: particles of two consecutive stages; z_extent_vox: the stage's z size.
StageMap estimate_map(const std::vector<Point>& a, const std::vector<Point>& b, double z_extent_vox,
                      const MapOptions& options = {});

}  // namespace tg::track
