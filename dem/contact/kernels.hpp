// The two hot loops of a DEM step, written once for any lane width and
// compiled once per instruction set: SSE2 (2 lanes, every x86-64), AVX2 (4
// lanes) and AVX-512 (8 lanes), chosen at run time from what the CPU has.
//  * pair_range: the sphere–sphere contacts of a range of the pair list,
//    each touching pair's force and torques into its slot (PairData);
//  * gather_block: for a block of spheres, the sums of their pairs' slots
//    (see "Sums" below), the sphere–wall contacts (bottom and top platen,
//    cylinder), local damping and the closing half kick.
//
// Sums: each sphere's contact force and torque are the sums of kForceParts
// parts, added in part order, part 0 starting from the weight; a pair
// belongs to the part of its row i (rows in chunks of kRowChunk spheres,
// dealt to the parts in turn) and each part takes its pairs in ascending
// pair order. The gather pulls them per sphere from the slots: first the
// pairs where the sphere is j (rows below it, by the transposed list, in
// ascending order), then its own row. Every sum has the same operands in
// the same order whichever thread computed which pair, so the contact loop
// and the gather split the lists into contiguous ranges, one a thread
// (session 14: the parts were summed by pushing into a per-part array of
// 64 bytes a sphere, each part on its own thread, so that a sphere's sums
// were written by both cores and read by one; the order, hence the bits,
// are those of that scheme).
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

// The parts of each sphere's sums (see "Sums" above). Rows (i) of the pair
// list in chunks of kRowChunk spheres, dealt out to the parts in turn: a
// pair's part depends on its i alone, not on the list or the threads.
constexpr int kForceParts = 2;
constexpr int64_t kRowChunk = 64;
[[gnu::always_inline]] inline int row_part(int64_t i) { return static_cast<int>((i / kRowChunk) % kForceParts); }

// What the contact loop reads and writes; the engine's arrays.
struct PairKernelArgs {
  const int64_t *pi, *pj;  // pair (i, j)
  const double *x, *y, *z, *r, *vx, *vy, *vz, *wx, *wy, *wz;
  const double *reff, *meff;  // R*, m* per pair
  double* xi;                 // tangential history, 3 per pair
  PairData* slot;             // per pair: written when it touches, zeroed when it separates
  uint8_t *touching, *bad;    // per pair
  HertzMindlin law;
  double dt, overlap_limit;
};

// Pairs [kb, ke) of the list: each touching pair's force and torques into
// its slot, touching[k] = kTouching exactly for the pairs whose slot the
// gather is to add. Returns 1 if some pair overlapped beyond the limit or
// was not finite (its bad flag set). Pairs are independent: any split of
// the list among threads gives the same slots.
using PairRangeKernel = int (*)(const PairKernelArgs&, int64_t kb, int64_t ke);

// Spheres per block of the gather (and of the kicks in the engine).
constexpr int64_t kSphereBlock = 64;

// What the gather reads and writes; the engine's arrays and walls.
struct GatherArgs {
  // The pairs' results and the two ways into them: each sphere's row of the
  // list (offsets), and the pairs where it is j, by part (rev: pair indices,
  // ascending within each; sphere s's of part p from rev_offsets[s
  // kForceParts + p]), so that each part's sums stay in registers.
  const PairData* slot;
  const uint8_t* touching;
  const int64_t *offsets, *rev_offsets, *rev;
  double gravity_z;  // the weight starts part 0's sums
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
  PairRangeKernel pairs = nullptr;
  GatherKernel gather = nullptr;
};

// PFC local non-viscous damping α of one force (or torque) component f of
// a body whose velocity (spin) component is v: α|f| against the motion.
// The gather's damping of the contact force and the engine's damping of the
// total force (EngineOptions::local_damping_total) both call this one;
// always inlined, as the kernels' other helpers (see the note above).
[[gnu::always_inline]] inline double local_damping(double f, double v, double alpha) {
  return v > 0 ? f - alpha * __builtin_fabs(f) : v < 0 ? f + alpha * __builtin_fabs(f) : f;
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

// The body of every kernel; V is Lanes2, Lanes4 or Lanes8.
template <class V, class IV = LaneIndex<V>>
int pair_range(const PairKernelArgs& a, int64_t first, int64_t end) {
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

  // W listed pairs kk[0] < ... < kk[used-1]; lanes from `used` on repeat
  // the last pair and are dropped. A lane whose pair does not touch
  // computes on stand-in values and is dropped; that pair has its state
  // reset if it touched before.
  const auto lanes = [&](const int64_t* kk, int used) __attribute__((always_inline)) {
    // kk holds W entries (the list is padded with its last pair).
    IV kv;
    std::memcpy(&kv, kk, sizeof kv);
    const IV iv = lane_gather(pi, kv), jv = lane_gather(pj, kv), k3 = 3 * kv;
    int64_t k[W];
    std::memcpy(k, &kv, sizeof k);
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
    const Vec3T<V> wi{L(wx, iv), L(wy, iv), L(wz, iv)}, wj{L(wx, jv), L(wy, jv), L(wz, jv)};
    const Vec3T<V> vci = Vec3T<V>{L(vx, iv), L(vy, iv), L(vz, iv)} + cross(wi, ai * nrm);
    const Vec3T<V> vcj = Vec3T<V>{L(vx, jv), L(vy, jv), L(vz, jv)} + cross(wj, -aj * nrm);
    const ContactGeometryT<V> g{nrm, delta, L(reff, kv), L(meff, kv), vcj - vci};
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
      slot[kl] = PairData{cf.force_on_j.x[l], cf.force_on_j.y[l], cf.force_on_j.z[l], ti.x[l], ti.y[l], ti.z[l],
                          tj.x[l], tj.y[l], tj.z[l]};
      touching[kl] = kTouching;
    }
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

  int failed = 0;
  for (int64_t kb = first; kb < end; kb += kPairBlock) failed |= block(kb, end - kb < kPairBlock ? end : kb + kPairBlock);
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

template <class V>
int gather_block(const GatherArgs& a, int64_t from, int64_t to) {
  const double lim = a.overlap_limit;
  WallList platen, cyl;
  int eb[kSphereBlock], et[kSphereBlock], ec[kSphereBlock];  // each sphere's contacts (-1: none)
  // 1. Which spheres touch which wall; histories of the others forgotten.
  for (int64_t s = from; s < to; ++s) {
    const int q = static_cast<int>(s - from);
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
  // 3. Each sphere: its parts (the pairs where it is j, then its row), then
  // its bottom, top and cylinder contacts.
  const double half = 0.5 * a.dt, alpha = a.local_damping;
  const PairData* __restrict slot = a.slot;
  const uint8_t* __restrict touching = a.touching;
  int any_bad = 0, moved = 0;
  for (int64_t s = from; s < to; ++s) {
    const int q = static_cast<int>(s - from);
    const int own = row_part(s);
    Vec3 f, t;
    for (int part = 0; part < kForceParts; ++part) {
      Vec3 fp{0.0, 0.0, part == 0 ? a.m[s] * a.gravity_z : 0.0}, tp;
      for (int64_t e = a.rev_offsets[s * kForceParts + part]; e < a.rev_offsets[s * kForceParts + part + 1]; ++e) {
        const int64_t k = a.rev[e];
        if (touching[k] != kTouching) continue;
        const PairData& d = slot[k];
        fp = fp + Vec3{d.fx, d.fy, d.fz};
        tp = tp + Vec3{d.tjx, d.tjy, d.tjz};
      }
      if (part == own)
        for (int64_t k = a.offsets[s]; k < a.offsets[s + 1]; ++k) {
          if (touching[k] != kTouching) continue;
          const PairData& d = slot[k];
          fp = fp - Vec3{d.fx, d.fy, d.fz};
          tp = tp + Vec3{d.tix, d.tiy, d.tiz};
        }
      f = f + fp;
      t = t + tp;
    }
    double fw[3] = {0, 0, 0};
    const auto apply = [&](const WallList& w, int e, int slot, bool radial) __attribute__((always_inline)) {
      if (e < 0) return;
      const Vec3 F{w.fx[e], w.fy[e], w.fz[e]};
      f = f - F;
      t = t + Vec3{w.tx[e], w.ty[e], w.tz[e]};
      fw[slot] = radial ? dot(F, Vec3{w.nx[e], w.ny[e], w.nz[e]}) : F.z;
    };
    apply(platen, eb[q], 0, false);
    apply(platen, et[q], 1, false);
    apply(cyl, ec[q], 2, true);
    if (eb[q] >= 0) a.hbx[s] = platen.hx[eb[q]], a.hby[s] = platen.hy[eb[q]], a.hbz[s] = platen.hz[eb[q]];
    if (et[q] >= 0) a.htx[s] = platen.hx[et[q]], a.hty[s] = platen.hy[et[q]], a.htz[s] = platen.hz[et[q]];
    if (ec[q] >= 0) a.hcx[s] = cyl.hx[ec[q]], a.hcy[s] = cyl.hy[ec[q]], a.hcz[s] = cyl.hz[ec[q]];
    const uint8_t now = uint8_t((eb[q] >= 0) | (et[q] >= 0) << 1 | (ec[q] >= 0) << 2);
    if (now | a.wall_state[s]) {
      a.wall_f[3 * s] = fw[0];
      a.wall_f[3 * s + 1] = fw[1];
      a.wall_f[3 * s + 2] = fw[2];
      a.wall_state[s] = now;
    }
    if (alpha > 0) {  // PFC local damping: oppose the velocity with α|F|
      f = {local_damping(f.x, a.vx[s], alpha), local_damping(f.y, a.vy[s], alpha), local_damping(f.z, a.vz[s], alpha)};
      t = {local_damping(t.x, a.wx[s], alpha), local_damping(t.y, a.wy[s], alpha), local_damping(t.z, a.wz[s], alpha)};
    }
    a.fx[s] = f.x, a.fy[s] = f.y, a.fz[s] = f.z;
    a.tx[s] = t.x, a.ty[s] = t.y, a.tz[s] = t.z;
    if (a.kick && !(a.flags[s] & a.fixed_flag)) {
      const double hm = half * a.inv_m[s], hi = half * a.inv_i[s];
      const auto half_kick = [&] __attribute__((always_inline)) {
        a.vx[s] += hm * f.x;
        a.vy[s] += hm * f.y;
        a.vz[s] += hm * f.z;
        a.wx[s] += hi * t.x;
        a.wy[s] += hi * t.y;
        a.wz[s] += hi * t.z;
      };
      half_kick();  // as the engine's closing half kick
      if (a.drift) {  // the next step's opening half kick and drift, as the engine's
        half_kick();
        a.x[s] += a.dt * a.vx[s];
        a.y[s] += a.dt * a.vy[s];
        a.z[s] += a.dt * a.vz[s];
      }
    }
    if (a.drift && s < a.n_built) {
      const double dx = a.x[s] - a.x0[s], dy = a.y[s] - a.y0[s], dz = a.z[s] - a.z0[s];
      const double d2 = dx * dx + dy * dy + dz * dz;
      if (!(d2 <= a.skin_lim2)) moved |= __builtin_isfinite(d2) ? 1 : 3;
    }
    if (!__builtin_isfinite(f.x + f.y + f.z + t.x + t.y + t.z)) a.bad[s] = 2;
    any_bad |= int(a.bad[s] != 0);
  }
  return any_bad | moved << 1;
}

template <class V>
ContactKernels kernels_for() {
  return {pair_range<V>, gather_block<V>};
}

}  // namespace
}  // namespace tg::dem
