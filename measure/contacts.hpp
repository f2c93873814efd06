// Contacts between particles of a label volume, per-particle coordination and
// the fabric tensor of the contact normals.
//
// What counts as a contact. Labels a != b touch when a lattice line (along z,
// y or x) goes from a voxel of a to a voxel of b through at most `cap` void
// voxels (a "crossing"): cap = 0 when a and b share faces anywhere (labels
// face to face, no watershed line), otherwise the thickness, along the
// counting axis, of a 26-separating one-voxel watershed line for the pair's
// normal n (segmentation/watershed.hpp draws such lines: a and b are never
// 26-adjacent):  cap = ceil(sum_d |n_d| h_d / (|n_c| h_c) - 0.05), 1..3,
// i.e. 1 for a line normal to an axis, 3 for one along a cube diagonal. So
// the detection tolerance is one watershed line: particles whose surfaces
// are closer than ~1 voxel (1 to 1.3 voxel along the normal, depending on
// its direction) are in contact; farther ones are not.
//
// Steps (per pair, all sums are integer, so the result is exact and
// independent of the thread count):
//  1. Three scans of the volume (one per axis) list the crossings with at
//     most max_gap_voxels (3) void voxels, aggregated per pair, axis and
//     run length: count and the sum of their midpoints.
//  2. Provisional contact point: mean midpoint of the pair's crossings
//     (run 0 only when the pair is face to face).
//  3. Normal (unit, from a to b): the direction between the centroids of
//     a's and b's voxels inside a ball of radius normal_radius_voxels around
//     that point. Near a planar interface these are two half-balls whose
//     centroids lie on the normal through the centre; on two spheres they
//     are two caps symmetric about the line of centres, so the estimate is
//     the line of centres however small the contact (the interface voxels
//     themselves are too few for a plane fit at a point contact). The ball
//     averages thousands of voxels, which cancels the staircase. Void voxels
//     with both a and b among their 26 neighbours (the watershed line) count
//     half for each side, so a line drawn on one side does not tilt it.
//     Radius 9 voxels (default) against 6 on the tuning scenes (seeds 3-5)
//     of the test, grains of radius 20-23: median normal error 0.35 deg (face to face)
//     and 0.5 deg (lines) against 0.9 and 1.4 deg, fabric anisotropy within
//     0.01 instead of 0.04. On grains of radius < ~10 voxels the ball holds
//     most of both grains and the normal tends to the line between their
//     centroids (the branch vector). A deviation from SPAM (Ando et al.
//     2012, doi:10.1007/s10035-012-0326-2), which fits the contact zone.
//  4. Counting axis c = argmax |n_c| h_c (the most crossings per area);
//     accepted crossings: those along c with run <= cap (step "what counts").
//     No accepted crossing: no contact (a gap wider than a line).
//  5. Area = N_c * (face area normal to c) / |n_c|: a planar interface of
//     area A with unit normal n is crossed by A |n_c| / face_c lines along
//     c (exactly one crossing per line when the line's run <= cap), so the
//     estimate is unbiased for a planar contact of known normal, without
//     the staircase's 1.5x excess of counting faces. Its bias is the rim:
//     crossings are also accepted where the two surfaces diverge but are
//     still within `cap` voxels, which adds an annulus, and a point contact
//     is digitised into a small patch: two tangent spheres of radius 10
//     voxels, face to face, read 32 voxel^2 where the truth is 0, so areas
//     of a few tens of voxel^2 are resolution-limited. Lens-shaped contacts
//     of two radius-20 spheres (550 voxel^2): within 4.3 % face to face,
//     18 % with lines (tests/measure/contacts_test.cpp).
//  6. Contact point: mean midpoint of the accepted crossings (metres).
//
// Fabric (Oda 1982, doi:10.1016/0038-0806(82)90061-8; Kanatani 1984,
// doi:10.1016/0020-7225(84)90090-9): N = <n (x) n> over contacts (sign-free),
// trace 1; deviator D = N - I/3; F = (15/2) D, the coefficient of the
// second-order Fourier approximation E(n) = (1 + F:(n (x) n)) / (4 pi) of the
// normals' density; anisotropy a = sqrt(3/2 F:F) (the convention of SPAM's
// fabricTensor and of Kuhn's "a"; 0 for isotropic normals, 15/2 sqrt(3/2)
// |D| in general; all normals along one axis give a = 7.5). The same
// formula applied to the truth's normals is what the tests compare with.
//
// Cost: three streaming passes over the volume, O(V); per pair O(r^3) for
// the ball (r = normal_radius_voxels). Memory: O(ny nx) line state per
// z-scan, plus one aggregate per candidate pair per thread.
// Coordinates (z, y, x), metres; voxel (k, j, i) centre at origin + h (k + 0.5, ...).
#pragma once
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "core/volume.hpp"

namespace tg::measure {

struct ContactOptions {
  int max_gap_voxels = 3;             // longest void run listed in step 1 (3 = a diagonal watershed line)
  double normal_radius_voxels = 9.0;  // radius of the ball of step 3 (tuned: header)
  int threads = 0;                    // OpenMP threads; 0 = the OpenMP default
};

struct Contact {
  uint32_t a = 0, b = 0;   // a < b
  double area_m2 = 0;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit, from a to b, (z, y, x)
  Eigen::Vector3d point_m = Eigen::Vector3d::Zero();  // (z, y, x)
  int64_t crossings = 0;   // accepted crossings along the counting axis
  int axis = 0;            // counting axis: 0 = z, 1 = y, 2 = x
  bool face_to_face = false;  // a and b share faces (no watershed line between them)
};

struct ContactResult {
  std::vector<Contact> contacts;  // sorted by (a, b)
};

// All contacts of a label volume (needs its voxel size, UsageError otherwise).
ContactResult find_contacts(const VolumeView<const uint32_t>& labels, const ContactOptions& opt = {});

// The same contacts, found slab by slab (measure_chunked.hpp; find_contacts
// is this on one slab). Step 1's crossings are integer sums: a slab records
// the crossings that end in its core, for which its window must hold
// kCrossingMarginBelow slices below the core (a z line's previous labelled
// voxel is at most 4 slices lower for a run of <= 3 void voxels) unless the
// core starts at the volume's first slice. Once every slab is added, each
// pair's provisional point (step 2) is known, and a second pass over slabs
// with ball_margin() slices below and above their core computes the normals
// (step 3) of the pairs whose point lies in the core; steps 4-6 need no
// voxels. Windows: slices k_offset .. k_offset + nz - 1 of the whole volume.
inline constexpr int64_t kCrossingMarginBelow = 4;
class ContactSearch {
 public:
  ContactSearch(const Shape& whole, const Geometry& geometry, const ContactOptions& opt);  // UsageError on bad options
  ~ContactSearch();
  ContactSearch(const ContactSearch&) = delete;
  ContactSearch& operator=(const ContactSearch&) = delete;
  // Pass 1: crossings ending in core slices [core_begin, core_end) of the window.
  void add_crossings(const VolumeView<const uint32_t>& window, int64_t core_begin, int64_t core_end, int64_t k_offset);
  // Slices a pass-2 window needs below and above its core.
  int64_t ball_margin() const;
  // Pass 2: the normals of the pairs whose provisional point lies in the core.
  void add_normals(const VolumeView<const uint32_t>& window, int64_t core_begin, int64_t core_end, int64_t k_offset);
  // The contacts, sorted by (a, b), once both passes covered the volume.
  ContactResult result();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Number of contacts of each label in `labels` (any order; labels absent
// from every contact get 0).
std::vector<int> coordination(std::span<const Contact> contacts, std::span<const uint32_t> labels);

struct Fabric {
  int64_t contacts = 0;
  Eigen::Matrix3d N = Eigen::Matrix3d::Zero();          // <n (x) n>, (z, y, x)
  Eigen::Matrix3d deviator = Eigen::Matrix3d::Zero();   // N - I/3
  Eigen::Matrix3d F = Eigen::Matrix3d::Zero();          // 15/2 deviator
  double anisotropy = 0;                                // sqrt(3/2 F:F)
  Eigen::Vector3d eigenvalues = Eigen::Vector3d::Zero();  // of N, descending
  Eigen::Vector3d major_axis = Eigen::Vector3d::UnitZ();  // eigenvector of the largest
};

// Fabric of unit normals (NaN entries when `normals` is empty).
Fabric fabric(std::span<const Eigen::Vector3d> normals);

// Angle between a normal and the z axis (the loading axis), sign-free:
// acos |n_z| in degrees, 0..90.
double polar_angle_deg(const Eigen::Vector3d& n);

// Distribution of the polar angle over bands [edges[k], edges[k+1]) (the
// last band includes 90). density[k] = (share of the normals in band k) /
// (share an isotropic set would have, cos edges[k] - cos edges[k+1]), so
// isotropic normals read 1 in every band and E(n) = density / (4 pi).
struct PolarHistogram {
  std::vector<double> edges_deg;  // ascending, 0 .. 90
  std::vector<int64_t> count;
  std::vector<double> density;   // NaN when there is no normal
};
PolarHistogram polar_histogram(std::span<const Eigen::Vector3d> normals, std::vector<double> edges_deg);
// Edges of `bands` bands of equal solid angle: acos(1 - k / bands) in degrees
// (each holds 1/bands of isotropic normals: equal counting noise per band).
std::vector<double> equal_solid_angle_edges_deg(int bands);

// Mean coordination by size class: the particles sorted by size (ties by
// coordination) and cut into `classes` groups of equal count (quartiles for
// 4); `size` and `coordination` are per particle, same order.
struct SizeClass {
  double size_from = 0, size_to = 0;  // smallest and largest size in the class
  int64_t particles = 0;
  double mean_coordination = 0;
};
std::vector<SizeClass> coordination_by_size(std::span<const double> size, std::span<const double> coordination,
                                            int classes = 4);

}  // namespace tg::measure
