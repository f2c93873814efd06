#include "segmentation/distance_transform.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "core/memory.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace tg {

namespace detail {

// Windows are used while their mean length is at most this many rows (see
// edt_block_window). Measured at 256^3, one thread, packed balls of radius
// 20/40/80/120 voxels: 64 -> 91/87/74/65 Mvox/s, 96 -> 91/95/88/74,
// 128 -> 85/95/87/73; envelopes only: 42/45/54/50.
constexpr int64_t kWindowBudget = 96;

void edt_line(const float* f, float* d, int64_t n, int64_t stride, double w, EnvelopeSite* st) {
  if (n <= 0) return;
  // Sites with f = +inf (a row without any void in the passes before) get
  // g = kBig instead of +inf: their intersections with finite sites come out
  // at about -+1e290 (pushed last, popped by the next finite site, never the
  // nearest while a finite site exists) and inf - inf = NaN never arises, so
  // the loop needs no isinf test. The output adds the stored f = +inf, so a
  // line of such sites only still gives +inf.
  constexpr double kBig = 1e290;
  const double w2 = w * w, inv_w2 = 1.0 / w2;

  // Writes d on positions [a, b) from the envelope st[0..k].
  auto emit = [&](int64_t a, int64_t b, int64_t k) {
    st[k + 1].zn = 1, st[k + 1].zd = 0;  // takes over at +inf
    int64_t j = 0;
    for (int64_t p = a; p < b; ++p) {
      const double x = double(p);
      while (st[j + 1].zn < x * st[j + 1].zd) ++j;
      const double dx = x - st[j].v;
      d[p * stride] = float(dx * dx * w2 + st[j].f);
    }
  };

  // Voxel units: with g(q) = f(q) / w^2 + q^2 the parabolas of v < q meet at
  // s = (g(q) - g(v)) / (2 (q - v)), one subtraction and one division per
  // push, and the test s > z is done without the division.
  //
  // Zeros (void voxels) cut the line into independent runs: for p between
  // two zeros q1 < p < q2, a site r outside [q1, q2] is never nearer than
  // the zero on its side ((p - r)^2 w^2 + f(r) >= (p - q1)^2 w^2). So at
  // each zero the positions since the last one are written from the
  // envelope, which then restarts with that zero alone: short envelopes,
  // and runs of zeros (about 40 % of a granular scan) cost one test each.
  const double f0 = f[0];
  st[0] = {0.0, std::min(f0 * inv_w2, kBig), f0, -1, 0};
  int64_t k = 0, start = 0;  // envelope st[0..k]; positions < start are written
  if (f0 == 0) d[0] = 0, start = 1;
  for (int64_t q = 1; q < n; ++q) {
    const double fq = f[q * stride], x = double(q);
    if (fq == 0 && start == q) {  // a zero right after a zero: nothing to write
      st[0] = {x, x * x, 0.0, -1, 0};
      k = 0, d[q * stride] = 0, start = q + 1;
      continue;
    }
    const double gq = std::min(fq * inv_w2 + x * x, kBig);
    double num, den;
    for (;;) {  // st[0] takes over at -inf, so k never drops below 0
      num = gq - st[k].g, den = 2.0 * (x - st[k].v);
      if (num * st[k].zd > st[k].zn * den) break;
      --k;
    }
    ++k;
    st[k] = {x, gq, fq, num, den};
    if (fq == 0) {
      emit(start, q, k);
      st[0] = {x, x * x, 0.0, -1, 0};
      k = 0, d[q * stride] = 0, start = q + 1;
    }
  }
  emit(start, n, k);
}

// Window bound: the nearest site q* of p satisfies (w (p - q*))^2 <= d[p]
// <= f[p], so it lies within r_p = floor(sqrt(m_p) / w) of p, m_p the
// largest f[p] of the block's row p. In a granular scan m_p is a few grain
// radii squared at most, and the minimum over the window is 16 lanes of
// add + min per window row, without branches; the envelope pays several
// data-dependent branches per sample. Where a window would be wide (rows
// without void: +inf; large grains) the envelopes win, so the block falls
// back to them when the windows' total length exceeds kWindowBudget rows
// per row (about where the two cost the same, measured).
bool edt_block_window(const float* in, float* out, int64_t n, int64_t stride, double w, int64_t* radius, float* cost) {
  int64_t total = 0;
  for (int64_t p = 0; p < n; ++p) {
    float m = 0;
    for (int64_t b = 0; b < kEdtBlock; ++b) m = std::max(m, in[p * stride + b]);
    // A little over the bound (1e-9) so that rounding never cuts a window short.
    const double r = std::sqrt(double(m)) / w * (1 + 1e-9);
    radius[p] = r < double(n) ? int64_t(r) : n;  // +inf: n
    total += std::min(p, radius[p]) + std::min(n - 1 - p, radius[p]) + 1;
  }
  if (total > kWindowBudget * n) return false;
  // cost[k] = (w k)^2, rounded once (the window loop then stays a plain
  // add + min; converting k in the loop cost 30 %).
  const int64_t rmax = std::min(n - 1, *std::max_element(radius, radius + n));
  for (int64_t k = 0; k <= rmax; ++k) cost[k] = float(w * w * double(k * k));
  for (int64_t p = 0; p < n; ++p) {
    float acc[kEdtBlock];
    for (int64_t b = 0; b < kEdtBlock; ++b) acc[b] = in[p * stride + b];
    const int64_t lo = std::max<int64_t>(0, p - radius[p]), hi = std::min(n - 1, p + radius[p]);
    for (int64_t q = lo; q <= hi; ++q) {
      const float c = cost[q > p ? q - p : p - q];
      const float* row = in + q * stride;
#pragma omp simd  // GCC vectorises the min only when told it may
      for (int64_t b = 0; b < kEdtBlock; ++b) acc[b] = std::min(acc[b], row[b] + c);
    }
    std::memcpy(out + p * stride, acc, sizeof acc);
  }
  return true;
}

}  // namespace detail

namespace {

constexpr int64_t kBlock = detail::kEdtBlock;  // columns solved together: 16 floats = one 64-byte cache line

// Pass x on one row: squared distance to the nearest void voxel of the row.
void row_x(const uint8_t* m, float* d, int64_t nx, double w2, uint8_t solid_from) {
  // Distances in voxels counted in float (exact up to 2^24; +inf + 1 stays
  // +inf when no void came yet), selects instead of branches.
  float run = std::numeric_limits<float>::infinity();
  for (int64_t i = 0; i < nx; ++i) d[i] = run = m[i] < solid_from ? 0.f : run + 1.f;
  run = std::numeric_limits<float>::infinity();
  for (int64_t i = nx - 1; i >= 0; --i) {
    run = m[i] < solid_from ? 0.f : run + 1.f;
    const double t = std::min(d[i], run);
    d[i] = float(t * t * w2);
  }
}

// dst[i] = sqrt(src[i]). GCC keeps std::sqrt scalar (it may set errno),
// and the scalar root was 10-15 % of the whole transform; SSE2's root is
// the same correctly rounded IEEE operation, four at a time.
void sqrt_row(const float* src, float* dst, int64_t n) {
  int64_t i = 0;
#if defined(__SSE2__)
  for (; i + 4 <= n; i += 4) _mm_storeu_ps(dst + i, _mm_sqrt_ps(_mm_loadu_ps(src + i)));
#endif
  for (; i < n; ++i) dst[i] = std::sqrt(src[i]);
}

// Passes y and z work on a slab: the n samples along the pass of all nx
// columns, as n rows of the volume copied whole (sequential reads; copying
// 64-byte pieces of rows a slice apart, as before, took as long as pass z's
// windows). The kernels take 16 columns at a time. Rows are padded to a
// multiple of 16 columns (zeros: void lines, ignored) plus one cache line,
// so that rows 2^k bytes apart do not all fall in the same cache sets.
struct Slab {
  int64_t n, nx, width;
  std::vector<float> in, out, cost;
  std::vector<int64_t> radius;
  std::vector<detail::EnvelopeSite> sites;
  Slab(int64_t n_, int64_t nx_)
      : n(n_), nx(nx_), width((nx_ + kBlock - 1) / kBlock * kBlock + kBlock),
        in(size_t(n * width)), out(size_t(n * width)), cost(size_t(n)), radius(size_t(n)), sites(size_t(n + 1)) {}
  float* row(int64_t p) { return in.data() + p * width; }

  // in -> out, block by block: windows, or envelopes where they would be wide.
  void solve(double w) {
    for (int64_t i0 = 0; i0 < nx; i0 += kBlock) {
      const float* f = in.data() + i0;
      float* d = out.data() + i0;
      if (detail::edt_block_window(f, d, n, width, w, radius.data(), cost.data())) continue;
      for (int64_t b = 0; b < std::min(kBlock, nx - i0); ++b) detail::edt_line(f + b, d + b, n, width, w, sites.data());
    }
  }

  // Results to n rows of the volume `step` floats apart; the last pass takes
  // the square root on the way, saving a sweep over the volume.
  void store(float* base, int64_t step, bool take_sqrt) const {
    for (int64_t p = 0; p < n; ++p) {
      const float* src = out.data() + p * width;
      float* dst = base + p * step;
      if (take_sqrt)
        sqrt_row(src, dst, nx);
      else
        std::memcpy(dst, src, size_t(nx) * sizeof(float));
    }
  }
};

void transform(const Volume<uint8_t>& solid, Volume<float>& out, const EdtOptions& opt, bool take_sqrt) {
  for (double w : opt.spacing)
    if (!(w > 0) || !std::isfinite(w))
      throw UsageError("distance transform: voxel spacing must be positive and finite (got " + std::to_string(w) + ")");
  if (opt.solid_from == 0) throw UsageError("distance transform: solid_from must be >= 1 (0 would leave no void)");
  const Shape s = solid.shape();
  if (out.shape() != s) out = Volume<float>(s, solid.geometry());
  out.set_geometry(solid.geometry());
  if (s.empty()) return;

  const int64_t nz = s.nz, ny = s.ny, nx = s.nx, sz = s.slice_voxels();
  // Passes x and y slice by slice: pass x writes the slab pass y reads (the
  // volume is written once for both).
  {
    const double wx2 = opt.spacing[2] * opt.spacing[2], wy = opt.spacing[1];
    const bool last = take_sqrt && nz == 1;
#pragma omp parallel
    {
      Slab slab(ny, nx);
#pragma omp for schedule(static)
      for (int64_t k = 0; k < nz; ++k) {
        for (int64_t j = 0; j < ny; ++j) row_x(solid.data() + k * sz + j * nx, slab.row(j), nx, wx2, opt.solid_from);
        slab.solve(wy);
        slab.store(out.data() + k * sz, nx, last);
      }
    }
  }
  // Pass z: for each y, the slab of rows (k, y, 0..nx) over all k.
  if (nz > 1) {
    const double wz = opt.spacing[0];
#pragma omp parallel
    {
      Slab slab(nz, nx);
#pragma omp for schedule(static)
      for (int64_t j = 0; j < ny; ++j) {
        for (int64_t k = 0; k < nz; ++k) std::memcpy(slab.row(k), out.data() + k * sz + j * nx, size_t(nx) * sizeof(float));
        slab.solve(wz);
        slab.store(out.data() + j * nx, sz, take_sqrt);
      }
    }
  }
}

}  // namespace

void squared_distance_transform(const Volume<uint8_t>& solid, Volume<float>& out, const EdtOptions& opt) {
  transform(solid, out, opt, false);
}

void distance_transform(const Volume<uint8_t>& solid, Volume<float>& out, const EdtOptions& opt) {
  transform(solid, out, opt, true);
}

float deepest_distance(const Volume<float>& dist, const std::string& who) {
  const int64_t n = dist.size();
  const float* d = dist.data();
  float dmax = 0;
  int bad = 0;  // bitwise, so that the loop vectorises
#pragma omp parallel for simd schedule(static) reduction(max : dmax) reduction(| : bad)
  for (int64_t i = 0; i < n; ++i) {
    const float v = d[i];
    bad |= int(!(v >= 0.0f)) | int(!(v <= std::numeric_limits<float>::max()));  // NaN, < 0, inf
    dmax = v > dmax ? v : dmax;
  }
  if (bad) throw UsageError(who + ": the distance map is not finite and >= 0 everywhere");
  return dmax;
}

double fixed_point_units(float dmax) {
  double u = 256.0;
  while (u > 1.0 && double(dmax) * u > 65535.0) u /= 2;
  return u;
}

FixedDistance to_fixed_point(Volume<float>&& dist, double per_unit) {
  if (!(per_unit >= 0) || !std::isfinite(per_unit)) throw UsageError("distance map: fixed-point units must be >= 0");
  const int64_t n = dist.size();
  const float dmax = deepest_distance(dist, "distance map");
  FixedDistance r;
  r.dmax = dmax;
  r.per_unit = per_unit > 0 ? per_unit : fixed_point_units(dmax);
  const float p = float(r.per_unit);
  r.map = std::move(dist).convert_in_place<uint16_t>([p](float v) -> uint16_t {
    const float f = v * p + 0.5f;
    const uint16_t u = uint16_t(f < 65535.0f ? f : 65535.0f);
    return v > 0 && u == 0 ? uint16_t(1) : u;  // the solid stays > 0
  });
  discard_pages(r.map.data() + n, size_t(n) * (sizeof(float) - sizeof(uint16_t)));
  return r;
}

}  // namespace tg
