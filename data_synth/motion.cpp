#include "data_synth/motion.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <unordered_map>

#include "core/errors.hpp"
#include "data_synth/rng.hpp"

namespace tg::synth {
namespace {

using Mat3 = std::array<Vec3, 3>;  // rows

Vec3 mul(const Mat3& m, const Vec3& v) { return {dot(m[0], v), dot(m[1], v), dot(m[2], v)}; }

// Rotation by `angle` about unit `axis` (Rodrigues).
Mat3 rotation(const Vec3& a, double angle) {
  const double c = std::cos(angle), s = std::sin(angle), t = 1 - c;
  return Mat3{Vec3{t * a[0] * a[0] + c, t * a[0] * a[1] - s * a[2], t * a[0] * a[2] + s * a[1]},
              Vec3{t * a[0] * a[1] + s * a[2], t * a[1] * a[1] + c, t * a[1] * a[2] - s * a[0]},
              Vec3{t * a[0] * a[2] - s * a[1], t * a[1] * a[2] + s * a[0], t * a[2] * a[2] + c}};
}

// x' = c + R (x - c) + t for every sphere, plane and pore of p. A half-space
// n.x <= d becomes (R n).x' <= d - n.c + (R n).(c + t).
void transform(Particle& p, const Mat3& R, const Vec3& c, const Vec3& t) {
  auto move = [&](const Vec3& x) {
    const Vec3 r = mul(R, Vec3{x[0] - c[0], x[1] - c[1], x[2] - c[2]});
    return Vec3{c[0] + r[0] + t[0], c[1] + r[1] + t[1], c[2] + r[2] + t[2]};
  };
  const Vec3 ct{c[0] + t[0], c[1] + t[1], c[2] + t[2]};
  for (Piece& pc : p.pieces) {
    pc.sphere.c = move(pc.sphere.c);
    for (HalfSpace& h : pc.planes) {
      const Vec3 n = mul(R, h.n);
      h.d = h.d - dot(h.n, c) + dot(n, ct);
      h.n = n;
    }
  }
  for (Sphere& s : p.pores) s.c = move(s.c);
}

const Mat3 kIdentity{Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};

// The side a piece lies on: minus the sum of its planes' outward normals.
Vec3 side_of(const Particle& p) {
  Vec3 s{0, 0, 0};
  for (const HalfSpace& h : p.pieces[0].planes)
    for (int a = 0; a < 3; ++a) s[a] -= h.n[a];
  return unit(s);
}

// Stream keys of this file (granule.cpp has its own).
constexpr uint64_t kBreakStage = 0x5a9e0000, kJitter = 0x7177e000, kTurn = 0x70a70000, kRebreak = 0x4eb4000;

// First stage whose draw says "broken" (stages.size() when never).
int break_stage(uint32_t id, const StageOptions& o) {
  const double u = uniform01(o.breakage.seed, kBreakStage + id, 0);
  for (size_t s = 0; s < o.broken.size(); ++s)
    if (u < o.broken[s]) return static_cast<int>(s);
  return static_cast<int>(o.broken.size());
}

// The two halves of a fragment (plane through its sphere's centre that halves it exactly).
std::vector<Particle> halve(const Particle& f, uint32_t first_id, double gap, uint64_t seed) {
  const Piece& pc = f.pieces[0];
  Vec3 n;
  if (pc.planes.size() >= 2) {
    n = unit(cross(pc.planes[0].n, pc.planes[1].n));  // perpendicular to a wedge's edge
  } else {
    const Vec3 n0 = side_of(f);  // a plane containing a cap's axis
    const Vec3 v = random_direction(seed, kRebreak + f.id, 100);
    const double d = dot(v, n0);
    n = unit({v[0] - d * n0[0], v[1] - d * n0[1], v[2] - d * n0[2]});
  }
  std::vector<Particle> out;
  for (int side = 0; side < 2; ++side) {
    const Vec3 m = side == 0 ? n : Vec3{-n[0], -n[1], -n[2]};
    Particle p;
    p.id = first_id + static_cast<uint32_t>(side);
    p.kind = Kind::multi;
    p.parent = f.parent;
    Piece q = pc;
    q.planes.push_back(keep_above(m, pc.sphere.c, 0.5 * gap));
    p.pieces.push_back(q);
    for (const Sphere& pore : f.pores) {
      bool inside = true;
      for (const HalfSpace& h : q.planes) inside = inside && dot(h.n, pore.c) + pore.r <= h.d;
      if (inside) p.pores.push_back(pore);
    }
    out.push_back(std::move(p));
  }
  return out;
}

}  // namespace

std::vector<SeriesParticle> oedometer_stage(const std::vector<Particle>& grains, double z_bottom, int stage,
                                            const StageOptions& o, const MotionOptions& mo) {
  if (o.strains.empty() || o.strains.size() != o.broken.size())
    throw InputError("stages: strains and broken fractions must be lists of the same length");
  if (stage < 0 || stage >= static_cast<int>(o.strains.size())) throw UsageError("stage index out of range");
  for (size_t q = 0; q < o.strains.size(); ++q) {
    if (!(o.strains[q] >= 0 && o.strains[q] < 1) || !(o.broken[q] >= 0 && o.broken[q] <= 1))
      throw InputError("stages: strains must be in [0, 1), broken fractions in [0, 1]");
    if (q && (o.strains[q] < o.strains[q - 1] || o.broken[q] < o.broken[q - 1]))
      throw InputError("stages: an oedometer series needs non-decreasing strains and broken fractions");
  }
  if (!(mo.jitter >= 0 && mo.drift >= 0 && mo.rebreak >= 0 && mo.rebreak <= 1))
    throw InputError("stages: jitter and drift must be >= 0, rebreak in [0, 1]");
  const uint64_t seed = o.breakage.seed;
  const double emax = o.strains.back();
  auto progress = [&](int s) { return emax > 0 ? o.strains[s] / emax : 0.0; };  // e_s / e_max
  uint32_t max_id = 0;
  for (const Particle& g : grains) max_id = std::max(max_id, g.id);
  const uint32_t first = max_id + 1;
  const double f = (1 - o.strains[stage]) / (1 - emax);

  std::vector<SeriesParticle> out;
  for (const Particle& g : grains) {
    if (g.pieces.size() != 1 || !g.pieces[0].planes.empty()) throw UsageError("oedometer_stage: intact grains only");
    const Vec3 c0 = g.pieces[0].sphere.c;
    const double R = g.pieces[0].sphere.r;
    // The grain's rigid motion at this stage.
    Vec3 cs{z_bottom + (c0[0] - z_bottom) * f, c0[1], c0[2]};
    for (int q = 1; q <= stage; ++q) {
      const double step = emax > 0 ? std::sqrt(std::max(0.0, o.strains[q] - o.strains[q - 1]) / emax) : 0.0;
      for (int a = 0; a < 3; ++a) cs[a] += step * mo.jitter * R * normal01(seed, kJitter + g.id, 6 * q + 2 * a);
    }
    const Mat3 turn = rotation(random_direction(seed, kTurn + g.id, 0), mo.rotation_deg * std::numbers::pi / 180 * progress(stage));
    const Vec3 t{cs[0] - c0[0], cs[1] - c0[1], cs[2] - c0[2]};
    auto place = [&](Particle p, const Vec3& drift) {
      transform(p, kIdentity, c0, drift);
      transform(p, turn, c0, t);
      return p;
    };
    const int b = break_stage(g.id, o);
    if (stage < b) {
      out.push_back({place(g, {0, 0, 0}), stage ? g.id : 0u, g.id, "intact"});
      continue;
    }
    const Event ev = draw_event(g.id, o.breakage);
    const auto pieces = fragment(g, ev, first + 16 * (g.id - 1), o.breakage);
    const double since_b = progress(stage) - (b > 0 ? progress(b - 1) : 0.0);
    for (size_t p = 0; p < pieces.size(); ++p) {
      const Particle& pc = pieces[p];
      const Vec3 dir = side_of(pc);
      const double d = mo.drift * R * since_b;
      const Vec3 drift{d * dir[0], d * dir[1], d * dir[2]};
      // Who it comes from and what made it, at this stage.
      const bool born_now = stage == b;
      const uint32_t grain = b == 0 ? pc.id : g.id;
      std::string made = "intact";
      if (born_now && stage > 0)
        made = ev == Event::split ? "split" : ev == Event::multi ? "fragmentation" : pc.kind == Kind::chip ? "chip" : "chipping";
      const uint32_t parent = stage == 0 ? 0u : born_now ? g.id : pc.id;
      // A second breakage?
      int r = static_cast<int>(o.strains.size());
      if (pc.kind != Kind::chip)
        for (int s = b + 1; s < static_cast<int>(o.strains.size()); ++s)
          if (uniform01(seed, kRebreak + pc.id, static_cast<uint64_t>(s)) < mo.rebreak) {
            r = s;
            break;
          }
      if (stage < r || !(0.5 * o.breakage.gap < 0.5 * R)) {
        out.push_back({place(pc, drift), parent, grain, made});
        continue;
      }
      const double since_r = progress(stage) - progress(r - 1);
      for (Particle& h : halve(pc, first + 16 * (g.id - 1) + 4 + 2 * static_cast<uint32_t>(p), o.breakage.gap, seed)) {
        const Vec3 hd = unit({-h.pieces[0].planes.back().n[0], -h.pieces[0].planes.back().n[1], -h.pieces[0].planes.back().n[2]});
        const double e = mo.drift * R * since_r;
        const Vec3 dd{drift[0] + e * hd[0], drift[1] + e * hd[1], drift[2] + e * hd[2]};
        out.push_back({place(h, dd), stage == r ? pc.id : h.id, grain, stage == r ? "split" : "intact"});
      }
    }
  }
  return out;
}

Table lineage_truth(const std::vector<std::vector<SeriesParticle>>& stages, const std::vector<Table>& truth_tables) {
  if (stages.size() != truth_tables.size()) throw UsageError("lineage_truth: one truth table per stage");
  RowTable out({"stage", "label", "parent_label", "grain", "event", "volume_vox", "cz_vox", "cy_vox", "cx_vox"});
  std::unordered_map<uint32_t, uint32_t> prev_grain;  // present at the previous stage: id -> grain
  for (size_t s = 0; s < stages.size(); ++s) {
    const Table& t = truth_tables[s];
    const auto &id = t.num("id"), &lv = t.num("label_voxels"), &z = t.num("cz_vox"), &y = t.num("cy_vox"), &x = t.num("cx_vox");
    std::unordered_map<uint32_t, int64_t> row;
    for (int64_t q = 0; q < t.rows(); ++q)
      if (lv[q] > 0) row[static_cast<uint32_t>(id[q])] = q;
    std::unordered_map<uint32_t, uint32_t> now;
    for (const SeriesParticle& sp : stages[s]) {
      auto it = row.find(sp.particle.id);
      if (it == row.end()) continue;
      const int64_t q = it->second;
      uint32_t par = sp.parent, gr = sp.grain;
      std::string ev = sp.event;
      if (s == 0) {
        par = 0, gr = sp.particle.id, ev = "intact";
      } else if (!prev_grain.count(par)) {
        par = 0, gr = 0, ev = "new";
      } else {
        gr = prev_grain.at(par);
      }
      now[sp.particle.id] = gr;
      out.row({s, static_cast<int64_t>(sp.particle.id), static_cast<int64_t>(par), static_cast<int64_t>(gr), ev, lv[q],
               z[q], y[q], x[q]});
    }
    prev_grain = std::move(now);
  }
  return out.table();
}

}  // namespace tg::synth
