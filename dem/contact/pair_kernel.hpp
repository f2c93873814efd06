// The sphere–sphere contact loop of one part of the pair list (see
// dem/engine.hpp), written once for any lane width and compiled once per
// instruction set: SSE2 (2 lanes, every x86-64), AVX2 (4 lanes) and
// AVX-512 (8 lanes), chosen at run time from what the CPU has.
//
// Why lanes: the Hertz–Mindlin law is a chain of dependent square roots and
// divisions whose latency, not the arithmetic, bounds the loop; W contacts
// in the lanes of one register take W chains through each instruction. On
// the 2-core Xeon VM of bench/dem/RESULTS.md a restart from 8 % strain took
// 1.37 s with 2 lanes, 1.23 s with 4 and 1.0 s with 8 (session 7).
//
// Same bits with any kernel: lane arithmetic is IEEE double arithmetic lane
// by lane, the kernels' files are compiled without contraction into fused
// multiply-adds, and every kernel takes a part's touching pairs in ascending
// order and sums them into the part's per-sphere array in that order.
// Tests run every kernel the CPU offers against the SSE2 one.
//
// The kernel template below lives in an unnamed namespace, so that each
// kernel's file has its own copy compiled for its own instruction set (no
// inline function shared between the files: the linker could otherwise
// keep an AVX-512 copy for the SSE2 caller).
#pragma once
#include <cstdint>
#include <string>

#include "dem/contact/hertz_mindlin.hpp"

namespace tg::dem {

// One pair slot: force on j (on i: the opposite) and the two torques.
struct PairData {
  double fx, fy, fz;     // force on j
  double tix, tiy, tiz;  // torque on i
  double tjx, tjy, tjz;  // torque on j
};

// Per-pair state flag: in contact this step, holding a history or a force
// without being known to touch (after a rebuild or a restart), or nothing
// stored (a separated pair costs one test).
enum : uint8_t { kNotTouching = 0, kTouching = 1, kHistoryOnly = 2 };

// A sphere's force and torque sums of one part (6 doubles) in a 64-byte
// line of its own.
constexpr int64_t kAccStride = 8;
// Rows (i) of the pair list in chunks of this many spheres, dealt out to
// the parts in turn: a pair's part depends on its i alone.
constexpr int64_t kRowChunk = 64;

// What the contact loop reads and writes; the engine's arrays.
struct PairKernelArgs {
  const int64_t *pi, *pj, *offsets;  // pair (i, j), CSR row offsets
  int64_t rows, n;                   // rows of the list, spheres
  const double *x, *y, *z, *r, *vx, *vy, *vz, *wx, *wy, *wz, *m;
  const double *reff, *meff;  // R*, m* per pair
  double* xi;                 // tangential history, 3 per pair
  PairData* slot;             // written only when `keep`
  uint8_t *touching, *bad;    // per pair
  HertzMindlin law;
  double dt, overlap_limit, gravity_z;
  bool keep;
  int parts;
};

// Part `part` of the pair list: fills acc (kAccStride doubles per sphere,
// 64-byte aligned) with the weights (part 0) or zeros, then adds the part's
// contact forces and torques. Returns 1 if some pair overlapped beyond the
// limit or was not finite (its bad flag set).
using PairPartKernel = int (*)(const PairKernelArgs&, int part, double* acc);

enum class PairKernelIsa { kAuto, kSse2, kAvx2, kAvx512 };
// Whether this build has the kernel and this CPU can run it.
bool pair_kernel_available(PairKernelIsa isa);
// kAuto: the widest available (or the one TOMOGRAIN_SIMD = sse2 | avx2 |
// avx512 names). Throws InputError for a kernel that is not available.
PairPartKernel pair_kernel(PairKernelIsa isa = PairKernelIsa::kAuto);
// "sse2 (2 lanes)" etc. for the run record.
std::string pair_kernel_name(PairKernelIsa isa = PairKernelIsa::kAuto);

// The kernels, one per file (pair_kernel*.cpp).
int pair_part_sse2(const PairKernelArgs&, int part, double* acc);
int pair_part_avx2(const PairKernelArgs&, int part, double* acc);
int pair_part_avx512(const PairKernelArgs&, int part, double* acc);

namespace {

// The body of every kernel; V is Lanes2, Lanes4 or Lanes8.
template <class V>
int pair_part(const PairKernelArgs& a, int part, double* __restrict acc) {
  static constexpr int W = sizeof(V) / sizeof(double);
  // Local, non-aliased views: the compiler keeps them in registers instead
  // of reloading them after every store into the pair arrays.
  const int64_t* __restrict pi = a.pi;
  const int64_t* __restrict pj = a.pj;
  const double *__restrict x = a.x, *__restrict y = a.y, *__restrict z = a.z, *__restrict r = a.r;
  const double *__restrict vx = a.vx, *__restrict vy = a.vy, *__restrict vz = a.vz;
  const double *__restrict wx = a.wx, *__restrict wy = a.wy, *__restrict wz = a.wz;
  const double *__restrict reff = a.reff, *__restrict meff = a.meff;
  double* __restrict xi = a.xi;
  PairData* __restrict slot = a.slot;
  uint8_t* __restrict touching = a.touching;
  uint8_t* __restrict badk = a.bad;
  const HertzMindlin law = a.law;
  const double dt = a.dt, lim = a.overlap_limit;
  const bool keep = a.keep;

  // W listed pairs kk[0] < ... < kk[used-1]; lanes from `used` on repeat
  // the last pair and are dropped. A lane whose pair does not touch
  // computes on stand-in values and is dropped; that pair has its state
  // reset if it touched before. Results are written lane 0 first, so the
  // part's sums take its pairs in ascending order.
  const auto lanes = [&](const int64_t* kk, int used) __attribute__((always_inline)) {
    int64_t k[W], i[W], j[W];
    for (int l = 0; l < W; ++l) {
      k[l] = kk[l < used ? l : used - 1];
      i[l] = pi[k[l]];
      j[l] = pj[k[l]];
    }
    const auto L = [](const double* __restrict v, const int64_t* u) __attribute__((always_inline)) {
      V o;
      for (int l = 0; l < W; ++l) o[l] = v[u[l]];
      return o;
    };
    const auto H = [&](int c) __attribute__((always_inline)) {
      V o;
      for (int l = 0; l < W; ++l) o[l] = xi[3 * k[l] + c];
      return o;
    };
    const Vec3T<V> d{L(x, j) - L(x, i), L(y, j) - L(y, i), L(z, j) - L(z, i)};
    const V ri = L(r, i), rj = L(r, j), rs = ri + rj;
    const V d2 = dot(d, d);
    // Touching, or not finite (caught below): !(d2 >= rs²).
    auto on = ~(d2 >= rs * rs);
    for (int l = used; l < W; ++l) on[l] = 0;
    for (int l = 0; l < used; ++l) {
      // Just separated (touching at the last step, or holding a history, as
      // after a restart or a rebuild): forget it. Most listed pairs never
      // touch, and are not written every step.
      if (!on[l] && touching[k[l]]) {
        touching[k[l]] = kNotTouching;
        xi[3 * k[l]] = xi[3 * k[l] + 1] = xi[3 * k[l] + 2] = 0;
        slot[k[l]] = PairData{};
      }
    }
    if (!any(on)) return 0;
    // Stand-ins for a lane that does not touch: a contact at rest, overlap
    // a thousandth of rs (no NaN, no denormal on the way).
    const V dist = select(on, lane_sqrt(d2), rs);
    const V delta = select(on, rs - dist, 1e-3 * rs);
    int failed = 0;
    for (int l = 0; l < used; ++l) {
      const double rmin = ri[l] < rj[l] ? ri[l] : rj[l];
      if (on[l] && (!(dist[l] > 0) || delta[l] > lim * rmin)) {
        badk[k[l]] = 1;
        touching[k[l]] = kNotTouching;
        slot[k[l]] = PairData{};
        on[l] = 0;
        failed = 1;
      }
    }
    if (!any(on)) return failed;
    const Vec3T<V> nrm = (1.0 / dist) * d;
    const V ai = ri - 0.5 * delta, aj = rj - 0.5 * delta;
    const Vec3T<V> wi{L(wx, i), L(wy, i), L(wz, i)}, wj{L(wx, j), L(wy, j), L(wz, j)};
    const Vec3T<V> vci = Vec3T<V>{L(vx, i), L(vy, i), L(vz, i)} + cross(wi, ai * nrm);
    const Vec3T<V> vcj = Vec3T<V>{L(vx, j), L(vy, j), L(vz, j)} + cross(wj, -aj * nrm);
    const ContactGeometryT<V> g{nrm, delta, L(reff, k), L(meff, k), vcj - vci};
    Vec3T<V> h{H(0), H(1), H(2)};
    const ContactForceT<V> cf = hertz_mindlin_force(law, g, dt, h);
    const Vec3T<V> nf = cross(nrm, cf.force_on_j);
    const Vec3T<V> ti = -ai * nf, tj = -aj * nf;
    for (int l = 0; l < used; ++l) {
      if (!on[l]) continue;
      const int64_t kl = k[l];
      const double fx = cf.force_on_j.x[l], fy = cf.force_on_j.y[l], fz = cf.force_on_j.z[l];
      xi[3 * kl] = h.x[l];
      xi[3 * kl + 1] = h.y[l];
      xi[3 * kl + 2] = h.z[l];
      if (keep) slot[kl] = PairData{fx, fy, fz, ti.x[l], ti.y[l], ti.z[l], tj.x[l], tj.y[l], tj.z[l]};
      touching[kl] = kTouching;
      double *ai_ = acc + kAccStride * i[l], *aj_ = acc + kAccStride * j[l];
      ai_[0] -= fx;
      ai_[1] -= fy;
      ai_[2] -= fz;
      ai_[3] += ti.x[l];
      ai_[4] += ti.y[l];
      ai_[5] += ti.z[l];
      aj_[0] += fx;
      aj_[1] += fy;
      aj_[2] += fz;
      aj_[3] += tj.x[l];
      aj_[4] += tj.y[l];
      aj_[5] += tj.z[l];
    }
    return failed;
  };

  // Pairs in blocks: a first, branch-free pass over a block lists the pairs
  // that touch (or touched, to be reset) in ascending order, and the lanes
  // are filled from that list, so few lanes carry a pair that does not
  // touch (session 5: a restart from 8 % strain on one thread, median
  // 1.31 -> 1.07 s).
  constexpr int64_t kBlock = 256;
  const auto block = [&](int64_t kb, int64_t ke) __attribute__((always_inline)) {
    int64_t listed[kBlock];
    int m = 0;
    for (int64_t k = kb; k < ke; ++k) {
      const int64_t i = pi[k], j = pj[k];
      const double dx = x[j] - x[i], dy = y[j] - y[i], dz = z[j] - z[i], rs = r[i] + r[j];
      listed[m] = k;
      m += int(!(dx * dx + dy * dy + dz * dz >= rs * rs)) | int(touching[k] != 0);  // NaN: listed
    }
    int failed = 0;
    for (int q = 0; q < m; q += W) failed |= lanes(listed + q, m - q < W ? m - q : W);
    return failed;
  };

  const int64_t n = a.n;
  for (int64_t s = 0; s < n; ++s) {
    double* c = acc + kAccStride * s;
    c[0] = c[1] = 0;
    c[2] = part == 0 ? a.m[s] * a.gravity_z : 0.0;
    c[3] = c[4] = c[5] = 0;
  }
  int failed = 0;
  for (int64_t c = part; c * kRowChunk < a.rows; c += a.parts) {
    const int64_t lo = a.offsets[c * kRowChunk];
    const int64_t hi = a.offsets[(c + 1) * kRowChunk < a.rows ? (c + 1) * kRowChunk : a.rows];
    for (int64_t kb = lo; kb < hi; kb += kBlock) failed |= block(kb, hi - kb < kBlock ? hi : kb + kBlock);
  }
  return failed;
}

}  // namespace
}  // namespace tg::dem
