// The two hot loops of a DEM step, written once for any lane width and
// compiled once per instruction set: SSE2 (2 lanes, every x86-64), AVX2 (4
// lanes) and AVX-512 (8 lanes), chosen at run time from what the CPU has.
//  * pair_part: the sphere–sphere contacts of one part of the pair list,
//    summed into the part's per-sphere array (see dem/engine.hpp);
//  * gather_block: for a block of spheres, the parts' sums, the sphere–wall
//    contacts (bottom and top platen, cylinder), local damping and the
//    closing half kick.
//
// Why lanes: the Hertz–Mindlin law is a chain of dependent square roots and
// divisions whose latency, not the arithmetic, bounds the loop; W contacts
// in the lanes of one register take W chains through each instruction. On
// the 2-core Xeon VM of bench/dem/RESULTS.md a restart from 8 % strain took
// 1.37 s with 2 lanes, 1.23 s with 4 and 1.0 s with 8 (session 7).
//
// Same bits with any kernel: lane arithmetic is IEEE double arithmetic lane
// by lane, the kernels' files are compiled without contraction into fused
// multiply-adds, every kernel takes a part's touching pairs in ascending
// order, and each sphere adds its parts, then its bottom, top and cylinder
// contacts, in that order. Tests run every kernel the CPU offers against the
// SSE2 one.
//
// The templates below live in an unnamed namespace, each lane type is
// instantiated in one file only, and the double helpers they use are
// always inlined (dem/vec3.hpp) or builtins: no inline function compiled
// for AVX-512 is shared with the SSE2 file, where the linker could keep
// either copy, even in an unoptimised build.
#pragma once
#include <cstdint>
#include <cstring>
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
// Rows (i) of the pair list in contiguous ranges, one a part, cut at
// multiples of kRowChunk (the engine chooses the cuts: dem/engine.hpp). A
// pair's part depends on its i and the cuts alone, never on the list.
// Contiguous, so that a part's rows are mostly the spheres its thread
// gathers and kicks: positions, velocities and sums stay in one core's
// cache, and part p's array holds non-zero sums only from its first row to
// its largest j, the only range it clears and the gather reads.
constexpr int64_t kRowChunk = 64;
// A part's spheres: its rows [lo, own_end), and [lo, hi) the spheres its
// sums may touch (hi past its largest j; the engine finds it at each
// rebuild, or takes n where it is unknown).
struct PartRange {
  int64_t lo, own_end, hi;
};

// What the contact loop reads and writes; the engine's arrays.
struct PairKernelArgs {
  const int64_t *pi, *pj, *offsets;  // pair (i, j), CSR row offsets
  int64_t rows, n;                   // rows of the list, spheres
  const double *x, *y, *z, *r, *vx, *vy, *vz, *wx, *wy, *wz, *m;
  double* xi;                 // tangential history, 3 per pair
  PairData* slot;             // written only when `keep` (null or empty otherwise)
  uint8_t *touching, *bad;    // per pair
  HertzMindlin law;
  double dt, overlap_limit, gravity_z;
  bool keep;
  int parts;
  const PartRange* range;  // per part: the spheres its sums may touch
};

// Part `part` of the pair list: fills acc (kAccStride doubles per sphere,
// 64-byte aligned) over the part's range with the weights (its own rows)
// or zeros (the j beyond them), then adds the part's contact forces and
// torques. Returns 1 if some pair overlapped beyond the limit or was not
// finite (its bad flag set). part = kAllParts: every part on this thread,
// in order, acc = part 0's array (the parts' arrays follow it, n spheres
// apart): the same sums in the same order as part by part.
using PairPartKernel = int (*)(const PairKernelArgs&, int part, double* acc);
constexpr int kAllParts = -1;

// Spheres per block of the gather (and of the kicks in the engine).
constexpr int64_t kSphereBlock = 64;

// What the gather reads and writes; the engine's arrays and walls.
struct GatherArgs {
  const double* acc;  // the parts' sums: part p, sphere s at (p n + s) kAccStride
  int parts;
  const PartRange* range;  // per part: the spheres whose sums it wrote
  double *x, *y, *z;
  const double *r, *m, *inv_m, *inv_i;
  double *vx, *vy, *vz, *wx, *wy, *wz;
  double *fx, *fy, *fz, *tx, *ty, *tz;
  double *hbx, *hby, *hbz, *htx, *hty, *htz, *hcx, *hcy, *hcz;  // wall histories
  const uint32_t* flags;
  uint32_t fixed_flag;  // spheres with this flag are not kicked
  double* wall_f;       // per sphere: force on bottom (z), top (z), cylinder (radial)
  // Per sphere: which of its wall histories and wall_f may be non-zero (bit
  // 1 bottom, 2 top, 4 cylinder; all clear: all zero), so that a sphere away
  // from the walls costs one byte a step, not 96 bytes of zeros written.
  uint8_t* wall_state;
  uint8_t* bad;         // per sphere: 1 overlap beyond the limit, 2 non-finite force
  HertzMindlin law_platen, law_cyl;
  bool bottom, top, cylinder;
  double top_z, top_vz, cylinder_radius;
  double dt, overlap_limit, local_damping;  // 0: no damping in the gather
  int64_t n;
  bool kick;   // end each sphere with the closing half kick
  bool drift;  // then the next step's opening half kick and drift, and its skin test:
  const double *x0, *y0, *z0;  // positions at the last rebuild (spheres below n_built)
  int64_t n_built;
  double skin_lim2;  // (skin/2)²
};

// Spheres [from, to), at most kSphereBlock of them: forces and torques into
// fx..tz, wall reactions into wall_f, histories updated, optionally kicked
// (and drifted). Returns bit 0: some sphere got a bad flag; bits 1-2 (with
// drift): 1 a sphere moved beyond skin/2 since the last rebuild, 3 a
// position is not finite.
using GatherKernel = int (*)(const GatherArgs&, int64_t from, int64_t to);

struct ContactKernels {
  PairPartKernel pairs = nullptr;
  GatherKernel gather = nullptr;
};

// PFC local non-viscous damping α of one force (or torque) component f of
// a body whose velocity (spin) component is v: α|f| against the motion.
// The gather's damping of the contact force and the engine's damping of the
// total force (EngineOptions::local_damping_total) both call this one;
// always inlined, as the kernels' other helpers (see the note above).
// Written without branches: velocity signs are random from sphere to sphere,
// and the branches' mispredictions made the engine's total-force damping 11 %
// of a breakage run's profile. Same bits as the branches: sign ±1 times
// α|f| is exact, and 0 (v = 0) takes nothing from f (not even a -0).
[[gnu::always_inline]] inline double local_damping(double f, double v, double alpha) {
  const double sign = static_cast<double>(v > 0) - static_cast<double>(v < 0);
  return f - sign * (alpha * __builtin_fabs(f));
}

enum class KernelIsa { kAuto, kSse2, kAvx2, kAvx512 };
// Whether this build has the kernels and this CPU can run them.
bool kernels_available(KernelIsa isa);
// kAuto: the widest available (or the one TOMOGRAIN_SIMD = sse2 | avx2 |
// avx512 names). Throws InputError for kernels that are not available.
ContactKernels contact_kernels(KernelIsa isa = KernelIsa::kAuto);
// "sse2 (2 lanes)" etc. for the run record.
std::string kernels_name(KernelIsa isa = KernelIsa::kAuto);

// The kernels, one set per file (kernels*.cpp).
ContactKernels kernels_sse2();
ContactKernels kernels_avx2();
ContactKernels kernels_avx512();

namespace {

// Listed pairs per block of the contact loop (see pair_part).
constexpr int64_t kPairBlock = 256;

// W 64-bit indices, one a lane (the type of a lane comparison).
template <class V>
using LaneIndex = decltype(V{} < V{});

// Adds W pairs' forces and torques to their spheres' sums, lane by lane in
// order (lanes `on` among the first `used`): -f and ti to sphere i, f and tj
// to sphere j.
template <class V, class M>
[[gnu::always_inline]] inline void add_pair_sums(double* __restrict acc, const int64_t* i, const int64_t* j, int used,
                                                 M on, const Vec3T<V>& f, const Vec3T<V>& ti, const Vec3T<V>& tj) {
  for (int l = 0; l < used; ++l) {
    if (!on[l]) continue;
    double *a = acc + kAccStride * i[l], *c = acc + kAccStride * j[l];
    a[0] -= f.x[l];
    a[1] -= f.y[l];
    a[2] -= f.z[l];
    a[3] += ti.x[l];
    a[4] += ti.y[l];
    a[5] += ti.z[l];
    c[0] += f.x[l];
    c[1] += f.y[l];
    c[2] += f.z[l];
    c[3] += tj.x[l];
    c[4] += tj.y[l];
    c[5] += tj.z[l];
  }
}

#if defined(__AVX512F__)
// On 8 lanes: the lanes' sums transposed into one 64-byte line a sphere
// (f, t, 0, 0: the accumulator's layout), each added to its sphere's line
// with one vector add, in lane order. a - f and a + (-f) are the same IEEE
// result, and the padding entries gain zeros: the same bits as above.
// (The generic shuffles of GCC >= 12 and Clang: the unpack and shuffle
// intrinsics start from an "undefined" vector that GCC 12 reports as maybe
// uninitialised.)
[[gnu::always_inline]] inline void transpose8(Lanes8 r[8]) {
#define TG_LO(a, b) __builtin_shufflevector(a, b, 0, 8, 2, 10, 4, 12, 6, 14)
#define TG_HI(a, b) __builtin_shufflevector(a, b, 1, 9, 3, 11, 5, 13, 7, 15)
#define TG_EVEN(a, b) __builtin_shufflevector(a, b, 0, 1, 4, 5, 8, 9, 12, 13)  // 128-bit chunks 0, 2 of a, then of b
#define TG_ODD(a, b) __builtin_shufflevector(a, b, 2, 3, 6, 7, 10, 11, 14, 15)  // chunks 1, 3
  Lanes8 t[8], u[8];
  for (int q = 0; q < 4; ++q) {
    t[2 * q] = TG_LO(r[2 * q], r[2 * q + 1]);
    t[2 * q + 1] = TG_HI(r[2 * q], r[2 * q + 1]);
  }
  for (int h = 0; h < 2; ++h) {  // rows 0-3, then 4-7
    u[4 * h] = TG_EVEN(t[4 * h], t[4 * h + 2]);          // columns 0, 4
    u[4 * h + 1] = TG_ODD(t[4 * h], t[4 * h + 2]);       // 2, 6
    u[4 * h + 2] = TG_EVEN(t[4 * h + 1], t[4 * h + 3]);  // 1, 5
    u[4 * h + 3] = TG_ODD(t[4 * h + 1], t[4 * h + 3]);   // 3, 7
  }
  r[0] = TG_EVEN(u[0], u[4]);
  r[4] = TG_ODD(u[0], u[4]);
  r[2] = TG_EVEN(u[1], u[5]);
  r[6] = TG_ODD(u[1], u[5]);
  r[1] = TG_EVEN(u[2], u[6]);
  r[5] = TG_ODD(u[2], u[6]);
  r[3] = TG_EVEN(u[3], u[7]);
  r[7] = TG_ODD(u[3], u[7]);
#undef TG_LO
#undef TG_HI
#undef TG_EVEN
#undef TG_ODD
}

[[gnu::always_inline]] inline void add_pair_sums(double* __restrict acc, const int64_t* i, const int64_t* j, int used,
                                                 Mask8 on, const Vec3T<Lanes8>& f, const Vec3T<Lanes8>& ti,
                                                 const Vec3T<Lanes8>& tj) {
  static_assert(kAccStride == 8);
  const Lanes8 zero{};
  Lanes8 ri[8] = {-f.x, -f.y, -f.z, ti.x, ti.y, ti.z, zero, zero};
  Lanes8 rj[8] = {f.x, f.y, f.z, tj.x, tj.y, tj.z, zero, zero};
  transpose8(ri);
  transpose8(rj);
  for (int l = 0; l < used; ++l) {
    if (!on[l]) continue;
    double *a = acc + kAccStride * i[l], *c = acc + kAccStride * j[l];
    _mm512_store_pd(a, _mm512_add_pd(_mm512_load_pd(a), __m512d(ri[l])));
    _mm512_store_pd(c, _mm512_add_pd(_mm512_load_pd(c), __m512d(rj[l])));
  }
}
#endif

// The body of every kernel; V is Lanes2, Lanes4 or Lanes8.
template <class V, class IV = LaneIndex<V>>
int pair_part(const PairKernelArgs& a, int part, double* acc_base) {
  static constexpr int W = sizeof(V) / sizeof(double);
  // Local, non-aliased views: the compiler keeps them in registers instead
  // of reloading them after every store into the pair arrays.
  const int64_t* __restrict pi = a.pi;
  const int64_t* __restrict pj = a.pj;
  const double *__restrict x = a.x, *__restrict y = a.y, *__restrict z = a.z, *__restrict r = a.r;
  const double *__restrict vx = a.vx, *__restrict vy = a.vy, *__restrict vz = a.vz;
  const double *__restrict wx = a.wx, *__restrict wy = a.wy, *__restrict wz = a.wz;
  const double* __restrict m = a.m;
  double* __restrict xi = a.xi;
  PairData* __restrict slot = a.slot;
  uint8_t* __restrict touching = a.touching;
  uint8_t* __restrict badk = a.bad;
  const HertzMindlin law = a.law;
  const double dt = a.dt, lim = a.overlap_limit;
  const bool keep = a.keep;
  double* __restrict acc = acc_base;  // the current chunk's part's sums

  // W listed pairs kk[0] < ... < kk[used-1]; lanes from `used` on repeat
  // the last pair and are dropped. A lane whose pair does not touch
  // computes on stand-in values and is dropped; that pair has its state
  // reset if it touched before. Results are written lane 0 first, so the
  // part's sums take its pairs in ascending order.
  const auto lanes = [&](const int64_t* kk, int used) __attribute__((always_inline)) {
    // kk holds W entries (the list is padded with its last pair).
    IV kv;
    std::memcpy(&kv, kk, sizeof kv);
    const IV iv = lane_gather(pi, kv), jv = lane_gather(pj, kv), k3 = 3 * kv;
    int64_t k[W], i[W], j[W];
    std::memcpy(k, &kv, sizeof k);
    std::memcpy(i, &iv, sizeof i);
    std::memcpy(j, &jv, sizeof j);
    const auto L = [](const double* __restrict v, IV u) __attribute__((always_inline)) { return lane_gather(v, u); };
    const auto H = [&](int c) __attribute__((always_inline)) { return lane_gather(xi + c, k3); };
    const Vec3T<V> d{L(x, jv) - L(x, iv), L(y, jv) - L(y, iv), L(z, jv) - L(z, iv)};
    const V ri = L(r, iv), rj = L(r, jv), rs = ri + rj;
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
        if (keep) slot[k[l]] = PairData{};  // slots exist only with a force hook
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
        if (keep) slot[k[l]] = PairData{};
        on[l] = 0;
        failed = 1;
      }
    }
    if (!any(on)) return failed;
    const Vec3T<V> nrm = (1.0 / dist) * d;
    const V ai = ri - 0.5 * delta, aj = rj - 0.5 * delta;
    const Vec3T<V> wi{L(wx, iv), L(wy, iv), L(wz, iv)}, wj{L(wx, jv), L(wy, jv), L(wz, jv)};
    const Vec3T<V> vci = Vec3T<V>{L(vx, iv), L(vy, iv), L(vz, iv)} + cross(wi, ai * nrm);
    const Vec3T<V> vcj = Vec3T<V>{L(vx, jv), L(vy, jv), L(vz, jv)} + cross(wj, -aj * nrm);
    // R* and m* from the spheres (as rebuild() once kept them per pair: the
    // same expressions, the same bits; 16 bytes a listed pair less to read).
    const V mi = L(m, iv), mj = L(m, jv);
    const ContactGeometryT<V> g{nrm, delta, ri * rj / rs, mi * mj / (mi + mj), vcj - vci};
    Vec3T<V> h{H(0), H(1), H(2)};
    const ContactForceT<V> cf = hertz_mindlin_force(law, g, dt, h);
    const Vec3T<V> nf = cross(nrm, cf.force_on_j);
    const Vec3T<V> ti = -ai * nf, tj = -aj * nf;
    // The touching lanes' pairs are distinct: their histories are stored in any order.
    lane_scatter(xi, k3, h.x, on);
    lane_scatter(xi + 1, k3, h.y, on);
    lane_scatter(xi + 2, k3, h.z, on);
    for (int l = 0; l < used; ++l) {
      if (!on[l]) continue;
      const int64_t kl = k[l];
      if (keep)
        slot[kl] = PairData{cf.force_on_j.x[l], cf.force_on_j.y[l], cf.force_on_j.z[l], ti.x[l], ti.y[l], ti.z[l],
                            tj.x[l], tj.y[l], tj.z[l]};
      touching[kl] = kTouching;
    }
    add_pair_sums(acc, i, j, used, on, cf.force_on_j, ti, tj);
    return failed;
  };

  // Pairs in blocks: a first, branch-free pass over a block lists the pairs
  // that touch (or touched, to be reset) in ascending order, and the lanes
  // are filled from that list, so few lanes carry a pair that does not
  // touch (session 5: a restart from 8 % strain on one thread, median
  // 1.31 -> 1.07 s).
  const auto block = [&](int64_t kb, int64_t ke) __attribute__((always_inline)) {
    int64_t listed[kPairBlock + 8];  // padded for up to 8 lanes
    int m = 0;
    int64_t k = kb;
    for (; k + W <= ke; k += W) {  // W pairs a time, then one a time
      IV iv, jv, kv, t;
      std::memcpy(&iv, pi + k, sizeof iv);
      std::memcpy(&jv, pj + k, sizeof jv);
      for (int l = 0; l < W; ++l) kv[l] = k + l, t[l] = touching[k + l];
      const V dx = lane_gather(x, jv) - lane_gather(x, iv), dy = lane_gather(y, jv) - lane_gather(y, iv);
      const V dz = lane_gather(z, jv) - lane_gather(z, iv), rs = lane_gather(r, iv) + lane_gather(r, jv);
      m += lane_compress(listed + m, kv, ~(dx * dx + dy * dy + dz * dz >= rs * rs) | (t != 0));
    }
    for (; k < ke; ++k) {
      const int64_t i = pi[k], j = pj[k];
      const double dx = x[j] - x[i], dy = y[j] - y[i], dz = z[j] - z[i], rs = r[i] + r[j];
      listed[m] = k;
      m += int(!(dx * dx + dy * dy + dz * dz >= rs * rs)) | int(touching[k] != 0);  // NaN: listed
    }
    for (int l = 0; l < W; ++l) listed[m + l] = listed[m > 0 ? m - 1 : 0];  // pad the last lanes
    int failed = 0;
    for (int q = 0; q < m; q += W) failed |= lanes(listed + q, m - q < W ? m - q : W);
    return failed;
  };

  const int64_t n = a.n;
  const bool all = part == kAllParts;
  int failed = 0;
  for (int q = all ? 0 : part; q <= (all ? a.parts - 1 : part); ++q) {
    acc = all ? acc_base + q * kAccStride * n : acc_base;
    const int64_t own_end = a.range[q].own_end;
    for (int64_t s = a.range[q].lo; s < a.range[q].hi; ++s) {
      double* c = acc + kAccStride * s;
      c[0] = c[1] = 0;
      c[2] = s < own_end ? a.m[s] * a.gravity_z : 0.0;  // each sphere's weight in the part of its row
      c[3] = c[4] = c[5] = c[6] = c[7] = 0;  // 6, 7: padding (the AVX-512 kernel adds whole lines)
    }
    const int64_t r0 = a.range[q].lo, r1 = own_end < a.rows ? own_end : a.rows;
    if (r0 >= r1) continue;
    const int64_t lo = a.offsets[r0], hi = a.offsets[r1];
    for (int64_t kb = lo; kb < hi; kb += kPairBlock) failed |= block(kb, hi - kb < kPairBlock ? hi : kb + kPairBlock);
  }
  return failed;
}

// The wall contacts of a block of spheres, in lists of one law each (the
// platens, the cylinder): what a contact needs, its history and its result.
struct WallList {
  static constexpr int kCap = 2 * kSphereBlock + 8;  // both platens, lanes padded
  int count = 0;
  int64_t s[kCap];
  double nx[kCap], ny[kCap], nz[kCap], delta[kCap], vz[kCap];  // normal into the wall, overlap, wall speed
  double hx[kCap], hy[kCap], hz[kCap];                          // tangential history in and out
  double fx[kCap], fy[kCap], fz[kCap], tx[kCap], ty[kCap], tz[kCap];  // force on the wall, torque on the sphere
  int add(int64_t sphere, double x, double y, double z, double d, double v, double a, double b, double c) {
    const int e = count++;
    s[e] = sphere, nx[e] = x, ny[e] = y, nz[e] = z, delta[e] = d, vz[e] = v, hx[e] = a, hy[e] = b, hz[e] = c;
    return e;
  }
};

template <class V, class IV = LaneIndex<V>>
void wall_lanes(const GatherArgs& a, const HertzMindlin& law, WallList& w) {
  static constexpr int W = sizeof(V) / sizeof(double);
  if (w.count == 0) return;
  const int used = w.count, count = (used + W - 1) / W * W;
  for (int e = used; e < count; ++e)  // pad the last lanes with the last contact
    w.add(w.s[used - 1], w.nx[used - 1], w.ny[used - 1], w.nz[used - 1], w.delta[used - 1], w.vz[used - 1],
          w.hx[used - 1], w.hy[used - 1], w.hz[used - 1]);
  const auto ld = [](const double* v) __attribute__((always_inline)) {
    V o;
    std::memcpy(&o, v, sizeof o);
    return o;
  };
  const auto st = [](double* v, V o) __attribute__((always_inline)) { std::memcpy(v, &o, sizeof o); };
  for (int q = 0; q < count; q += W) {
    IV sv;
    std::memcpy(&sv, w.s + q, sizeof sv);
    const Vec3T<V> n{ld(w.nx + q), ld(w.ny + q), ld(w.nz + q)};
    const V delta = ld(w.delta + q), r = lane_gather(a.r, sv);
    const V ai = r - 0.5 * delta;
    const Vec3T<V> v{lane_gather(a.vx, sv), lane_gather(a.vy, sv), lane_gather(a.vz, sv)};
    const Vec3T<V> om{lane_gather(a.wx, sv), lane_gather(a.wy, sv), lane_gather(a.wz, sv)};
    const Vec3T<V> vc = v + cross(om, ai * n);
    const V zero{};
    const Vec3T<V> vwall{zero, zero, ld(w.vz + q)};
    const ContactGeometryT<V> g{n, delta, r, lane_gather(a.m, sv), vwall - vc};
    Vec3T<V> h{ld(w.hx + q), ld(w.hy + q), ld(w.hz + q)};
    const ContactForceT<V> cf = hertz_mindlin_force(law, g, a.dt, h);
    const Vec3T<V> t = cross(ai * n, -cf.force_on_j);
    st(w.hx + q, h.x), st(w.hy + q, h.y), st(w.hz + q, h.z);
    st(w.fx + q, cf.force_on_j.x), st(w.fy + q, cf.force_on_j.y), st(w.fz + q, cf.force_on_j.z);
    st(w.tx + q, t.x), st(w.ty + q, t.y), st(w.tz + q, t.z);
  }
}

// What the gather's last pass does to one sphere (T = double) or to W of
// them (T = V) with one text: lane l of a V result is the double result.
[[gnu::always_inline]] inline double lane(double v, int) { return v; }
template <class V>
[[gnu::always_inline]] inline double lane(V v, int l) { return v[l]; }
// Lanes' mask from -1 / 0 entries (one sphere: a bool).
[[gnu::always_inline]] inline bool lane_mask_of(double, const int64_t* m) { return *m != 0; }
template <class V>
[[gnu::always_inline]] inline LaneIndex<V> lane_mask_of(V, const int64_t* m) {
  LaneIndex<V> o;
  std::memcpy(&o, m, sizeof o);
  return o;
}
[[gnu::always_inline]] inline bool any_not(bool m) { return !m; }
template <class M>
[[gnu::always_inline]] inline bool any_not(M m) { return any(~m); }
// local_damping() lane by lane: the same sign and the same |f| (the sign bit
// cleared, as fabs does), so the same bits.
[[gnu::always_inline]] inline double damp(double f, double v, double alpha) { return local_damping(f, v, alpha); }
template <class V>
[[gnu::always_inline]] inline V damp(V f, V v, double alpha) {
  const V one = V{} + 1.0, zero{};
  const V sign = select(v > zero, one, zero) - select(v < zero, one, zero);
  LaneIndex<V> bits;
  std::memcpy(&bits, &f, sizeof bits);
  bits &= INT64_MAX;
  V abs_f;
  std::memcpy(&abs_f, &bits, sizeof abs_f);
  return f - sign * (alpha * abs_f);
}

template <class V>
int gather_block(const GatherArgs& a, int64_t from, int64_t to) {
  const double lim = a.overlap_limit;
  const int64_t n = a.n;
  WallList platen, cyl;
  int eb[kSphereBlock], et[kSphereBlock], ec[kSphereBlock];  // each sphere's contacts (-1: none)
  // 1. Which spheres touch which wall; histories of the others forgotten.
  //    W spheres a time are tested for being near a wall or having been on
  //    one (most spheres of a specimen are neither); only such groups go
  //    through the per-sphere code below.
  static constexpr int W = sizeof(V) / sizeof(double);
  const auto near_a_wall = [&](int64_t s) __attribute__((always_inline)) {
    V r, z, x, y;
    std::memcpy(&r, a.r + s, sizeof r);
    std::memcpy(&z, a.z + s, sizeof z);
    std::memcpy(&x, a.x + s, sizeof x);
    std::memcpy(&y, a.y + s, sizeof y);
    const V inner = a.cylinder_radius - r, zero{};
    // All ones on every lane where the wall is there, zero where it is not.
    const LaneIndex<V> bottom = LaneIndex<V>{} - int64_t(a.bottom), top = LaneIndex<V>{} - int64_t(a.top);
    const LaneIndex<V> cylinder = LaneIndex<V>{} - int64_t(a.cylinder);
    // Not finite: near (the per-sphere code decides, as before).
    auto near = ~(r - z <= zero) & bottom;
    near |= ~(z + r - a.top_z <= zero) & top;
    near |= ~((inner > zero) & (x * x + y * y <= inner * inner)) & cylinder;
    uint8_t was[W];
    std::memcpy(was, a.wall_state + s, W);
    for (int l = 0; l < W; ++l) near[l] |= -int64_t(was[l] != 0);  // all ones: any() may read sign bits only
    return any(near);
  };
  for (int64_t s = from; s < to; ++s) {
    const int q = static_cast<int>(s - from);
    if ((q % W) == 0 && s + W <= to && !near_a_wall(s)) {
      for (int l = 0; l < W; ++l) eb[q + l] = et[q + l] = ec[q + l] = -1;
      s += W - 1;
      continue;
    }
    const double r = a.r[s];
    const double db = r - a.z[s];
    const uint8_t was = a.wall_state[s];
    eb[q] = et[q] = ec[q] = -1;
    if (a.bottom && db > 0) {
      if (db > lim * r) a.bad[s] = 1;
      eb[q] = platen.add(s, 0, 0, -1, db, 0, a.hbx[s], a.hby[s], a.hbz[s]);
    } else if (was & 1) {
      a.hbx[s] = a.hby[s] = a.hbz[s] = 0;
    }
    const double dtp = a.z[s] + r - a.top_z;
    if (a.top && dtp > 0) {
      if (dtp > lim * r) a.bad[s] = 1;
      et[q] = platen.add(s, 0, 0, 1, dtp, a.top_vz, a.htx[s], a.hty[s], a.htz[s]);
    } else if (was & 2) {
      a.htx[s] = a.hty[s] = a.htz[s] = 0;
    }
    // The square root only for spheres near the cylinder (rho > R - r).
    const double rho2 = a.x[s] * a.x[s] + a.y[s] * a.y[s], inner = a.cylinder_radius - r;
    const double rho = inner > 0 && rho2 <= inner * inner ? 0.0 : __builtin_sqrt(rho2);
    const double dc = rho + r - a.cylinder_radius;
    if (a.cylinder && dc > 0 && rho > 0) {
      if (dc > lim * r) a.bad[s] = 1;
      ec[q] = cyl.add(s, a.x[s] / rho, a.y[s] / rho, 0, dc, 0, a.hcx[s], a.hcy[s], a.hcz[s]);
    } else if (was & 4) {
      a.hcx[s] = a.hcy[s] = a.hcz[s] = 0;
    }
  }
  // 2. The wall contacts, W a time.
  wall_lanes<V>(a, a.law_platen, platen);
  wall_lanes<V>(a, a.law_cyl, cyl);
  // 3. Each sphere's force and torque: its parts, then its bottom, top and
  //    cylinder contacts, into the block's arrays (scalar: the parts' sums
  //    are 64 bytes apart, and few spheres touch a wall).
  alignas(64) double F[6][kSphereBlock];
  alignas(64) int64_t kickable[kSphereBlock];  // -1: kicked, 0: fixed (a lane mask)
  const uint32_t* __restrict flags = a.flags;
  uint8_t* __restrict wall_state = a.wall_state;
  double* __restrict wall_f = a.wall_f;
  for (int64_t s = from; s < to; ++s) {
    const int q = static_cast<int>(s - from);
    Vec3 f, t;
    for (int part = 0; part < a.parts; ++part) {
      if (s < a.range[part].lo || s >= a.range[part].hi) continue;  // no sums of this part
      const double* c = a.acc + (part * n + s) * kAccStride;
      f = f + Vec3{c[0], c[1], c[2]};
      t = t + Vec3{c[3], c[4], c[5]};
    }
    const uint8_t now = uint8_t((eb[q] >= 0) | (et[q] >= 0) << 1 | (ec[q] >= 0) << 2);
    if (now | wall_state[s]) {
      double fw[3] = {0, 0, 0};
      const auto apply = [&](const WallList& w, int e, int slot, bool radial) __attribute__((always_inline)) {
        if (e < 0) return;
        const Vec3 Fw{w.fx[e], w.fy[e], w.fz[e]};
        f = f - Fw;
        t = t + Vec3{w.tx[e], w.ty[e], w.tz[e]};
        fw[slot] = radial ? dot(Fw, Vec3{w.nx[e], w.ny[e], w.nz[e]}) : Fw.z;
      };
      apply(platen, eb[q], 0, false);
      apply(platen, et[q], 1, false);
      apply(cyl, ec[q], 2, true);
      if (eb[q] >= 0) a.hbx[s] = platen.hx[eb[q]], a.hby[s] = platen.hy[eb[q]], a.hbz[s] = platen.hz[eb[q]];
      if (et[q] >= 0) a.htx[s] = platen.hx[et[q]], a.hty[s] = platen.hy[et[q]], a.htz[s] = platen.hz[et[q]];
      if (ec[q] >= 0) a.hcx[s] = cyl.hx[ec[q]], a.hcy[s] = cyl.hy[ec[q]], a.hcz[s] = cyl.hz[ec[q]];
      wall_f[3 * s] = fw[0];
      wall_f[3 * s + 1] = fw[1];
      wall_f[3 * s + 2] = fw[2];
      wall_state[s] = now;
    }
    F[0][q] = f.x, F[1][q] = f.y, F[2][q] = f.z, F[3][q] = t.x, F[4][q] = t.y, F[5][q] = t.z;
    kickable[q] = (flags[s] & a.fixed_flag) ? 0 : -1;
  }
  // 4. Damping, the stores, the closing half kick and (drift) the next
  //    step's opening half kick, drift and skin test: W spheres a time (the
  //    last few one a time), each lane the scalar arithmetic of one sphere.
  //    Written per sphere as before, with a.vx etc. read through the
  //    argument struct, this was a third of a step on one thread: every
  //    byte store (wall state, bad flags) made the compiler reload the
  //    struct's fields.
  const double half = 0.5 * a.dt, dt = a.dt, alpha = a.local_damping, lim2 = a.skin_lim2;
  const bool kick = a.kick, drift = a.drift;
  const int64_t n_built = a.n_built;
  double *__restrict vx = a.vx, *__restrict vy = a.vy, *__restrict vz = a.vz;
  double *__restrict wx = a.wx, *__restrict wy = a.wy, *__restrict wz = a.wz;
  double *__restrict x = a.x, *__restrict y = a.y, *__restrict z = a.z;
  double *__restrict fx = a.fx, *__restrict fy = a.fy, *__restrict fz = a.fz;
  double *__restrict tx = a.tx, *__restrict ty = a.ty, *__restrict tz = a.tz;
  const double *__restrict inv_m = a.inv_m, *__restrict inv_i = a.inv_i;
  const double *__restrict x0 = a.x0, *__restrict y0 = a.y0, *__restrict z0 = a.z0;
  uint8_t* __restrict bad = a.bad;
  int moved = 0;
  // Spheres s .. s + width - 1 (q their first block index) as lanes of T
  // (V, or double for one sphere); `skin`: test them against the skin.
  const auto spheres = [&](auto lanes, int64_t s, int q, bool skin) __attribute__((always_inline)) {
    using T = decltype(lanes);
    const auto ld = [](const double* p) __attribute__((always_inline)) {
      T o;
      std::memcpy(&o, p, sizeof o);
      return o;
    };
    const auto st = [](double* p, T o) __attribute__((always_inline)) { std::memcpy(p, &o, sizeof o); };
    const T v[3] = {ld(vx + s), ld(vy + s), ld(vz + s)}, w[3] = {ld(wx + s), ld(wy + s), ld(wz + s)};
    T f[3] = {ld(F[0] + q), ld(F[1] + q), ld(F[2] + q)}, t[3] = {ld(F[3] + q), ld(F[4] + q), ld(F[5] + q)};
    if (alpha > 0)  // PFC local damping: oppose the velocity with α|F|
      for (int c = 0; c < 3; ++c) f[c] = damp(f[c], v[c], alpha), t[c] = damp(t[c], w[c], alpha);
    st(fx + s, f[0]), st(fy + s, f[1]), st(fz + s, f[2]);
    st(tx + s, t[0]), st(ty + s, t[1]), st(tz + s, t[2]);
    if (kick) {
      const auto on = lane_mask_of(lanes, kickable + q);
      const T hm = half * ld(inv_m + s), hi = half * ld(inv_i + s);
      T nv[3] = {v[0], v[1], v[2]}, nw[3] = {w[0], w[1], w[2]};
      for (int c = 0; c < 3; ++c) nv[c] += hm * f[c], nw[c] += hi * t[c];  // as the engine's closing half kick
      if (drift) {  // the next step's opening half kick and drift, as the engine's
        for (int c = 0; c < 3; ++c) nv[c] += hm * f[c], nw[c] += hi * t[c];
        st(x + s, select(on, ld(x + s) + dt * nv[0], ld(x + s)));
        st(y + s, select(on, ld(y + s) + dt * nv[1], ld(y + s)));
        st(z + s, select(on, ld(z + s) + dt * nv[2], ld(z + s)));
      }
      st(vx + s, select(on, nv[0], v[0])), st(vy + s, select(on, nv[1], v[1])), st(vz + s, select(on, nv[2], v[2]));
      st(wx + s, select(on, nw[0], w[0])), st(wy + s, select(on, nw[1], w[1])), st(wz + s, select(on, nw[2], w[2]));
    }
    if (skin) {
      const T dx = ld(x + s) - ld(x0 + s), dy = ld(y + s) - ld(y0 + s), dz = ld(z + s) - ld(z0 + s);
      const T d2 = dx * dx + dy * dy + dz * dz;
      if (any_not(d2 <= lim2))
        for (int l = 0; l < int(sizeof(T) / sizeof(double)); ++l)
          if (!(lane(d2, l) <= lim2)) moved |= __builtin_isfinite(lane(d2, l)) ? 1 : 3;
    }
    const T sum = f[0] + f[1] + f[2] + t[0] + t[1] + t[2];
    if (any_not(sum - sum == 0.0))  // not finite
      for (int l = 0; l < int(sizeof(T) / sizeof(double)); ++l)
        if (!__builtin_isfinite(lane(sum, l))) bad[s + l] = 2;
  };
  const int count = static_cast<int>(to - from);
  int q = 0;
  for (; q + W <= count; q += W) {
    const int64_t s = from + q;
    if (!drift || s + W <= n_built || s >= n_built) spheres(V{}, s, q, drift && s + W <= n_built);
    else
      for (int l = 0; l < W; ++l) spheres(0.0, s + l, q + l, s + l < n_built);
  }
  for (; q < count; ++q) spheres(0.0, from + q, q, drift && from + q < n_built);
  int any_bad = 0;
  for (int64_t s = from; s < to; ++s) any_bad |= int(bad[s] != 0);
  return any_bad | moved << 1;
}

template <class V>
ContactKernels kernels_for() {
  return {pair_part<V>, gather_block<V>};
}

}  // namespace
}  // namespace tg::dem
