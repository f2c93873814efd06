// Shape of a 3-D volume and its 64-bit index arithmetic.
//
// Layout: (z, y, x), contiguous in x. Linear index of voxel (k, j, i) is
// (k * ny + j) * nx + i, always in int64_t: a full scan is 1220^3 ~ 1.8e9
// voxels, past 2^31, so 32-bit arithmetic silently wraps.
//
// Coordinate convention (every module): voxel (k, j, i) covers
// [k, k+1) x [j, j+1) x [i, i+1) in voxel units, its centre is at
// (k+0.5, j+0.5, i+0.5); physical position = origin + voxel_size * coordinate.
#pragma once
#include <array>
#include <cstdint>
#include <string>

#include "core/errors.hpp"

namespace tg {

struct Shape {
  int64_t nz = 0, ny = 0, nx = 0;

  friend bool operator==(const Shape&, const Shape&) = default;

  // Number of voxels; throws ResourceError if it does not fit in int64_t or
  // a dimension is negative. Checked once at allocation, not in loops.
  int64_t voxels() const {
    if (nz < 0 || ny < 0 || nx < 0)
      throw UsageError("negative volume dimension " + str());
    int64_t n = 0;
    if (__builtin_mul_overflow(nz, ny, &n) || __builtin_mul_overflow(n, nx, &n))
      throw ResourceError("volume shape " + str() + " has more voxels than a 64-bit count holds");
    return n;
  }
  int64_t slice_voxels() const { return ny * nx; }
  bool empty() const { return nz == 0 || ny == 0 || nx == 0; }

  int64_t index(int64_t k, int64_t j, int64_t i) const { return (k * ny + j) * nx + i; }
  // Inverse of index(): (k, j, i) of a linear index.
  std::array<int64_t, 3> coords(int64_t idx) const {
    const int64_t i = idx % nx, r = idx / nx;
    return {r / ny, r % ny, i};
  }
  bool contains(int64_t k, int64_t j, int64_t i) const {
    return k >= 0 && j >= 0 && i >= 0 && k < nz && j < ny && i < nx;
  }
  std::string str() const {
    return std::to_string(nz) + "x" + std::to_string(ny) + "x" + std::to_string(nx) + " (z,y,x)";
  }
};

}  // namespace tg
