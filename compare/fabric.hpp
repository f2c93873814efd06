// Contact fabric side by side (issue 22): one series' contacts summarised the
// same way whether they come from labels (measure/contacts.hpp: experiment,
// DEM ideal, DEM imaged) or from the DEM's spheres (dem_stage.hpp's
// sphere_contacts: DEM exact).
//
// Per series: the fabric tensor N = <n (x) n> and anisotropy a (measure::fabric,
// the definition of `tomograin contacts`), the share of normals within 30 deg
// of the loading axis z (isotropic normals: 1 - cos 30 deg = 0.134), the
// distribution of the polar angle acos|n_z| in kPolarBands bands of equal
// solid angle (density 1 = isotropic), and the mean coordination by size
// quartile (equal-volume diameter d_eq; interior particles only for labels,
// see series.hpp).
#pragma once
#include <Eigen/Core>
#include <span>
#include <vector>

#include "core/table.hpp"
#include "measure/contacts.hpp"

namespace tg::compare {

inline constexpr int kPolarBands = 9;          // equal solid angle: 1/9 of isotropic normals each
inline constexpr double kNearAxisDeg = 30.0;   // "near the loading axis"

struct ContactSeries {
  bool measured = false;       // false: no contacts for this series (a particle-table input)
  Table contacts;              // a, b (labels or DEM particle ids), normal_z, normal_y, normal_x
  measure::Fabric fabric;
  double near_axis_share = 0;  // share of normals with polar angle <= kNearAxisDeg
  measure::PolarHistogram polar;
  std::vector<measure::SizeClass> by_size;  // size = d_eq (mm)
};

// Fabric, near-axis share and polar histogram of `normals` (z, y, x), and the
// contact table (pairs[k] = (a, b) of normals[k]); by_size is left to the caller.
ContactSeries contact_series(std::span<const std::pair<int64_t, int64_t>> pairs,
                             std::span<const Eigen::Vector3d> normals);

// Mean coordination of the particles the size classes cover (they partition them).
double mean_coordination(std::span<const measure::SizeClass> by_size);

// Coordination by d_eq quartile of a particle table's interior particles
// (columns d_eq_mm, coordination, touches_border; empty without them).
std::vector<measure::SizeClass> coordination_by_size(const Table& particles);

}  // namespace tg::compare
