// Voxel neighbourhoods and 64-bit index helpers shared by the segmentation
// kernels.
//
// The 26 neighbours of a voxel, ordered so that the first 6 are the face
// neighbours, the first 18 add the edge neighbours and all 26 add the corner
// neighbours; connectivity c uses the first c entries:
//
//        z-1 slice          z slice            z+1 slice
//      C  E  C            E  F  E            C  E  C       F face   (6)
//      E  F  E            F  .  F            E  F  E       E edge   (12)
//      C  E  C            E  F  E            C  E  C       C corner (8)
//
// Linear offsets (dz*ny + dy)*nx + dx are int64_t: a 1220^3 scan has 1.8e9
// voxels, so a 32-bit offset wraps (tests check this on a >2^31 Shape
// without allocating). Kernels use the offsets directly for interior voxels
// and the (dz, dy, dx) triplets with a bounds test only on the volume border.
#pragma once
#include <array>
#include <cstdint>
#include <string>

#include "core/errors.hpp"
#include "core/shape.hpp"

namespace tg::seg {

struct Step {
  int dz, dy, dx;
};

inline constexpr std::array<Step, 26> kSteps = {{
    // faces
    {-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1},
    // edges
    {-1, -1, 0}, {-1, 1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 0, -1}, {-1, 0, 1},
    {1, 0, -1}, {1, 0, 1}, {0, -1, -1}, {0, -1, 1}, {0, 1, -1}, {0, 1, 1},
    // corners
    {-1, -1, -1}, {-1, -1, 1}, {-1, 1, -1}, {-1, 1, 1}, {1, -1, -1}, {1, -1, 1}, {1, 1, -1}, {1, 1, 1},
}};

inline void check_connectivity(int c) {
  if (c != 6 && c != 18 && c != 26)
    throw UsageError("connectivity " + std::to_string(c) + ": only 6, 18 and 26 are supported in 3-D");
}

// Linear offset of a step in a volume of this shape.
inline int64_t step_offset(const Shape& s, const Step& d) {
  return (int64_t(d.dz) * s.ny + d.dy) * s.nx + d.dx;
}

// The neighbourhood of one connectivity in one shape: steps and their offsets.
struct Neighbourhood {
  int count = 0;
  std::array<Step, 26> step{};
  std::array<int64_t, 26> offset{};

  Neighbourhood(const Shape& s, int connectivity) {
    check_connectivity(connectivity);
    count = connectivity;
    for (int n = 0; n < count; ++n) {
      step[size_t(n)] = kSteps[size_t(n)];
      offset[size_t(n)] = step_offset(s, kSteps[size_t(n)]);
    }
  }
  // Only the steps that precede the voxel in raster order (dz, dy, dx
  // lexicographically negative): the mask of a forward labelling pass.
  static Neighbourhood backward(const Shape& s, int connectivity) {
    Neighbourhood all(s, connectivity), b(s, 6);
    b.count = 0;
    for (int n = 0; n < all.count; ++n) {
      const Step d = all.step[size_t(n)];
      if (d.dz < 0 || (d.dz == 0 && (d.dy < 0 || (d.dy == 0 && d.dx < 0)))) {
        b.step[size_t(b.count)] = d;
        b.offset[size_t(b.count)] = all.offset[size_t(n)];
        ++b.count;
      }
    }
    return b;
  }
};

// True when all 26 neighbours of (k, j, i) lie inside the volume.
inline bool interior(const Shape& s, int64_t k, int64_t j, int64_t i) {
  return k > 0 && j > 0 && i > 0 && k + 1 < s.nz && j + 1 < s.ny && i + 1 < s.nx;
}
inline bool on_border(const Shape& s, int64_t k, int64_t j, int64_t i) { return !interior(s, k, j, i); }

}  // namespace tg::seg
