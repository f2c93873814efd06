#include "segmentation/markers.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <omp.h>

#include "core/errors.hpp"
#include "segmentation/neighbourhood.hpp"

namespace tg {
namespace {

constexpr uint32_t kDecided = 1u << 31;  // a flood from this height already settled this voxel
constexpr uint32_t kVisited = 1u << 30;  // in the current flood
constexpr uint32_t kMarkerMask = kVisited - 1;

// The candidates of 26-connectivity: the solid voxels whose 3x3x3 block
// holds nothing higher. The block's maximum of the masked distance (void
// and outside the volume: -inf) is separable: along x within each row,
// then along y within the slice, then over three slices; each thread keeps
// the plane maxima of three slices and one scratch plane (4 nx ny floats),
// so the test costs a few vector max operations a voxel instead of up to
// 26 dependent branches. Same candidates as the neighbour loop.
// By value, as MAXPS computes it (std::max returns a reference, which
// kept GCC from vectorising the loops below).
template <class T>
inline T max2(T a, T b) {
  return a > b ? a : b;
}

// T: float, or uint16_t (FixedDistance: the void is 0, below every solid value).
template <class T, class Solid>
void list_candidates_26(const T* d, Solid solid, const Shape& s, std::vector<std::vector<int64_t>>& part) {
  const int64_t nx = s.nx, ny = s.ny, sl = s.slice_voxels();
  constexpr T kLow = std::numeric_limits<T>::has_infinity ? -std::numeric_limits<T>::infinity()
                                                          : std::numeric_limits<T>::lowest();
#pragma omp parallel num_threads(int(part.size()))
  {
    auto& mine = part[size_t(omp_get_thread_num())];
    std::vector<T> row(static_cast<size_t>(nx)), x3(static_cast<size_t>(sl)), planes(3 * static_cast<size_t>(sl));
    // Plane maximum (3x3 in y and x) of slice k into out; -inf outside.
    auto plane_max = [&](int64_t k, T* out) {
      if (k < 0 || k >= s.nz) {
        std::fill(out, out + sl, kLow);
        return;
      }
      const T* dk = d + k * sl;
      for (int64_t j = 0; j < ny; ++j) {
        const T* dr = dk + j * nx;
        const int64_t r0 = k * sl + j * nx;
        T* xr = x3.data() + j * nx;
        T* rw = row.data();
        for (int64_t i = 0; i < nx; ++i) {
          const T v = dr[i];  // loaded whatever the mask says: a select, not a branch
          rw[i] = solid(r0 + i) ? v : kLow;
        }
        xr[0] = nx > 1 ? max2(rw[0], rw[1]) : rw[0];
        for (int64_t i = 1; i + 1 < nx; ++i) xr[i] = max2(max2(rw[i - 1], rw[i]), rw[i + 1]);
        if (nx > 1) xr[nx - 1] = max2(rw[nx - 2], rw[nx - 1]);
      }
      for (int64_t j = 0; j < ny; ++j) {
        const T* up = x3.data() + std::max<int64_t>(j - 1, 0) * nx;  // row j itself at the edges: same max
        const T* mid = x3.data() + j * nx;
        const T* dn = x3.data() + std::min(j + 1, ny - 1) * nx;
        T* o = out + j * nx;
        for (int64_t i = 0; i < nx; ++i) o[i] = max2(max2(up[i], mid[i]), dn[i]);
      }
    };
    // This thread's slices: the t-th chunk, as schedule(static) gives it.
    const int t = omp_get_thread_num(), nt = omp_get_num_threads();
    const int64_t k0 = s.nz * t / nt, k1 = s.nz * (t + 1) / nt;
    T* pl[3] = {planes.data(), planes.data() + sl, planes.data() + 2 * sl};  // slices k-1, k, k+1
    if (k0 < k1) {
      plane_max(k0 - 1, pl[0]);
      plane_max(k0, pl[1]);
    }
    for (int64_t k = k0; k < k1; ++k) {
      plane_max(k + 1, pl[2]);
      const T* dk = d + k * sl;
      const T *p0 = pl[0], *p1 = pl[1], *p2 = pl[2];
      auto is_candidate = [&](int64_t i) { return solid(k * sl + i) && !(max2(max2(p0[i], p1[i]), p2[i]) > dk[i]); };
      // Candidates are rare (1 voxel in 2000 at 256^3): a vectorised test of
      // 64 voxels at a time, and a second look only where it finds one.
      for (int64_t i0 = 0; i0 < sl; i0 += 64) {
        const int64_t i1 = std::min(sl, i0 + 64);
        int hit = 0;
        for (int64_t i = i0; i < i1; ++i) hit |= int(solid(k * sl + i)) & int(!(max2(max2(p0[i], p1[i]), p2[i]) > dk[i]));
        if (!hit) continue;
        for (int64_t i = i0; i < i1; ++i)
          if (is_candidate(i)) mine.push_back(k * sl + i);
      }
      std::rotate(pl, pl + 1, pl + 3);
    }
  }
}

// The markers of the solid voxels x for which solid(x) holds; h_units is
// opt.h in the map's units (FixedDistance::per_unit of them a voxel).
template <class T, class Solid>
uint32_t markers_of(const Volume<T>& dist, Solid solid, Volume<uint32_t>& markers, const MarkerOptions& opt,
                    double h_units) {
  if (!(opt.h >= 0) || !std::isfinite(opt.h)) throw UsageError("markers: h must be finite and >= 0");
  const Shape s = dist.shape();
  if (markers.shape() != s) markers = Volume<uint32_t>(s, dist.geometry());
  markers.set_geometry(dist.geometry());
  {
    uint32_t* z = markers.data();
    const int64_t nz = markers.size();
#pragma omp parallel for schedule(static)  // also spreads a fresh volume's page faults
    for (int64_t i = 0; i < nz; ++i) z[i] = 0;
  }
  const seg::Neighbourhood nb(s, opt.connectivity);
  const T* d = dist.data();
  uint32_t* M = markers.data();
  uint32_t count = 0;
  std::vector<int64_t> queue;

  // Calls f(n) for each neighbour n of idx inside the volume.
  auto for_neighbours = [&](int64_t idx, auto&& f) {
    const auto [k, j, i] = s.coords(idx);
    const bool in = seg::interior(s, k, j, i);
    for (int q = 0; q < nb.count; ++q) {
      if (!in) {
        const seg::Step st = nb.step[size_t(q)];
        if (!s.contains(k + st.dz, j + st.dy, i + st.dx)) continue;
      }
      if (!f(idx + nb.offset[size_t(q)])) return;
    }
  };

  // Candidates: solid voxels with no higher neighbour (plateaus of local
  // maxima included), found in parallel and listed in index order (thread
  // t has the t-th chunk of the static schedule). The caps are then grown
  // serially from the candidates in that order, as the one serial scan
  // did before (same markers, same numbering).
  const int64_t n = dist.size();
  const int nthreads = omp_get_max_threads();
  std::vector<std::vector<int64_t>> part(static_cast<size_t>(nthreads));
  if (opt.connectivity == 26) {
    list_candidates_26(d, solid, s, part);
  } else {
#pragma omp parallel num_threads(nthreads)
    {
      auto& mine = part[size_t(omp_get_thread_num())];
#pragma omp for schedule(static)
      for (int64_t k = 0; k < s.nz; ++k)
        for (int64_t j = 0; j < s.ny; ++j) {
          const bool inner_row = k > 0 && j > 0 && k + 1 < s.nz && j + 1 < s.ny;
          for (int64_t i = 0; i < s.nx; ++i) {
            const int64_t idx = s.index(k, j, i);
            if (!solid(idx)) continue;
            const T top = d[idx];
            bool higher = false;
            if (inner_row && i > 0 && i + 1 < s.nx) {
              for (int q = 0; q < nb.count && !higher; ++q) {
                const int64_t y = idx + nb.offset[size_t(q)];
                higher = solid(y) && d[y] > top;
              }
            } else {
              for_neighbours(idx, [&](int64_t y) {
                if (solid(y) && d[y] > top) higher = true;
                return !higher;
              });
            }
            if (!higher) mine.push_back(idx);
          }
        }
    }
  }
  for (const auto& cand : part) {
    for (const int64_t start : cand) {
      if (M[start] & kDecided) continue;
      const T top = d[start];
      bool higher = false;
      // Flood the cap {d >= top - h} from `start`, stopping at a higher voxel.
      const double floor_level = double(top) - h_units;
      queue.clear();
      queue.push_back(start);
      M[start] |= kVisited;
      for (size_t head = 0; head < queue.size() && !higher; ++head)
        for_neighbours(queue[head], [&](int64_t q) {
          if (!solid(q) || (M[q] & kVisited) || double(d[q]) < floor_level) return true;
          if (d[q] > top) {
            higher = true;
            return false;
          }
          M[q] |= kVisited;
          queue.push_back(q);
          return true;
        });
      const uint32_t label = higher ? 0 : ++count;
      if (count > kMarkerMask) throw ResourceError("markers: more than 2^30 markers");
      for (int64_t q : queue) {
        uint32_t v = M[q] & ~kVisited;
        if (d[q] == top) v |= kDecided;  // same height, same cap: same outcome
        // A kept cap cannot overlap another kept cap (its dynamic would be < h),
        // so a voxel is labelled at most once.
        if (label) v = (v & kDecided) | label;
        M[q] = v;
      }
    }
  }
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < n; ++i) M[i] &= kMarkerMask;
  return count;
}

}  // namespace

uint32_t find_markers(const Volume<float>& dist, const Volume<uint8_t>& solid, Volume<uint32_t>& markers,
                      const MarkerOptions& opt) {
  if (dist.shape() != solid.shape())
    throw UsageError("markers: distance map " + dist.shape().str() + " and mask " + solid.shape().str() +
                     " differ in shape");
  const uint8_t* m = solid.data();
  const uint32_t n = markers_of(dist, [m](int64_t x) { return m[x] != 0; }, markers, opt, opt.h);
  markers.set_geometry(solid.geometry());
  return n;
}

uint32_t find_markers(const Volume<float>& dist, Volume<uint32_t>& markers, const MarkerOptions& opt) {
  const float* d = dist.data();
  return markers_of(dist, [d](int64_t x) { return d[x] > 0; }, markers, opt, opt.h);
}

uint32_t find_markers(const FixedDistance& dist, Volume<uint32_t>& markers, const MarkerOptions& opt) {
  const uint16_t* d = dist.map.data();
  return markers_of(dist.map, [d](int64_t x) { return d[x] > 0; }, markers, opt, opt.h * dist.per_unit);
}

}  // namespace tg
