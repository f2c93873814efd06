#include "segmentation/pore_filter.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <sstream>
#include <utility>
#include <vector>

#include <omp.h>

#include "core/errors.hpp"
#include "core/memory.hpp"
#include "segmentation/runs.hpp"

namespace tg {

PoreFilterOptions PoreFilterOptions::from_grain_radius(double r) {
  if (!(r > 0)) throw UsageError("pore filter: the expected grain radius must be positive (voxels)");
  PoreFilterOptions o;
  o.max_volume_vox = std::max<int64_t>(1, std::llround(0.02 * 4.0 / 3.0 * std::numbers::pi * r * r * r));
  o.min_sphericity = 0.5;
  return o;
}

std::string PoreFilterOptions::describe() const {
  std::ostringstream s;
  s << "fill enclosed voids with volume <= " << max_volume_vox << " voxels and sphericity >= " << min_sphericity
    << " (36 pi V^2/A^3, A = 2/3 of the voxel faces)";
  return s.str();
}

double voxel_sphericity(int64_t volume_vox, int64_t faces) {
  if (volume_vox <= 0 || faces <= 0) return 0.0;
  const double v = double(volume_vox), a = 2.0 / 3.0 * double(faces);
  return std::min(1.0, 36.0 * std::numbers::pi * v * v / (a * a * a));
}

namespace {

// A run of void voxels [a, b) along x within one row.
struct Run {
  int64_t a, b;
};

// Calls f(v) for each run v of `row` (sorted) that overlaps [a, b).
template <class F>
void for_overlaps(const Run* row, const Run* end, int64_t a, int64_t b, F&& f) {
  const Run* v = std::lower_bound(row, end, a, [](const Run& r, int64_t x) { return r.b <= x; });
  for (; v < end && v->a < b; ++v) f(*v);
}

}  // namespace

PoreFilterResult fill_pores(Volume<uint8_t>& solid, const PoreFilterOptions& opt, uint8_t solid_from,
                            uint8_t fill_value) {
  if (opt.max_volume_vox < 0 || !(opt.min_sphericity >= 0 && opt.min_sphericity <= 1))
    throw UsageError("pore filter: max volume must be >= 0 and min sphericity in [0, 1]");
  if (opt.void_connectivity != 6 && opt.void_connectivity != 26)
    throw UsageError("pore filter: the void's connectivity must be 6 or 26");
  if (solid_from == 0 || fill_value < solid_from) throw UsageError("pore filter: filled voxels must be solid");
  const Shape s = solid.shape();
  const int64_t nx = s.nx, ny = s.ny, rows = s.nz * s.ny;
  uint8_t* m = solid.data();
  PoreFilterResult res;
  if (s.empty()) return res;

  // The void as runs, row by row (counted, then written: rows in parallel).
  const std::vector<int64_t> first = seg::run_offsets(solid, [solid_from](uint8_t v) { return v < solid_from; });
  const int64_t R = first[size_t(rows)];
  if (R == 0) return res;
  // Per-run arrays uninitialised (every entry is written before it is
  // read) and first written by the threads: zeroing them, and taking their
  // fresh pages, in one thread was most of this function's time (a 256^3
  // scan: ~1.3 M runs, 40 MB of arrays, twice per segmentation).
  const LargeArray<Run> run = large_array<Run>(size_t(R));
#pragma omp parallel for schedule(static)
  for (int64_t r = 0; r < rows; ++r) {
    const uint8_t* row = m + r * nx;
    Run* out = run.get() + first[size_t(r)];
    for (int64_t i = 0; i < nx;) {
      if (row[i] >= solid_from) {
        ++i;
        continue;
      }
      const int64_t a = i;
      while (i < nx && row[i] < solid_from) ++i;
      *out++ = {a, i};
    }
  }
  auto row_runs = [&](int64_t k, int64_t j) {
    const int64_t r = k * ny + j;
    return std::pair<const Run*, const Run*>{run.get() + first[size_t(r)], run.get() + first[size_t(r) + 1]};
  };

  // Components (6-connectivity: runs overlapping in the row before, y - 1,
  // or the slice below, z - 1) by union-find over run numbers, the smaller
  // root kept; slabs of slices in parallel, then their seams, as in
  // connected_components: the sets do not depend on the split.
  LargeArray<int64_t> parent = large_array<int64_t>(size_t(R));
#pragma omp parallel for schedule(static)
  for (int64_t p = 0; p < R; ++p) parent[size_t(p)] = p;
  auto find = [&](int64_t x) {
    while (parent[size_t(x)] != x) {
      parent[size_t(x)] = parent[size_t(parent[size_t(x)])];
      x = parent[size_t(x)];
    }
    return x;
  };
  // 26-connectivity (slack 1): runs also touch corner to corner, in the
  // diagonal rows too.
  const int64_t slack = opt.void_connectivity == 26 ? 1 : 0;
  auto unite_with = [&](int64_t k, int64_t j, int64_t kk, int64_t jj) {
    if (jj < 0 || jj >= ny) return;
    const auto [b0, e0] = row_runs(k, j);
    const auto [b1, e1] = row_runs(kk, jj);
    // Both rows' runs are sorted: one walk over the two, uniting each
    // overlapping pair (u and v overlap when each starts before the other
    // ends, give or take the slack; runs of a row are a voxel apart at
    // least, so advancing the one that ends first still misses none).
    const Run *u = b0, *v = b1;
    while (u < e0 && v < e1) {
      if (u->a < v->b + slack && v->a < u->b + slack) {
        const int64_t x = find(u - run.get()), y = find(v - run.get());
        if (x < y) parent[size_t(y)] = x;
        else if (y < x) parent[size_t(x)] = y;
      }
      if (u->b < v->b) ++u;  // the run that ends first meets nothing further on
      else ++v;
    }
  };
  const int64_t slabs = std::min<int64_t>(s.nz, 4 * int64_t(omp_get_max_threads()));
  auto slab_begin = [&](int64_t p) { return s.nz * p / slabs; };
#pragma omp parallel for schedule(dynamic, 1)
  for (int64_t p = 0; p < slabs; ++p)
    for (int64_t k = slab_begin(p); k < slab_begin(p + 1); ++k)
      for (int64_t j = 0; j < ny; ++j) {
        if (j > 0) unite_with(k, j, k, j - 1);
        if (k > slab_begin(p))
          for (int64_t dj = -slack; dj <= slack; ++dj) unite_with(k, j, k - 1, j + dj);
      }
  for (int64_t p = 1; p < slabs; ++p)
    for (int64_t j = 0; j < ny; ++j)
      for (int64_t dj = -slack; dj <= slack; ++dj) unite_with(slab_begin(p), j, slab_begin(p) - 1, j + dj);
  // Component numbers in raster order of their first run (a root is its
  // component's first run: parent[p] <= p): the roots numbered in order
  // (per-chunk counts, then each chunk from its start), then every run
  // takes its root's number. In parallel: the serial loop, one dependent
  // load per run, was 15 ms of a 0.12 s stage at 256^3.
  const LargeArray<int64_t> comp = large_array<int64_t>(size_t(R));
  constexpr int64_t kChunks = 256;
  std::vector<int64_t> roots_before(size_t(kChunks) + 1, 0);
  auto chunk_begin = [&](int64_t c) { return R * c / kChunks; };
#pragma omp parallel for schedule(static)
  for (int64_t c = 0; c < kChunks; ++c) {
    int64_t n = 0;
    for (int64_t p = chunk_begin(c); p < chunk_begin(c + 1); ++p) n += parent[size_t(p)] == p;
    roots_before[size_t(c) + 1] = n;
  }
  for (int64_t c = 0; c < kChunks; ++c) roots_before[size_t(c) + 1] += roots_before[size_t(c)];
  const int64_t count = roots_before[size_t(kChunks)];
#pragma omp parallel for schedule(static)
  for (int64_t c = 0; c < kChunks; ++c) {
    int64_t next = roots_before[size_t(c)];
    for (int64_t p = chunk_begin(c); p < chunk_begin(c + 1); ++p)
      if (parent[size_t(p)] == p) comp[size_t(p)] = next++;
  }
#pragma omp parallel for schedule(static)
  for (int64_t p = 0; p < R; ++p) {
    int64_t r = p;
    while (parent[size_t(r)] != r) r = parent[size_t(r)];
    if (r != p) comp[size_t(p)] = comp[size_t(r)];
  }
  parent.reset();
  res.void_components = count;

  // Per component: voxels, and whether it reaches a face of the volume
  // that does not close it (border), or only faces that do (at_face).
  std::vector<int64_t> size(size_t(count), 0);
  std::vector<uint8_t> border(size_t(count), 0), at_face(size_t(count), 0);
  const auto& closed = opt.closed_faces;
  for (int64_t r = 0; r < rows; ++r) {
    const int64_t k = r / ny, j = r % ny;
    const bool face_row = k == 0 || k + 1 == s.nz || j == 0 || j + 1 == ny;
    for (int64_t p = first[size_t(r)]; p < first[size_t(r) + 1]; ++p) {
      const Run& u = run[size_t(p)];
      const int64_t c = comp[size_t(p)];
      size[size_t(c)] += u.b - u.a;
      if (!face_row && u.a != 0 && u.b != nx) continue;
      const bool on[6] = {k == 0, k + 1 == s.nz, j == 0, j + 1 == ny, u.a == 0, u.b == nx};
      for (size_t f = 0; f < 6; ++f)
        if (on[f]) (closed[f] ? at_face : border)[size_t(c)] = 1;
    }
  }
  // Solid faces of each run of an enclosed component: its two ends along
  // x, and along y and z its voxels less those next to void (which belongs
  // to the same component); a closed face of the volume counts as solid.
  // Per run in parallel, summed per component in run order.
  LargeArray<int64_t> run_faces = large_array<int64_t>(size_t(R));
#pragma omp parallel for schedule(static)
  for (int64_t r = 0; r < rows; ++r) {
    const int64_t k = r / ny, j = r % ny;
    for (int64_t p = first[size_t(r)]; p < first[size_t(r) + 1]; ++p) {
      run_faces[size_t(p)] = 0;
      if (border[size_t(comp[size_t(p)])]) continue;
      const Run& u = run[size_t(p)];
      int64_t f = 2;
      for (const auto& [kk, jj] : {std::pair{k, j - 1}, {k, j + 1}, {k - 1, j}, {k + 1, j}}) {
        int64_t open = 0;
        if (kk < 0 || kk >= s.nz || jj < 0 || jj >= ny) {  // beyond a closed face
          f += u.b - u.a;
          continue;
        }
        const auto [b1, e1] = row_runs(kk, jj);
        for_overlaps(b1, e1, u.a, u.b, [&](const Run& v) { open += std::min(u.b, v.b) - std::max(u.a, v.a); });
        f += (u.b - u.a) - open;
      }
      run_faces[size_t(p)] = f;
    }
  }
  std::vector<int64_t> faces(size_t(count), 0);
  for (int64_t p = 0; p < R; ++p) faces[size_t(comp[size_t(p)])] += run_faces[size_t(p)];
  run_faces.reset();

  std::vector<uint8_t> fill(size_t(count), 0);
  for (int64_t c = 0; c < count; ++c) {
    if (border[size_t(c)]) continue;
    ++res.enclosed;
    const int64_t v = size[size_t(c)];
    if (v <= opt.max_volume_vox && voxel_sphericity(v, faces[size_t(c)]) >= opt.min_sphericity) {
      fill[size_t(c)] = 1;
      ++res.filled;
      res.filled_voxels += v;
      res.filled_at_faces += at_face[size_t(c)];
    }
  }
  if (res.filled == 0) return res;
#pragma omp parallel for schedule(static)
  for (int64_t r = 0; r < rows; ++r)
    for (int64_t p = first[size_t(r)]; p < first[size_t(r) + 1]; ++p)
      if (fill[size_t(comp[size_t(p)])]) {
        const Run& u = run[size_t(p)];
        std::fill(m + r * nx + u.a, m + r * nx + u.b, fill_value);
      }
  return res;
}

int64_t brighten_pore_shells(Volume<uint8_t>& mask, uint8_t pore_value, uint8_t dim_value, uint8_t bright_value,
                             int steps) {
  const Shape S = mask.shape();
  const int64_t sl = S.ny * S.nx;
  uint8_t* m = mask.data();
  // The filled pores' voxels (slice by slice, in raster order), now bright.
  const int nt = omp_get_max_threads();
  std::vector<std::vector<int64_t>> part(static_cast<size_t>(nt));
#pragma omp parallel num_threads(nt)
  {
    auto& mine = part[size_t(omp_get_thread_num())];
#pragma omp for schedule(static)
    for (int64_t k = 0; k < S.nz; ++k)
      for (int64_t i = k * sl; i < (k + 1) * sl; ++i)
        if (m[i] == pore_value) {
          m[i] = bright_value;
          mine.push_back(i);
        }
  }
  std::vector<int64_t> front, next;
  for (const auto& p : part) front.insert(front.end(), p.begin(), p.end());
  // Layer by layer through the dim voxels (6-connected): the set reached is
  // that of the dim voxels within `steps` of a pore along dim voxels,
  // whatever the order within a layer.
  int64_t changed = 0;
  for (int t = 0; t < steps && !front.empty(); ++t) {
    next.clear();
    for (const int64_t i : front) {
      const int64_t z = i / sl, y = (i / S.nx) % S.ny, x = i % S.nx;
      auto visit = [&](bool inside, int64_t j) {
        if (inside && m[j] == dim_value) {
          m[j] = bright_value;
          next.push_back(j);
        }
      };
      visit(z > 0, i - sl), visit(z + 1 < S.nz, i + sl);
      visit(y > 0, i - S.nx), visit(y + 1 < S.ny, i + S.nx);
      visit(x > 0, i - 1), visit(x + 1 < S.nx, i + 1);
    }
    changed += int64_t(next.size());
    front.swap(next);
  }
  return changed;
}

}  // namespace tg
