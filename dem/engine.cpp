#include "dem/engine.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <omp.h>

#include "dem/time_step.hpp"

namespace tg::dem {

namespace {
inline double* align64(double* p) {
  return reinterpret_cast<double*>((reinterpret_cast<uintptr_t>(p) + 63) & ~uintptr_t(63));
}

// Runs body(i) for i in [0, n) and returns the OR of its results: on the
// OpenMP team when `par`, else as a plain loop. Entering a parallel region
// costs about 0.5 us even for a team of one (libgomp makes and frees a
// team), which was 3-4 % of a step of 910 spheres on one core. The bodies
// are marked always_inline: GCC left the gather's as a call per sphere,
// reloading every array (5 % of a step).
template <class Body>
int for_each_or(int64_t n, bool par, Body&& body) {
  int any = 0;
  if (par) {
#pragma omp parallel for schedule(static) reduction(| : any)
    for (int64_t i = 0; i < n; ++i) any |= body(i);
  } else {
    for (int64_t i = 0; i < n; ++i) any |= body(i);
  }
  return any;
}

void check_options(const EngineOptions& o) {
  auto need = [](bool ok, const std::string& what) {
    if (!ok) throw InputError("DEM options: " + what);
  };
  need(o.time_step > 0 && std::isfinite(o.time_step), "time step must be positive");
  need(o.skin >= 0 && std::isfinite(o.skin), "neighbour skin must be >= 0");
  need(o.local_damping >= 0 && o.local_damping < 1, "local damping must be in [0, 1)");
  need(o.overlap_limit > 0 && o.overlap_limit <= 1, "overlap limit must be in (0, 1]");
  need(std::isfinite(o.gravity_z), "gravity must be finite");
  need(o.walls.cylinder_radius > 0, "cylinder radius must be positive");
  need(o.walls.platen_friction >= 0 && o.walls.cylinder_friction >= 0, "wall friction must be >= 0");
}
}  // namespace

Engine::Engine(Particles p, const EngineOptions& opt) : p_(std::move(p)), opt_(opt) {
  check_options(opt_);
  law_pp_ = make_hertz_mindlin(opt_.material, opt_.material, opt_.friction, opt_.restitution);
  law_platen_ = make_hertz_mindlin(opt_.material, opt_.material, opt_.walls.platen_friction, opt_.restitution);
  law_cyl_ = make_hertz_mindlin(opt_.material, opt_.material, opt_.walls.cylinder_friction, opt_.restitution);
  kernels_ = contact_kernels(opt_.kernel_isa);
  for (int64_t i = 0; i < p_.size(); ++i)
    if (!(p_.r[i] > 0) || !(p_.m[i] > 0) || !(p_.inertia[i] > 0))
      throw InputError("DEM: sphere " + std::to_string(i) + " has a non-positive radius, mass or inertia");
  rebuild();
}

void Engine::rebuild() {
  const int64_t n = p_.size();
  PairListCSR fresh = build_pairs_grid(p_, opt_.skin);
  const int64_t np = fresh.pairs();
  std::vector<double> xi(3 * np, 0.0);
  std::vector<int64_t> pi(np);
  const int64_t old_n = static_cast<int64_t>(list_.offsets.size()) - 1;
  // Carry tangential histories over: both lists are sorted (i, then j).
#pragma omp parallel for schedule(static) if (n >= opt_.parallel_min_items)
  for (int64_t i = 0; i < n; ++i) {
    for (int64_t k = fresh.offsets[i]; k < fresh.offsets[i + 1]; ++k) {
      pi[k] = i;
      if (i >= old_n) continue;
      const auto b = list_.j.begin() + list_.offsets[i], e = list_.j.begin() + list_.offsets[i + 1];
      const auto it = std::lower_bound(b, e, fresh.j[k]);
      if (it != e && *it == fresh.j[k]) {
        const int64_t o = it - list_.j.begin();
        for (int c = 0; c < 3; ++c) xi[3 * k + c] = xi_[3 * o + c];
      }
    }
  }
  list_ = std::move(fresh);
  xi_ = std::move(xi);
  pi_ = std::move(pi);
  update_part_ranges();
  // Force slots only for a force hook (breakage reads them): 72 bytes a
  // pair, about a sixth of the engine's memory, unused without one.
  slot_.assign(force_hook_ ? np : 0, PairData{});
  touching_.assign(np, 0);
  for (int64_t k = 0; k < np; ++k)
    if (xi_[3 * k] != 0 || xi_[3 * k + 1] != 0 || xi_[3 * k + 2] != 0) touching_[k] = kHistoryOnly;
  bad_.assign(std::max(np, n), 0);
  wall_f_.assign(3 * n, 0.0);
  // Spheres whose wall histories are not all zero (restored, or kept over
  // the rebuild): their bits set, the gather clears the histories it ends.
  wall_state_.assign(n, 0);
  for (int64_t s = 0; s < n; ++s) {
    const Particles& p = p_;
    wall_state_[s] = uint8_t((p.hbx[s] != 0 || p.hby[s] != 0 || p.hbz[s] != 0) |
                             (p.htx[s] != 0 || p.hty[s] != 0 || p.htz[s] != 0) << 1 |
                             (p.hcx[s] != 0 || p.hcy[s] != 0 || p.hcz[s] != 0) << 2);
  }
  x0_ = p_.x;
  y0_ = p_.y;
  z0_ = p_.z;
  update_inverse_masses();
  force_rebuild_ = false;
  ++rebuilds_;
}

void Engine::reset_pair_history() { std::fill(xi_.begin(), xi_.end(), 0.0); }

std::vector<int64_t> Engine::remove_spheres(const std::vector<uint8_t>& remove) {
  const int64_t n = p_.size();
  if (static_cast<int64_t>(remove.size()) != n) throw std::logic_error("Engine::remove_spheres: mask size");
  std::vector<int64_t> map(n, -1);
  int64_t kept = 0;
  for (int64_t s = 0; s < n; ++s)
    if (!remove[s]) {
      if (s != kept) p_.copy_sphere(s, kept);  // every field of the declared list
      map[s] = kept++;
    }
  p_.resize(kept);
  // The current list in the new numbering (monotone map: i < j and the
  // ascending order within each row survive), so that rebuild() carries the
  // tangential histories over by (i, j) as usual.
  const int64_t old_n = static_cast<int64_t>(list_.offsets.size()) - 1;
  PairListCSR carried;
  carried.offsets.assign(kept + 1, 0);
  std::vector<double> xi;
  for (int64_t i = 0; i < std::min(old_n, n); ++i) {
    if (map[i] < 0) continue;
    for (int64_t k = list_.offsets[i]; k < list_.offsets[i + 1]; ++k) {
      const int64_t j = list_.j[k];
      if (j >= n || map[j] < 0) continue;
      carried.j.push_back(map[j]);
      for (int c = 0; c < 3; ++c) xi.push_back(xi_[3 * k + c]);
      ++carried.offsets[map[i] + 1];
    }
  }
  for (int64_t s = 0; s < kept; ++s) carried.offsets[s + 1] += carried.offsets[s];
  list_ = std::move(carried);
  xi_ = std::move(xi);
  rebuild();
  return map;
}

void Engine::update_part_ranges() {
  const int64_t n = p_.size();
  const int64_t rows = static_cast<int64_t>(list_.offsets.size()) - 1;
  const int64_t split = std::clamp<int64_t>(split_ < 0 ? n / 2 / kRowChunk * kRowChunk : split_, 0, n);
  const int64_t cut[kForceParts + 1] = {0, split, n};
  static_assert(kForceParts == 2);
  for (int q = 0; q < kForceParts; ++q) {
    // Rows ascend in j, so a row's last j is its largest; a list built for
    // another sphere count says nothing: every sphere may be touched.
    int64_t hi = rows == n ? cut[q + 1] : n;
    for (int64_t i = cut[q]; rows == n && i < cut[q + 1]; ++i)
      if (list_.offsets[i + 1] > list_.offsets[i]) hi = std::max(hi, list_.j[list_.offsets[i + 1] - 1] + 1);
    part_range_[q] = {cut[q], cut[q + 1], hi};
  }
  part_range_n_ = n;
}

void Engine::balance_parts() {
  // Row i weighs two per touching pair (the force chain) plus one (its
  // listed pairs' distance test and its sums): with these weights the two
  // parts' busy times came out 48/52 on the 1e4 oedometer of
  // bench/dem/scaling.sh (one per pair: 57/43; halves of the rows: 67/33).
  // The cut goes to the chunk boundary where the weight is half done. The
  // touching pairs are the same whatever the list holds, so the cut, and
  // the sums, do not depend on the skin or on when the list was rebuilt.
  const int64_t rows = static_cast<int64_t>(list_.offsets.size()) - 1;
  if (rows != p_.size()) return;
  std::vector<int64_t> weight(static_cast<size_t>((rows + kRowChunk - 1) / kRowChunk), 0);
  int64_t total = 0;
  for (int64_t i = 0; i < rows; ++i) {
    int64_t w = 1;
    for (int64_t k = list_.offsets[i]; k < list_.offsets[i + 1]; ++k) w += 2 * (touching_[k] == kTouching);
    weight[static_cast<size_t>(i / kRowChunk)] += w;
    total += w;
  }
  int64_t done = 0, chunk = 0;
  while (chunk < static_cast<int64_t>(weight.size()) && 2 * (done + weight[static_cast<size_t>(chunk)]) <= total)
    done += weight[static_cast<size_t>(chunk++)];
  const int64_t split = std::min(rows, chunk * kRowChunk);
  split_next_ = split;  // taken at the next step's start: this step's gather reads the ranges its pairs used
}

void Engine::set_part_split(int64_t split) {
  if (split < -1) throw InputError("DEM: part split must be >= -1");
  split_ = split_next_ = split;
  update_part_ranges();
}

bool Engine::parallel(int64_t items) const {
  return items >= opt_.parallel_min_items && omp_get_max_threads() > 1;
}

void Engine::update_inverse_masses() {
  const int64_t n = p_.size();
  inv_m_.resize(n);
  inv_i_.resize(n);
  for (int64_t s = 0; s < n; ++s) {
    inv_m_[s] = 1.0 / p_.m[s];
    inv_i_[s] = 1.0 / p_.inertia[s];
  }
}

void Engine::run(int64_t steps) {
  overlap_handed_ = false;
  for (int64_t s = 0; s < steps && !overlap_handed_; ++s) advance(s + 1 < steps);
}

void Engine::advance(bool fuse_next) {
  const int64_t n = p_.size();
  const double dt = opt_.time_step, half = 0.5 * dt;
  Particles& p = p_;
  // 1/m and 1/I are kept between steps (four divisions per sphere and step
  // cost 2 % of a run); edits to the spheres come with request_rebuild(),
  // which refreshes them before the next kick.
  const auto fresh_masses = [&] {
    if (force_rebuild_ || static_cast<int64_t>(inv_m_.size()) != p.size()) update_inverse_masses();
  };
  fresh_masses();
  // Velocity Verlet: half kick, drift, forces, half kick. Local,
  // non-aliased views of the arrays, as in the contact loop.
  // Skin criterion, checked as the spheres drift: a rebuild when one moved
  // more than skin/2 since the last build (or its position is not finite).
  // Spheres appended since the last build (breakage) have no x0_ entry: the
  // size test below rebuilds then; never read past x0_.
  const int64_t n_built = std::min<int64_t>(n, static_cast<int64_t>(x0_.size()));
  const double lim2 = 0.25 * opt_.skin * opt_.skin;
  // Returns, for the first kick, 1 if a sphere moved beyond the skin, 3 if
  // a position is not finite (an OR needs no ordered reduction).
  const auto half_kick = [&](int64_t from, int64_t to, bool drift) {
    const double *__restrict im = inv_m_.data(), *__restrict ii = inv_i_.data();
    const double *__restrict fx = p.fx.data(), *__restrict fy = p.fy.data(), *__restrict fz = p.fz.data();
    const double *__restrict tx = p.tx.data(), *__restrict ty = p.ty.data(), *__restrict tz = p.tz.data();
    double *__restrict vx = p.vx.data(), *__restrict vy = p.vy.data(), *__restrict vz = p.vz.data();
    double *__restrict wx = p.wx.data(), *__restrict wy = p.wy.data(), *__restrict wz = p.wz.data();
    double *__restrict x = p.x.data(), *__restrict y = p.y.data(), *__restrict z = p.z.data();
    const double *__restrict x0 = x0_.data(), *__restrict y0 = y0_.data(), *__restrict z0 = z0_.data();
    const uint32_t* __restrict flags = p.flags.data();
    int moved = 0;
    for (int64_t s = from; s < to; ++s) {
      if (!(flags[s] & kFlagFixed)) {
        const double hm = half * im[s], hi = half * ii[s];
        vx[s] += hm * fx[s];
        vy[s] += hm * fy[s];
        vz[s] += hm * fz[s];
        wx[s] += hi * tx[s];
        wy[s] += hi * ty[s];
        wz[s] += hi * tz[s];
        if (drift) {
          x[s] += dt * vx[s];
          y[s] += dt * vy[s];
          z[s] += dt * vz[s];
        }
      }
      if (drift && s < n_built) {
        const double dx = x[s] - x0[s], dy = y[s] - y0[s], dz = z[s] - z0[s];
        const double d2 = dx * dx + dy * dy + dz * dz;
        if (!(d2 <= lim2)) moved |= std::isfinite(d2) ? 1 : 3;
      }
    }
    return moved;
  };
  // Blocks of spheres per thread (static: the same spheres whatever the
  // team size; each sphere's update is independent anyway).
  const auto kick_all = [&](int64_t count, bool drift) {
    return for_each_or((count + kSphereBlock - 1) / kSphereBlock, parallel(count), [&](int64_t b) __attribute__((always_inline)) {
      return half_kick(b * kSphereBlock, std::min(count, (b + 1) * kSphereBlock), drift);
    });
  };
  // The previous step's gather may have made this step's opening kick and
  // drift already (fused, see run()).
  const int moved = drifted_ ? pending_moved_ : kick_all(n, true);
  drifted_ = false;
  opt_.walls.top_z += dt * opt_.walls.top_vz;
  if (force_rebuild_ || n != static_cast<int64_t>(x0_.size()) || moved) {
    if (moved & 2) explode("a sphere position became non-finite");
    rebuild();
  }

  // Without a force hook the gather ends each sphere with its closing half
  // kick (one pass over the spheres and one parallel region less a step);
  // the hook (breakage) may edit forces and spheres, so it is kicked after.
  const bool kick_in_gather = !force_hook_;
  // (Not with an overlap hook: run() may return after any step of it.)
  const bool fuse = kick_in_gather && fuse_next && !overlap_hook_;
  compute_forces(kick_in_gather, fuse);
  drifted_ = fuse;
  if (!kick_in_gather) {
    fresh_masses();
    kick_all(p.size(), false);
  }
  time_ += dt;
  ++steps_;
}

void Engine::compute_forces(bool kick, bool drift_next) {
  // The pair slots are read by the force hook's model only (breakage:
  // contact statistics); a scene without one does not write them.
  keep_slots_ = static_cast<bool>(force_hook_);
  compute_pair_forces();
  // With a hook (bonds) and damping of the total force, the gather leaves
  // the forces undamped and the damping follows the hook's additions.
  const bool damp_after = force_hook_ && opt_.local_damping_total && opt_.local_damping > 0;
  gather_forces(kick, drift_next, damp_after ? 0.0 : opt_.local_damping);
  if (force_hook_) force_hook_(*this);
  if (damp_after) damp_total_forces();
}

void Engine::damp_total_forces() {
  // The velocities are the half-step ones the gather's damping reads (the
  // closing kick comes after the hook); each sphere is independent.
  Particles& p = p_;
  const int64_t n = p.size();
  const double alpha = opt_.local_damping;
#pragma omp parallel for schedule(static) if (parallel(n))
  for (int64_t s = 0; s < n; ++s) {
    p.fx[s] = local_damping(p.fx[s], p.vx[s], alpha);
    p.fy[s] = local_damping(p.fy[s], p.vy[s], alpha);
    p.fz[s] = local_damping(p.fz[s], p.vz[s], alpha);
    p.tx[s] = local_damping(p.tx[s], p.wx[s], alpha);
    p.ty[s] = local_damping(p.ty[s], p.wy[s], alpha);
    p.tz[s] = local_damping(p.tz[s], p.wz[s], alpha);
  }
}

void Engine::set_time_step(double dt) {
  if (!(dt > 0) || !std::isfinite(dt)) throw InputError("DEM options: time step must be positive");
  opt_.time_step = dt;
}

// The contact loop: one pair, one slot; its body is the lane kernel of
// dem/contact/kernels.hpp. A bond law (issue 7) adds its force and
// torques into the same slot from the force hook.
void Engine::compute_pair_forces() {
  const int64_t np = list_.pairs();
  const int64_t n = p_.size();
  // Each part of the pair list sums its forces and torques into its own
  // per-sphere array (each sphere's weight in the part of its row); the
  // gather adds the parts in their order. A pair's part is fixed by its own
  // i and the cut between the parts (balance_parts), not by the list: the
  // sums then do not depend on which pairs that do not touch the list holds
  // (skin, rebuild times). The list only bounds the spheres a part clears
  // and the gather reads (part_range_), which skips exact zeros.
  acc_.resize(size_t(kForceParts) * kAccStride * size_t(n) + 8);
  double* const acc0 = align64(acc_.data());
  if (split_next_ != split_) split_ = split_next_, part_range_n_ = -1;  // balance_parts() moved the cut
  if (part_range_n_ != n) update_part_ranges();  // or spheres were added or removed since the last build
  const PairKernelArgs args{pi_.data(), list_.j.data(), list_.offsets.data(),
                            static_cast<int64_t>(list_.offsets.size()) - 1, n,
                            p_.x.data(), p_.y.data(), p_.z.data(), p_.r.data(),
                            p_.vx.data(), p_.vy.data(), p_.vz.data(),
                            p_.wx.data(), p_.wy.data(), p_.wz.data(), p_.m.data(),
                            xi_.data(), slot_.data(), touching_.data(), bad_.data(),
                            law_pp_, opt_.time_step, opt_.overlap_limit, opt_.gravity_z, keep_slots_, kForceParts,
                            part_range_.data()};
  const PairPartKernel kernel = kernels_.pairs;
  // One thread: the parts one after the other in one call (the same sums:
  // dem/contact/kernels.hpp, kAllParts).
  const int bad = parallel(np) ? for_each_or(kForceParts, true, [&](int64_t part) __attribute__((always_inline)) {
    return kernel(args, static_cast<int>(part), acc0 + part * kAccStride * n);
  }) : kernel(args, kAllParts, acc0);
  if (steps_ % kBalanceEvery == 0) balance_parts();
  const double lim = opt_.overlap_limit;
  const Particles& p = p_;
  if (bad) {
    for (int64_t k = 0; k < np; ++k)
      if (bad_[k]) {
        const int64_t i = pi_[k], j = list_.j[k];
        if (overlap_hook_ && overlap_hook_(i, j)) {
          overlap_handed_ = true;
          bad_[k] = 0;  // the gather reads the same flags per sphere
          continue;
        }
        const double dist = std::sqrt(std::pow(p.x[j] - p.x[i], 2) + std::pow(p.y[j] - p.y[i], 2) + std::pow(p.z[j] - p.z[i], 2));
        std::ostringstream os;
        os << "spheres " << i << " (r = " << p.r[i] << " m) and " << j << " (r = " << p.r[j] << " m) overlap by "
           << (p.r[i] + p.r[j] - dist) / std::min(p.r[i], p.r[j]) << " of the smaller radius (limit " << lim << ")";
        explode(os.str());
      }
  }
}

// The gather's body is the lane kernel of dem/contact/kernels.hpp: per
// block of spheres, the parts' sums, then the wall contacts W a time, then
// damping and (kick) the closing half kick.
void Engine::gather_forces(bool kick, bool drift_next, double alpha) {
  const int64_t n = p_.size();
  Particles& p = p_;
  const Walls& w = opt_.walls;
  const int64_t n_built = std::min<int64_t>(n, static_cast<int64_t>(x0_.size()));
  const GatherArgs args{align64(acc_.data()), kForceParts, part_range_.data(),
                        p.x.data(), p.y.data(), p.z.data(), p.r.data(), p.m.data(), inv_m_.data(), inv_i_.data(),
                        p.vx.data(), p.vy.data(), p.vz.data(), p.wx.data(), p.wy.data(), p.wz.data(),
                        p.fx.data(), p.fy.data(), p.fz.data(), p.tx.data(), p.ty.data(), p.tz.data(),
                        p.hbx.data(), p.hby.data(), p.hbz.data(), p.htx.data(), p.hty.data(), p.htz.data(),
                        p.hcx.data(), p.hcy.data(), p.hcz.data(),
                        p.flags.data(), kFlagFixed, wall_f_.data(), wall_state_.data(), bad_.data(),
                        law_platen_, law_cyl_, w.bottom, w.top, w.cylinder, w.top_z, w.top_vz, w.cylinder_radius,
                        opt_.time_step, opt_.overlap_limit, alpha, n, kick,
                        drift_next, x0_.data(), y0_.data(), z0_.data(), n_built, 0.25 * opt_.skin * opt_.skin};
  const GatherKernel gather = kernels_.gather;
  const auto blocks = [&](int64_t from, int64_t to) __attribute__((always_inline)) {
    int f = 0;
    for (int64_t s = from; s < to; s += kSphereBlock) f |= gather(args, s, std::min(to, s + kSphereBlock));
    return f;
  };
  int flags = 0;
  if (parallel(n) && omp_get_max_threads() == kForceParts) {
    // A team of as many threads as parts (two cores): each thread gathers
    // the spheres of its part's rows, whose pairs it has just summed, so
    // their sums, positions and velocities stay in its cache. (Halves of
    // the spheres left the thread of the loaded half of the specimen a
    // third more spheres to gather than its partner on the 10^4 bench
    // oedometer: 11 % of the samples against 7 %.) The cut is a multiple of
    // kSphereBlock (kRowChunk), so the blocks are the same as below.
    static_assert(kRowChunk % kSphereBlock == 0);
#pragma omp parallel num_threads(kForceParts) reduction(| : flags)
    {
      const PartRange& r = part_range_[size_t(omp_get_thread_num())];
      flags |= blocks(r.lo, r.own_end);
    }
  } else {
    // The kicks' blocks of spheres (kSphereBlock), so that each thread
    // gathers the spheres it kicks: fewer of them change hands between the
    // threads.
    flags = for_each_or((n + kSphereBlock - 1) / kSphereBlock, parallel(n), [&](int64_t b) __attribute__((always_inline)) {
      return gather(args, b * kSphereBlock, std::min(n, (b + 1) * kSphereBlock));
    });
  }
  pending_moved_ = flags >> 1;
  if (flags & 1) {
    for (int64_t s = 0; s < n; ++s)
      if (bad_[s]) {
        if (bad_[s] == 1 && overlap_hook_ && overlap_hook_(s, -1)) {
          overlap_handed_ = true;
          bad_[s] = 0;
          continue;
        }
        std::ostringstream os;
        os << "sphere " << s << " (r = " << p.r[s] << " m, at z = " << p.z[s] << " m)"
           << (bad_[s] == 2 ? " has a non-finite force" : " overlaps a wall by more than the limit");
        explode(os.str());
      }
  }
  // Serial, fixed order: the wall reactions do not depend on threads. The
  // spheres off the walls add exact zeros (the sum, from +0, is unchanged).
  WallForces sum;
  for (int64_t s = 0; s < n; ++s) {
    if (!wall_state_[s]) continue;
    sum.bottom_z += wall_f_[3 * s];
    sum.top_z += wall_f_[3 * s + 1];
    sum.cylinder_radial += wall_f_[3 * s + 2];
  }
  wf_ = sum;
}

void Engine::explode(const std::string& what) const {
  std::ostringstream os;
  os << "DEM simulation became unstable at step " << steps_ << " (t = " << time_ << " s): " << what
     << "; time step " << opt_.time_step << " s";
  try {
    const CriticalTimeStep c = critical_time_step(p_, opt_.material, {});
    os << " vs critical " << c.dt_critical << " s (" << opt_.time_step / c.dt_critical << "x)";
  } catch (const std::exception&) {
  }
  os << " — reduce the time step or check the packing for overlaps";
  throw SimulationError(os.str());
}

double Engine::kinetic_energy() const {
  double e = 0;
  for (int64_t s = 0; s < p_.size(); ++s)
    e += 0.5 * p_.m[s] * (p_.vx[s] * p_.vx[s] + p_.vy[s] * p_.vy[s] + p_.vz[s] * p_.vz[s]) +
         0.5 * p_.inertia[s] * (p_.wx[s] * p_.wx[s] + p_.wy[s] * p_.wy[s] + p_.wz[s] * p_.wz[s]);
  return e;
}

double Engine::potential_energy() const {
  double e = 0;
  for (int64_t s = 0; s < p_.size(); ++s) e -= p_.m[s] * opt_.gravity_z * p_.z[s];
  return e;
}

double Engine::elastic_energy() const {
  const Particles& p = p_;
  double e = 0;
  for (int64_t k = 0; k < list_.pairs(); ++k) {
    const int64_t i = pi_[k], j = list_.j[k];
    const double dist = std::sqrt(std::pow(p.x[j] - p.x[i], 2) + std::pow(p.y[j] - p.y[i], 2) + std::pow(p.z[j] - p.z[i], 2));
    const double delta = p.r[i] + p.r[j] - dist;
    if (delta > 0) e += law_pp_.elastic_energy(delta, p.r[i] * p.r[j] / (p.r[i] + p.r[j]));
  }
  const Walls& w = opt_.walls;
  for (int64_t s = 0; s < p.size(); ++s) {
    const double r = p.r[s];
    if (w.bottom && r - p.z[s] > 0) e += law_platen_.elastic_energy(r - p.z[s], r);
    if (w.top && p.z[s] + r - w.top_z > 0) e += law_platen_.elastic_energy(p.z[s] + r - w.top_z, r);
    const double dc = std::hypot(p.x[s], p.y[s]) + r - w.cylinder_radius;
    if (w.cylinder && dc > 0) e += law_cyl_.elastic_energy(dc, r);
  }
  return e;
}

int64_t Engine::contact_count() const {
  int64_t c = 0;
  for (uint8_t t : touching_) c += t == kTouching;
  return c;
}

double Engine::coordination_number() const {
  return p_.size() > 0 ? 2.0 * static_cast<double>(contact_count()) / static_cast<double>(p_.size()) : 0.0;
}

Engine::PairHistory Engine::pair_history() const {
  PairHistory h;
  for (int64_t k = 0; k < list_.pairs(); ++k) {
    if (xi_[3 * k] == 0 && xi_[3 * k + 1] == 0 && xi_[3 * k + 2] == 0) continue;
    h.i.push_back(pi_[k]);
    h.j.push_back(list_.j[k]);
    for (int c = 0; c < 3; ++c) h.xi.push_back(xi_[3 * k + c]);
  }
  return h;
}

void Engine::restore(double time, int64_t steps, const PairHistory& h) {
  time_ = time;
  steps_ = steps;
  reset_pair_history();
  for (size_t q = 0; q < h.i.size(); ++q) {
    const int64_t i = h.i[q];
    if (i < 0 || i >= p_.size()) throw InputError("checkpoint: contact history names sphere " + std::to_string(i) + " out of range");
    const auto b = list_.j.begin() + list_.offsets[i], e = list_.j.begin() + list_.offsets[i + 1];
    const auto it = std::lower_bound(b, e, h.j[q]);
    if (it == e || *it != h.j[q])
      throw InputError("checkpoint: contact " + std::to_string(i) + "-" + std::to_string(h.j[q]) + " is not a neighbour pair");
    const int64_t k = it - list_.j.begin();
    for (int c = 0; c < 3; ++c) xi_[3 * k + c] = h.xi[3 * q + c];
    touching_[k] = kHistoryOnly;
  }
}

}  // namespace tg::dem
