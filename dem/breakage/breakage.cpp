#include "dem/breakage/breakage.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <numeric>
#include <sstream>
#include <string>

#include "core/errors.hpp"
#include "dem/breakage/replacement.hpp"
#include "dem/time_step.hpp"

namespace tg::dem::breakage {
namespace {
Vec3 pos(const Particles& p, int64_t s) { return {p.x[s], p.y[s], p.z[s]}; }
Vec3 vel(const Particles& p, int64_t s) { return {p.vx[s], p.vy[s], p.vz[s]}; }
Vec3 spin(const Particles& p, int64_t s) { return {p.wx[s], p.wy[s], p.wz[s]}; }
}  // namespace

BreakageModel::BreakageModel(Engine& engine, const BreakageOptions& opt) : eng_(engine), opt_(opt) {
  validate(opt_.strength);
  validate(opt_.bond);
  if (opt_.check_interval < 1) throw InputError("breakage: check interval must be >= 1 step");
  if (!(opt_.min_split_diameter_m >= 0)) throw InputError("breakage: minimum split diameter must be >= 0");
  if (!(opt_.time_step_safety > 0 && opt_.time_step_safety <= 1)) throw InputError("breakage: time step safety must be in (0, 1]");
  if (!(opt_.min_time_step_s >= 0) || !std::isfinite(opt_.min_time_step_s))
    throw InputError("breakage: minimum time step must be >= 0 (0 = no density scaling)");
  if (!(opt_.fines_overlap > 0 && opt_.fines_overlap < 1)) throw InputError("breakage: fines overlap must be in (0, 1)");
  law_ = make_hertz_mindlin(eng_.options().material, eng_.options().material, 0.0, 1.0);
  const Particles& p = eng_.particles();
  const int64_t n = p.size();
  for_each_sphere_field([&](auto& v) { v.resize(n); });
  std::fill(generation_.begin(), generation_.end(), 0);
  std::fill(mass_factor_.begin(), mass_factor_.end(), 1.0);
  for (int64_t s = 0; s < n; ++s) {
    key_[s] = static_cast<uint64_t>(s);
    strength_[s] = sphere_strength(opt_.strength, key_[s], 2 * p.r[s]);
  }
  rec_.spheres = n;
  rec_.particles = n;
  eng_.set_force_hook([this](Engine& e) { add_bond_forces(e); });
  eng_.set_overlap_hook([this](int64_t i, int64_t j) { return take_squeezed(i, j); });
}

bool BreakageModel::take_squeezed(int64_t i, int64_t j) {
  // The rule of check(): a sub-limit sphere squeezed past fines_overlap × r
  // is fines, unless the policy keeps every sphere. Past the engine's limit
  // it is that by far; check() runs after this step (check_due) and removes it.
  if (opt_.sublimit == SublimitPolicy::kKeep) return false;
  const Particles& p = eng_.particles();
  const double overlap = j < 0 ? wall_overlap(i) : p.r[i] + p.r[j] - norm(pos(p, j) - pos(p, i));
  bool fines = false;
  for (const int64_t s : {i, j})
    if (s >= 0 && (p.flags[s] & kFlagBreakable) && 2 * p.r[s] < opt_.min_split_diameter_m &&
        overlap > opt_.fines_overlap * p.r[s]) {
      // Named here: a pair past the limit gets no contact (the engine skips
      // it), so check()'s own overlap pass would not see it.
      squeezed_.push_back(s);
      fines = true;
    }
  return fines;
}

void BreakageModel::add_bond_forces(Engine& e) {
  const int64_t nb = static_cast<int64_t>(ba_.size());
  if (nb == 0) return;
  Particles& p = e.particles();
  const double dt = e.options().time_step;
  const bool dashpots = opt_.bond.damping_ratio > 0;
  loads_.resize(nb);
  int any_broken = 0;
  // Each bond writes only its own slots: thread-independent.
#pragma omp parallel for schedule(static) reduction(| : any_broken) if (nb >= 4096)
  for (int64_t b = 0; b < nb; ++b) {
    const int64_t i = ba_[b], j = bb_[b];
    const Vec3 xa = pos(p, i), xb = pos(p, j);
    const Vec3 d = xb - xa;
    const Vec3 n = (1 / norm(d)) * d;
    const Vec3 c = bond_point(xa, p.r[i], xb, p.r[j]);
    const Vec3 wa = spin(p, i), wb = spin(p, j);
    const Vec3 v_rel = (vel(p, j) + cross(wb, c - xb)) - (vel(p, i) + cross(wa, c - xa));
    const BondKinematics kin{n, v_rel, wb - wa};
    update_bond(section_[b], kin, dt, state_[b]);
    if (bond_breaks(opt_.bond, section_[b], state_[b])) {
      broken_[b] = 1;
      any_broken = 1;
      loads_[b] = BondLoads{};
    } else if (dashpots) {
      const Vec3 dash = bond_dashpot_force(opt_.bond, section_[b], kin, p.m[i] * p.m[j] / (p.m[i] + p.m[j]));
      loads_[b] = bond_loads(state_[b], n, xa, xb, c, &dash);
    } else {
      loads_[b] = bond_loads(state_[b], n, xa, xb, c);
    }
  }
  // Serial scatter in bond order: the sums do not depend on threads.
  for (int64_t b = 0; b < nb; ++b) {
    const int64_t i = ba_[b], j = bb_[b];
    const BondLoads& l = loads_[b];
    p.fx[i] -= l.force_on_b.x;
    p.fy[i] -= l.force_on_b.y;
    p.fz[i] -= l.force_on_b.z;
    p.fx[j] += l.force_on_b.x;
    p.fy[j] += l.force_on_b.y;
    p.fz[j] += l.force_on_b.z;
    p.tx[i] += l.torque_on_a.x;
    p.ty[i] += l.torque_on_a.y;
    p.tz[i] += l.torque_on_a.z;
    p.tx[j] += l.torque_on_b.x;
    p.ty[j] += l.torque_on_b.y;
    p.tz[j] += l.torque_on_b.z;
  }
  if (any_broken) compact_bonds(&rec_.bonds_broken, true);
}

void BreakageModel::drop_bonds_of(const std::vector<uint8_t>& marked) {
  bool dropped = false;
  for (size_t b = 0; b < ba_.size(); ++b)
    if (marked[ba_[b]] || marked[bb_[b]]) {
      broken_[b] = 1;
      dropped = true;
    }
  if (dropped) compact_bonds(&rec_.bonds_dropped);
}

void BreakageModel::compact_bonds(int64_t* counter, bool log) {
  int64_t w = 0;
  const int64_t nb = static_cast<int64_t>(ba_.size());
  const Particles& p = eng_.particles();
  for (int64_t b = 0; b < nb; ++b) {
    if (broken_[b]) {
      ++*counter;
      if (log) {  // in the force hook: the step being made is step_count() + 1
        BondBreak r;
        r.step = eng_.step_count() + 1;
        r.time_s = eng_.time() + eng_.options().time_step;
        r.born_step = born_step_[b];
        r.age_steps = born_step_[b] >= 0 ? r.step - born_step_[b] : -1;
        r.age_s = born_step_[b] >= 0 ? r.time_s - born_time_[b] : -1.0;
        r.generation = std::max(generation_[ba_[b]], generation_[bb_[b]]);
        r.radius_a_m = p.r[ba_[b]];
        r.radius_b_m = p.r[bb_[b]];
        const BondStress st = bond_stress(section_[b], state_[b]);
        r.tensile = st.sigma_max / opt_.bond.tensile_strength_Pa >= st.tau_max / opt_.bond.shear_strength_Pa;
        bond_breaks_.push_back(r);
      }
      continue;
    }
    for_each_bond_field([&](auto& v) { v[w] = v[b]; });  // broken_[b] is 0 here
    ++w;
  }
  for_each_bond_field([&](auto& v) { v.resize(w); });
  bonds_changed_ = true;
}

std::vector<double> BreakageModel::max_normal_forces() const {
  const Particles& p = eng_.particles();
  std::vector<double> f(p.size(), 0.0);
  for (int64_t k = 0; k < eng_.pair_count(); ++k) {
    if (!eng_.pair_touching(k)) continue;
    const int64_t i = eng_.pair_i(k), j = eng_.pair_j(k);
    const Vec3 d = pos(p, j) - pos(p, i);
    const PairData& pd = eng_.pair_force(k);
    const double fn = dot(Vec3{pd.fx, pd.fy, pd.fz}, d) / norm(d);  // > 0: pushes apart
    f[i] = std::max(f[i], fn);
    f[j] = std::max(f[j], fn);
  }
  for (int64_t s = 0; s < p.size(); ++s) {
    const double* w = eng_.sphere_wall_forces(s);
    f[s] = std::max({f[s], -w[0], w[1], w[2]});
  }
  return f;
}

std::vector<std::vector<ContactLoad>> BreakageModel::contact_loads(const std::vector<int64_t>& spheres) const {
  // One pass over the pair list for all the spheres (a pass per sphere made
  // a check with k candidates cost k x pairs: quadratic in N once the number
  // of simultaneous splits grows with the specimen). Each sphere's contacts
  // keep the order of the single-sphere scan: pairs by ascending index, then
  // bottom platen, top platen, cylinder.
  const Particles& p = eng_.particles();
  std::vector<std::vector<ContactLoad>> out(spheres.size());
  if (spheres.empty()) return out;
  std::vector<int64_t> which(static_cast<size_t>(p.size()), -1);
  for (size_t q = 0; q < spheres.size(); ++q) which[spheres[q]] = static_cast<int64_t>(q);
  for (int64_t k = 0; k < eng_.pair_count(); ++k) {
    if (!eng_.pair_touching(k)) continue;
    const int64_t i = eng_.pair_i(k), j = eng_.pair_j(k);
    if (which[i] < 0 && which[j] < 0) continue;
    const Vec3 d = pos(p, j) - pos(p, i);
    const double dist = norm(d);
    const Vec3 n = (1 / dist) * d;
    const double delta = p.r[i] + p.r[j] - dist;
    const Vec3 point = pos(p, i) + (p.r[i] - 0.5 * delta) * n;
    const PairData& pd = eng_.pair_force(k);
    const Vec3 f{pd.fx, pd.fy, pd.fz};
    if (which[i] >= 0) out[which[i]].push_back({point, -f});
    if (which[j] >= 0) out[which[j]].push_back({point, f});
  }
  for (size_t q = 0; q < spheres.size(); ++q) {
    const int64_t s = spheres[q];
    std::vector<ContactLoad>& c = out[q];
    const Vec3 xs = pos(p, s);
    const double* w = eng_.sphere_wall_forces(s);
    const double r = p.r[s];
    if (w[0] != 0) c.push_back({xs - Vec3{0, 0, r}, {0, 0, -w[0]}});
    if (w[1] != 0) c.push_back({xs + Vec3{0, 0, r}, {0, 0, -w[1]}});
    if (w[2] != 0) {
      const double rho = std::hypot(xs.x, xs.y);
      const Vec3 nc{xs.x / rho, xs.y / rho, 0};
      c.push_back({xs + r * nc, -w[2] * nc});
    }
  }
  return out;
}

int BreakageModel::check() {
  Particles& p = eng_.particles();
  const int64_t n = p.size();
  const std::vector<double> fmax = max_normal_forces();
  // Collect every split first: planes are computed from the state of the
  // check, before any sphere is replaced.
  std::vector<SplitEvent> todo;
  std::vector<int64_t> fines;
  fines.swap(squeezed_);  // past the engine's overlap limit since the last check (take_squeezed)
  // remove: squeezed sub-limit spheres and deep-born fragment spheres are
  // fines; remove_over: so are sub-limit spheres over their strength.
  const bool remove = opt_.sublimit != SublimitPolicy::kKeep;
  const bool remove_over = opt_.sublimit == SublimitPolicy::kRemove;
  std::vector<double> overlap;
  if (remove || !opt_.split_bonded) overlap = max_overlap_ratios();
  std::vector<uint8_t> bonded;  // split_bonded = false: spheres with an intact bond
  if (!opt_.split_bonded) {
    bonded.assign(n, 0);
    for (size_t b = 0; b < ba_.size(); ++b) bonded[ba_[b]] = bonded[bb_[b]] = 1;
  }
  std::vector<int64_t> over_strength;  // spheres over their strength that may split
  for (int64_t s = 0; s < n; ++s) {
    const double d = 2 * p.r[s];
    if (!(p.flags[s] & kFlagBreakable)) continue;
    const bool over = fmax[s] > 0 && fmax[s] / (d * d) > strength_[s];
    if (d < opt_.min_split_diameter_m) {
      // Sub-limit: it would break into pieces below the resolution, or it is
      // being pushed through a neighbour its Hertz stiffness cannot resist.
      if (remove && ((remove_over && over) || overlap[s] > opt_.fines_overlap)) fines.push_back(s);
      continue;
    }
    // split_bonded = false: a bonded sphere splits only once squeezed past
    // fines_overlap × r (its bonds cannot hold it off: breakage.hpp).
    if (!over || (!opt_.split_bonded && bonded[s] && overlap[s] <= opt_.fines_overlap)) continue;
    over_strength.push_back(s);
  }
  const std::vector<std::vector<ContactLoad>> loads = contact_loads(over_strength);
  for (size_t q = 0; q < over_strength.size(); ++q) {
    const int64_t s = over_strength[q];
    const double d = 2 * p.r[s];
    const double sigma = fmax[s] / (d * d);
    const double volume = std::numbers::pi / 6 * d * d * d;
    const auto plane = splitting_plane(pos(p, s), volume, loads[q]);
    if (!plane) continue;
    SplitEvent ev;
    ev.step = eng_.step_count();
    ev.time_s = eng_.time();
    ev.position = pos(p, s);
    ev.sphere = s;
    ev.generation = generation_[s];
    ev.diameter_m = d;
    ev.f_max_N = fmax[s];
    ev.stress_Pa = sigma;
    ev.strength_Pa = strength_[s];
    ev.plane = *plane;
    todo.push_back(ev);
  }
  // The mothers' bonds go with them: one pass over the bonds for all splits
  // (a pass per split was splits x bonds). New fragment bonds only join a
  // mother's own index to appended spheres, never another mother, so the
  // bond list ends as dropping per split would leave it.
  if (!todo.empty()) {
    std::vector<uint8_t> mother(static_cast<size_t>(n), 0);
    for (const SplitEvent& ev : todo) mother[ev.sphere] = 1;
    drop_bonds_of(mother);
  }
  // Spheres touching each mother (before any split): the only ones a
  // fragment sphere can overlap, since it lies inside its mother (with the
  // fragments of a neighbour split earlier in this check, added below).
  std::vector<std::vector<int64_t>> near(todo.size());
  std::vector<int64_t> first_new_of;  // mother index -> her first appended sphere (this check)
  if (!todo.empty()) {
    first_new_of.assign(static_cast<size_t>(n), -1);
    std::vector<int64_t> which(n, -1);
    for (size_t q = 0; q < todo.size(); ++q) which[todo[q].sphere] = static_cast<int64_t>(q);
    for (int64_t k = 0; k < eng_.pair_count(); ++k) {
      if (!eng_.pair_touching(k)) continue;
      const int64_t i = eng_.pair_i(k), j = eng_.pair_j(k);
      if (which[i] >= 0) near[which[i]].push_back(j);
      if (which[j] >= 0) near[which[j]].push_back(i);
    }
  }
  // The mothers' overlaps, before any of them is replaced.
  for (size_t q = 0; q < todo.size(); ++q) {
    const int64_t s = todo[q].sphere;
    double o = wall_overlap(s);
    for (int64_t u : near[q]) o = std::max(o, p.r[s] + p.r[u] - norm(pos(p, u) - pos(p, s)));
    todo[q].mother_overlap_ratio = std::max(0.0, o) / p.r[s];
  }
  std::vector<int64_t> reach;
  std::vector<double> born_overlap;
  for (size_t q = 0; q < todo.size(); ++q) {
    SplitEvent& ev = todo[q];
    const int64_t first_new = p.size();
    // The new spheres may also overlap the fragments of a neighbour split
    // earlier in this check (her first sphere has her index, in near[q]).
    reach = near[q];
    for (int64_t u : near[q])
      if (first_new_of[u] >= 0)
        for (int64_t t = first_new_of[u]; t < first_new_of[u] + 33; ++t) reach.push_back(t);
    const Replacement rep = split(ev.sphere, ev.plane, reach, near[q], ev, born_overlap);
    first_new_of[ev.sphere] = first_new;
    ev.volume_mother_m3 = rep.volume_mother;
    events_.push_back(ev);
    if (!remove) continue;
    // A fragment sphere at the mother's contact inherits the mother's overlap
    // there, which can be a large fraction of its own small radius (a 17 µm
    // sphere of a 0.22 mm mother overlapped by 10 µm: 0.6 r, past the
    // engine's limit). That material is the crushed zone at the contact:
    // such spheres are not kept, they are fines (judged as placed, with the
    // mother's neighbours: the same rule whatever birth_overlap does).
    for (size_t k = 0; k < born_overlap.size(); ++k) {
      const int64_t t = k == 0 ? ev.sphere : first_new + static_cast<int64_t>(k) - 1;
      if (born_overlap[k] > opt_.fines_overlap * rep.spheres[k].r) fines.push_back(t);
    }
  }
  std::sort(fines.begin(), fines.end());
  fines.erase(std::unique(fines.begin(), fines.end()), fines.end());
  if (!todo.empty()) {
    eng_.request_rebuild();
    update_time_step();
  }
  // Splits keep every existing index (the mother's is reused, the rest are
  // appended), so the fines found above are still where they were.
  if (!fines.empty()) remove_fines(fines);
  if (!todo.empty() || !fines.empty()) update_mass_record();
  if (!todo.empty() || bonds_changed_) relabel_particles();
  rec_.spheres = p.size();
  rec_.bonds_intact = bond_count();
  return static_cast<int>(todo.size());
}

Replacement BreakageModel::split(int64_t s, const SplittingPlane& plane, const std::vector<int64_t>& neighbours,
                                 const std::vector<int64_t>& fines_neighbours, SplitEvent& ev,
                                 std::vector<double>& born_overlap) {
  Particles& p = eng_.particles();
  const Mother mother{pos(p, s), p.r[s], vel(p, s), spin(p, s)};
  const Replacement rep = replace_sphere(mother, plane.normal, plane.n_f);
  const int g = generation_[s];
  if (g == 0) ++rec_.grains_broken;
  if (static_cast<int>(rec_.splits_by_generation.size()) <= g) rec_.splits_by_generation.resize(g + 1, 0);
  ++rec_.splits_by_generation[g];

  // Birth overlaps of the new spheres (the mother still stands at s and is
  // no neighbour of her own fragments) and the radii they are born with.
  const size_t nnew = rep.spheres.size();
  born_overlap.assign(nnew, 0.0);
  std::vector<double> radius(nnew);
  const double qm = ev.mother_overlap_ratio;
  double shaved = 0, worst = 0;
  for (size_t k = 0; k < nnew; ++k) {
    const NewSphere& ns = rep.spheres[k];
    double o = wall_overlap(ns.x, ns.r);  // the fines rule's overlap: walls and the mother's neighbours
    for (int64_t u : fines_neighbours) o = std::max(o, ns.r + p.r[u] - norm(pos(p, u) - ns.x));
    born_overlap[k] = o;
    for (int64_t u : neighbours) o = std::max(o, ns.r + p.r[u] - norm(pos(p, u) - ns.x));
    worst = std::max(worst, o / ns.r);
    double cut = 0;  // radius shaved off (centre kept)
    if (opt_.birth_overlap == BirthOverlap::kNone) cut = o;
    else if (opt_.birth_overlap == BirthOverlap::kMotherRatio) cut = (o - qm * ns.r) / (1 - qm);  // (o − cut)/(r − cut) = qm
    cut = std::clamp(cut, 0.0, 0.5 * ns.r);
    radius[k] = ns.r;
    if (cut > 0) {
      radius[k] = ns.r - cut;
      shaved += 4.0 / 3.0 * std::numbers::pi * (ns.r * ns.r * ns.r - radius[k] * radius[k] * radius[k]);
    }
  }
  ev.fragment_overlap_ratio = worst;
  rec_.volume_lost_m3 += rep.volume_lost;
  ev.volume_retained_m3 = rep.volume_retained;
  if (shaved > 0) {
    rec_.volume_lost_m3 += shaved;
    ev.volume_retained_m3 -= shaved;
  }

  // The mother has no bonds left: check() dropped them before the splits.

  const int64_t n0 = p.size();
  const int64_t count = static_cast<int64_t>(rep.spheres.size());
  std::vector<int64_t> idx(count);
  idx[0] = s;
  for (int64_t k = 1; k < count; ++k) idx[k] = n0 + k - 1;
  p.resize(n0 + count - 1);  // every field of the declared list grows
  for (int64_t k = 1; k < count; ++k) p.copy_sphere(s, idx[k]);  // inherit material, flags, ...
  const double m_mother = p.m[s], r_mother = p.r[s];
  const uint64_t mother_key = key_[s];
  const double factor_mother = mass_factor_[s];
  for_each_sphere_field([&](auto& v) { v.resize(n0 + count - 1); });
  for (int64_t k = 0; k < count; ++k) {
    const NewSphere& ns = rep.spheres[k];
    const int64_t t = idx[k];
    p.x[t] = ns.x.x, p.y[t] = ns.x.y, p.z[t] = ns.x.z;
    p.vx[t] = ns.v.x, p.vy[t] = ns.v.y, p.vz[t] = ns.v.z;
    p.wx[t] = ns.w.x, p.wy[t] = ns.w.y, p.wz[t] = ns.w.z;
    p.fx[t] = p.fy[t] = p.fz[t] = 0;  // forces of the next evaluation start afresh
    p.tx[t] = p.ty[t] = p.tz[t] = 0;
    p.r[t] = radius[k];
    const double q = radius[k] / r_mother;
    p.m[t] = m_mother * q * q * q;  // keeps any mass scaling of the mother
    p.inertia[t] = 0.4 * p.m[t] * radius[k] * radius[k];
    p.flags[t] |= kFlagClusterElement;
    p.hbx[t] = p.hby[t] = p.hbz[t] = 0;
    p.htx[t] = p.hty[t] = p.htz[t] = 0;
    p.hcx[t] = p.hcy[t] = p.hcz[t] = 0;
    key_[t] = fragment_key(mother_key, ns.slot);
    generation_[t] = g + 1;
    strength_[t] = sphere_strength(opt_.strength, key_[t], 2 * radius[k]);
    mass_factor_[t] = factor_mother;
  }
  // As born: touching contacts with the neighbours and walls, largest Hertz force.
  for (int64_t k = 0; k < count; ++k) {
    const Vec3 x = pos(p, idx[k]);
    const double r = p.r[idx[k]];
    auto touch = [&](double delta, double r_eff) {
      if (delta <= 1e-9 * r) return;
      ++ev.fragment_contacts;
      ev.fragment_force_N = std::max(ev.fragment_force_N, law_.normal_force(delta, r_eff));
    };
    const Walls& w = eng_.options().walls;
    if (w.bottom) touch(r - x.z, r);
    if (w.top) touch(x.z + r - w.top_z, r);
    if (w.cylinder) touch(std::hypot(x.x, x.y) + r - w.cylinder_radius, r);
    for (int64_t u : neighbours) touch(r + p.r[u] - norm(pos(p, u) - x), r * p.r[u] / (r + p.r[u]));
  }
  for (auto b : rep.bonds) add_bond(idx[b[0]], idx[b[1]]);
  if (opt_.min_time_step_s > 0) {
    // Selective density scaling: each new sphere's own critical step (its
    // mass against its stiffest springs: Hertz at the reference overlap and
    // its fragment bonds) is lifted to min_time_step / safety if below. m and
    // I scale alike, so both √(m/k) and √(I/k_rot) grow by √factor.
    const size_t first_bond = ba_.size() - rep.bonds.size();
    std::vector<double> kt(count, 0.0), kr(count, 0.0);
    for (size_t q = 0; q < rep.bonds.size(); ++q) {
      const BondSection& sec = section_[first_bond + q];
      for (int e : {rep.bonds[q][0], rep.bonds[q][1]}) {
        kt[e] += bond_axial_stiffness(sec);
        kr[e] += bond_bending_stiffness(sec);
      }
    }
    const double need = opt_.min_time_step_s / opt_.time_step_safety;
    for (int64_t k = 0; k < count; ++k) {
      const int64_t t = idx[k];
      const double own = own_critical_step(p.m[t], p.inertia[t], p.r[t], kt[k], kr[k]);
      if (own >= need) continue;
      const double f = (need / own) * (need / own) * (1 + 1e-9);  // margin for rounding
      p.m[t] *= f;
      p.inertia[t] *= f;
      mass_factor_[t] *= f;
    }
  }
  return rep;
}

void BreakageModel::add_bond(int64_t a, int64_t b) {
  const Particles& p = eng_.particles();
  if (a == b || a < 0 || b < 0 || a >= p.size() || b >= p.size())
    throw std::logic_error("BreakageModel::add_bond: bad sphere indices");
  ba_.push_back(std::min(a, b));
  bb_.push_back(std::max(a, b));
  section_.push_back(bond_section(opt_.bond, p.r[a], p.r[b]));
  state_.push_back(BondState{});
  broken_.push_back(0);
  born_step_.push_back(eng_.step_count());
  born_time_.push_back(eng_.time());
  bonds_changed_ = true;
}

void BreakageModel::remove_fines(const std::vector<int64_t>& spheres) {
  Particles& p = eng_.particles();
  const int64_t n = p.size();
  std::vector<uint8_t> kill(n, 0);
  for (int64_t s : spheres) {
    if (s < 0 || s >= n || kill[s]) throw std::logic_error("BreakageModel::remove_fines: bad or repeated sphere index");
    kill[s] = 1;
    const double v = 4.0 / 3.0 * std::numbers::pi * p.r[s] * p.r[s] * p.r[s];
    rec_.fines_volume_m3 += v;
    rec_.volume_lost_m3 += v;
    ++rec_.fines_removed;
  }
  drop_bonds_of(kill);
  const std::vector<int64_t> map = eng_.remove_spheres(kill);
  for (size_t b = 0; b < ba_.size(); ++b) {  // monotone map: ba < bb stays true
    ba_[b] = map[ba_[b]];
    bb_[b] = map[bb_[b]];
  }
  for (int64_t s = 0; s < n; ++s) {
    const int64_t t = map[s];
    if (t < 0 || t == s) continue;
    for_each_sphere_field([&](auto& v) { v[t] = v[s]; });
  }
  const int64_t kept = p.size();
  for_each_sphere_field([&](auto& v) { v.resize(kept); });
  bonds_changed_ = true;
  relabel_particles();
  rec_.spheres = kept;
  rec_.bonds_intact = bond_count();
  update_mass_record();
}

std::vector<double> BreakageModel::max_overlap_ratios() const {
  const Particles& p = eng_.particles();
  const int64_t n = p.size();
  std::vector<double> o(n, 0.0);
  for (int64_t k = 0; k < eng_.pair_count(); ++k) {
    if (!eng_.pair_touching(k)) continue;
    const int64_t i = eng_.pair_i(k), j = eng_.pair_j(k);
    const double delta = p.r[i] + p.r[j] - norm(pos(p, j) - pos(p, i));
    o[i] = std::max(o[i], delta / p.r[i]);
    o[j] = std::max(o[j], delta / p.r[j]);
  }
  for (int64_t s = 0; s < n; ++s) o[s] = std::max(o[s], wall_overlap(s) / p.r[s]);
  return o;
}

double BreakageModel::wall_overlap(int64_t s) const {
  const Particles& p = eng_.particles();
  return wall_overlap(pos(p, s), p.r[s]);
}

double BreakageModel::wall_overlap(Vec3 x, double r) const {
  const Walls& w = eng_.options().walls;
  double d = 0;
  if (w.bottom) d = std::max(d, r - x.z);
  if (w.top) d = std::max(d, x.z + r - w.top_z);
  if (w.cylinder) d = std::max(d, std::hypot(x.x, x.y) + r - w.cylinder_radius);
  return d;
}

double BreakageModel::own_critical_step(double m, double inertia, double r, double kt, double kr) const {
  // Hertz: the stiffest partner of a sphere of radius r has R* ≤ r (a wall
  // or a larger sphere); stiffness at an overlap of 5 % of r (the engine's
  // reference overlap).
  const double ref = TimeStepOptions{}.reference_overlap;
  double dt = std::sqrt(m / law_.normal_stiffness(ref * r, r));
  if (kt > 0) dt = std::min({dt, std::sqrt(m / kt), std::sqrt(inertia / kr)});
  return dt;
}

void BreakageModel::update_mass_record() {
  const Particles& p = eng_.particles();
  double nominal = 0, total = 0;
  for (int64_t s = 0; s < p.size(); ++s) {
    total += p.m[s];
    nominal += p.m[s] / mass_factor_[s];
  }
  rec_.added_mass_kg = total - nominal;
  rec_.added_mass_fraction = nominal > 0 ? rec_.added_mass_kg / nominal : 0.0;
}

void BreakageModel::relabel_particles() {
  Particles& p = eng_.particles();
  const int64_t n = p.size();
  std::vector<int64_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int64_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  };
  for (size_t b = 0; b < ba_.size(); ++b) {
    const int64_t a = find(ba_[b]), c = find(bb_[b]);
    if (a != c) parent[std::max(a, c)] = std::min(a, c);  // root = smallest index
  }
  int64_t roots = 0;
  for (int64_t s = 0; s < n; ++s) {
    p.particle[s] = find(s);
    if (p.particle[s] == s) ++roots;
  }
  rec_.particles = roots;
  bonds_changed_ = false;
}

void BreakageModel::update_time_step() {
  const Particles& p = eng_.particles();
  const int64_t n = p.size();
  // Sum of bond spring constants per sphere.
  std::vector<double> kt(n, 0.0), kr(n, 0.0);
  for (size_t b = 0; b < ba_.size(); ++b) {
    for (int64_t s : {ba_[b], bb_[b]}) {
      kt[s] += bond_axial_stiffness(section_[b]);
      kr[s] += bond_bending_stiffness(section_[b]);
    }
  }
  // Pairing each sphere's own mass with its own stiffness avoids the
  // m_min / k(r_max) mismatch of a global estimate once fragments are two
  // orders of magnitude lighter than grains.
  double dt = std::numeric_limits<double>::infinity();
  for (int64_t s = 0; s < n; ++s) dt = std::min(dt, own_critical_step(p.m[s], p.inertia[s], p.r[s], kt[s], kr[s]));
  const double want = opt_.time_step_safety * dt;
  if (want < eng_.options().time_step) eng_.set_time_step(want);
}

namespace {
std::string g17(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}
}  // namespace

std::string BreakageModel::encode() const {
  std::ostringstream os;
  const int64_t n = static_cast<int64_t>(key_.size());
  os << "breakage3 " << g17(eng_.options().time_step) << ' ' << n;
  for (int64_t s = 0; s < n; ++s) os << ' ' << key_[s] << ' ' << generation_[s] << ' ' << g17(mass_factor_[s]);
  os << ' ' << rec_.grains_broken << ' ' << rec_.bonds_broken << ' ' << rec_.bonds_dropped << ' ' << g17(rec_.volume_lost_m3)
     << ' ' << rec_.fines_removed << ' ' << g17(rec_.fines_volume_m3) << ' ' << rec_.splits_by_generation.size();
  for (int64_t c : rec_.splits_by_generation) os << ' ' << c;
  os << ' ' << ba_.size();
  for (size_t b = 0; b < ba_.size(); ++b) {
    const BondState& st = state_[b];
    os << ' ' << ba_[b] << ' ' << bb_[b] << ' ' << g17(st.fn) << ' ' << g17(st.fs.x) << ' ' << g17(st.fs.y) << ' '
       << g17(st.fs.z) << ' ' << g17(st.mt) << ' ' << g17(st.mb.x) << ' ' << g17(st.mb.y) << ' ' << g17(st.mb.z)
       << ' ' << born_step_[b] << ' ' << g17(born_time_[b]);
  }
  return os.str();
}

void BreakageModel::restore(const std::string& state) {
  std::istringstream is(state);
  auto fail = [](const std::string& what) { throw InputError("checkpoint: breakage state " + what); };
  std::string tag;
  double dt = 0;
  int64_t n = 0;
  // breakage2 (before bond birth steps were kept): ages unknown (-1).
  if (!(is >> tag >> dt >> n) || (tag != "breakage2" && tag != "breakage3")) fail("missing or of an unknown version");
  const bool births = tag == "breakage3";
  const Particles& p = eng_.particles();
  if (n != p.size()) fail("has " + std::to_string(n) + " spheres, the checkpoint " + std::to_string(p.size()));
  for_each_sphere_field([&](auto& v) { v.resize(n); });
  for (int64_t s = 0; s < n; ++s) {
    if (!(is >> key_[s] >> generation_[s] >> mass_factor_[s]) || !(mass_factor_[s] >= 1)) fail("truncated (spheres)");
    strength_[s] = sphere_strength(opt_.strength, key_[s], 2 * p.r[s]);
  }
  size_t ngen = 0;
  if (!(is >> rec_.grains_broken >> rec_.bonds_broken >> rec_.bonds_dropped >> rec_.volume_lost_m3 >> rec_.fines_removed >>
        rec_.fines_volume_m3 >> ngen))
    fail("truncated (records)");
  rec_.splits_by_generation.assign(ngen, 0);
  for (auto& c : rec_.splits_by_generation)
    if (!(is >> c)) fail("truncated (generations)");
  size_t nb = 0;
  if (!(is >> nb)) fail("truncated (bonds)");
  for_each_bond_field([&](auto& v) { v.assign(nb, {}); });
  for (size_t b = 0; b < nb; ++b) {
    BondState& st = state_[b];
    if (!(is >> ba_[b] >> bb_[b] >> st.fn >> st.fs.x >> st.fs.y >> st.fs.z >> st.mt >> st.mb.x >> st.mb.y >> st.mb.z))
      fail("truncated (bond " + std::to_string(b) + ")");
    born_step_[b] = -1;
    if (births && !(is >> born_step_[b] >> born_time_[b])) fail("truncated (bond " + std::to_string(b) + ")");
    if (ba_[b] < 0 || bb_[b] >= n || ba_[b] >= bb_[b]) fail("names a bond between spheres out of range");
    section_[b] = bond_section(opt_.bond, p.r[ba_[b]], p.r[bb_[b]]);
  }
  eng_.set_time_step(dt);
  rec_.spheres = n;
  rec_.bonds_intact = static_cast<int64_t>(nb);
  relabel_particles();
  update_mass_record();
}

void BreakageModel::run(int64_t steps) {
  for (int64_t k = 0; k < steps; ++k) {
    eng_.step();
    if (check_due()) check();
  }
}

}  // namespace tg::dem::breakage
