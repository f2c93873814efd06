// Small binary test scenes drawn from centres (until data_synth scans are
// used): balls, touching pairs, split spheres, spheres with pores.
#pragma once
#include <cstdint>

#include "core/volume.hpp"

namespace tg::test {

// Sets voxels whose centre lies within r of (cz, cy, cx) (voxel-index
// coordinates of centres) to `value`.
inline void draw_ball(Volume<uint8_t>& m, double cz, double cy, double cx, double r, uint8_t value = 1) {
  const Shape s = m.shape();
  for (int64_t k = 0; k < s.nz; ++k)
    for (int64_t j = 0; j < s.ny; ++j)
      for (int64_t i = 0; i < s.nx; ++i) {
        const double dz = double(k) - cz, dy = double(j) - cy, dx = double(i) - cx;
        if (dz * dz + dy * dy + dx * dx <= r * r) m(k, j, i) = value;
      }
}

// Clears the slab x in [x0, x0 + width) (a planar gap splitting what is there).
inline void cut_slab_x(Volume<uint8_t>& m, int64_t x0, int64_t width) {
  const Shape s = m.shape();
  for (int64_t k = 0; k < s.nz; ++k)
    for (int64_t j = 0; j < s.ny; ++j)
      for (int64_t i = x0; i < x0 + width && i < s.nx; ++i) m(k, j, i) = 0;
}

inline int64_t count_value(const Volume<uint8_t>& m, uint8_t v) {
  int64_t n = 0;
  for (auto x : m.span()) n += x == v;
  return n;
}

}  // namespace tg::test
