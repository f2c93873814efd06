#include "data_synth/partial_volume.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "core/errors.hpp"

namespace tg::synth {
namespace detail {

// Gauss–Legendre nodes and weights on [0, 1] for orders 1..64, computed once by
// Newton iteration on P_n (Golub–Welsch would do too; Newton is short).
struct GaussLegendre {
  std::vector<std::vector<double>> x, w;
  GaussLegendre() : x(65), w(65) {
    for (int n = 1; n <= 64; ++n) {
      x[n].resize(n);
      w[n].resize(n);
      for (int i = 0; i < n; ++i) {
        double t = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5));
        double dp = 1;
        for (int it = 0; it < 100; ++it) {
          double p0 = 1, p1 = t;
          for (int k = 2; k <= n; ++k) {
            const double p2 = ((2.0 * k - 1) * t * p1 - (k - 1.0) * p0) / k;
            p0 = p1;
            p1 = p2;
          }
          dp = n * (t * p1 - p0) / (t * t - 1);
          const double dt = p1 / dp;
          t -= dt;
          if (std::abs(dt) < 1e-16) break;
        }
        // recompute derivative at the converged node
        double p0 = 1, p1 = t;
        for (int k = 2; k <= n; ++k) {
          const double p2 = ((2.0 * k - 1) * t * p1 - (k - 1.0) * p0) / k;
          p0 = p1;
          p1 = p2;
        }
        dp = (n == 1) ? 1.0 : n * (t * p1 - p0) / (t * t - 1);
        x[n][i] = 0.5 * (1 - t);
        w[n][i] = 1.0 / ((1 - t * t) * dp * dp);  // 2/((1−t²)P'²) on [−1,1], halved for [0,1]
      }
    }
  }
};
const GaussLegendre& gauss_legendre() {
  static const GaussLegendre g;
  return g;
}

// ∫₀ᵗ √(ρ² − s²) ds for |t| <= ρ.
inline double prim(double t, double rho, double rho2) {
  const double q = std::max(0.0, rho2 - t * t);
  return 0.5 * (t * std::sqrt(q) + rho2 * std::asin(std::clamp(t / rho, -1.0, 1.0)));
}

// Area of the disc of radius rho centred at the origin ∩ {a < u, b < v}.
// Integrates over a in [−ρ, min(u, ρ)] the length of the b-section below v.
inline double quadrant_area(double u, double v, double rho) {
  if (rho <= 0 || u <= -rho || v <= -rho) return 0;
  const double r2 = rho * rho;
  u = std::min(u, rho);
  const double quarter = 0.25 * std::numbers::pi * r2;  // prim(ρ)
  if (v >= rho) return 2 * (prim(u, rho, r2) + quarter);
  const double w = std::sqrt(r2 - v * v);  // |a| < w: the section is cut by b = v
  if (v >= 0) {
    double area = 2 * (prim(u, rho, r2) + quarter);
    if (u > -w) {
      const double m = std::min(u, w);
      area -= (prim(m, rho, r2) - prim(-w, rho, r2)) - v * (m + w);
    }
    return area;
  }
  if (u <= -w) return 0;
  const double m = std::min(u, w);
  return v * (m + w) + prim(m, rho, r2) - prim(-w, rho, r2);
}

// Area of the disc (radius rho, centre origin) ∩ [u0,u1] × [v0,v1].
inline double disc_rect_area(double rho, double u0, double u1, double v0, double v1) {
  if (rho <= 0) return 0;
  if (u0 <= -rho && u1 >= rho && v0 <= -rho && v1 >= rho) return std::numbers::pi * rho * rho;
  return quadrant_area(u1, v1, rho) - quadrant_area(u0, v1, rho) - quadrant_area(u1, v0, rho) +
         quadrant_area(u0, v0, rho);
}

constexpr int kSphereOrder = 10;  // Gauss–Legendre order per smooth piece (max error 5e-11/voxel measured)

// Exact chord of a convex piece along z at (y, x), clipped to [z0, z1].
inline bool piece_chord(const Piece& pc, double y, double x, double z0, double z1, double& a, double& b) {
  const Sphere& s = pc.sphere;
  const double dy = y - s.c[1], dx = x - s.c[2];
  const double h2 = s.r * s.r - dy * dy - dx * dx;
  if (h2 <= 0) return false;
  const double h = std::sqrt(h2);
  a = std::max(z0, s.c[0] - h);
  b = std::min(z1, s.c[0] + h);
  for (const HalfSpace& hs : pc.planes) {
    const double rhs = hs.d - hs.n[1] * y - hs.n[2] * x;
    if (hs.n[0] > 1e-14)
      b = std::min(b, rhs / hs.n[0]);
    else if (hs.n[0] < -1e-14)
      a = std::max(a, rhs / hs.n[0]);
    else if (rhs < 0)
      return false;
  }
  return b > a;
}

// Covered length (and ∫z dz over it) of particle p along the z-line at (y, x)
// within [z0, z1]: union of piece chords minus pore chords (pores lie inside).
inline double line_cover(const Particle& p, double y, double x, double z0, double z1, double* zmom,
                         bool with_pores = true) {
  double len = 0, mom = 0;
  double a, b;
  if (p.pieces.size() == 1) {
    if (piece_chord(p.pieces[0], y, x, z0, z1, a, b)) {
      len = b - a;
      mom = 0.5 * (b * b - a * a);
    }
  } else {
    // Small unions (clusters): collect, sort, merge.
    std::pair<double, double> iv[64];
    std::vector<std::pair<double, double>> big;
    std::pair<double, double>* buf = iv;
    if (p.pieces.size() > 64) {
      big.resize(p.pieces.size());
      buf = big.data();
    }
    int n = 0;
    for (const Piece& pc : p.pieces)
      if (piece_chord(pc, y, x, z0, z1, a, b)) buf[n++] = {a, b};
    std::sort(buf, buf + n);
    double ca = 0, cb = -1e300;
    for (int q = 0; q < n; ++q) {
      if (buf[q].first > cb) {
        if (cb > ca) { len += cb - ca; mom += 0.5 * (cb * cb - ca * ca); }
        ca = buf[q].first;
        cb = buf[q].second;
      } else {
        cb = std::max(cb, buf[q].second);
      }
    }
    if (n > 0 && cb > ca) { len += cb - ca; mom += 0.5 * (cb * cb - ca * ca); }
  }
  for (const Sphere& s : p.pores) {
    if (!with_pores) break;
    const double dy = y - s.c[1], dx = x - s.c[2];
    const double h2 = s.r * s.r - dy * dy - dx * dx;
    if (h2 <= 0) continue;
    const double h = std::sqrt(h2);
    a = std::max(z0, s.c[0] - h);
    b = std::min(z1, s.c[0] + h);
    if (b > a) { len -= b - a; mom -= 0.5 * (b * b - a * a); }
  }
  if (zmom) *zmom = mom;
  return len;
}

// Chord quadrature of one box face, single cell, pieces only (no pores).
inline double chord_quadrature(const Particle& p, const Vec3& lo, const Vec3& hi, int order) {
  const auto& g = gauss_legendre();
  const auto& xs = g.x[order];
  const auto& ws = g.w[order];
  const double ey = hi[1] - lo[1], ex = hi[2] - lo[2];
  double sum = 0;
  for (int a = 0; a < order; ++a) {
    const double y = lo[1] + ey * xs[a];
    double row = 0;
    for (int b = 0; b < order; ++b) row += ws[b] * line_cover(p, y, lo[2] + ex * xs[b], lo[0], hi[0], nullptr, false);
    sum += ws[a] * row;
  }
  return sum * ey * ex;
}

// Sphere coverage of a box, with pores ignored and no planes: classification first.
enum class Rel { outside, inside, boundary };
inline Rel sphere_relation(const Sphere& s, const Vec3& lo, const Vec3& hi) {
  double dmin2 = 0, dmax2 = 0;
  for (int a = 0; a < 3; ++a) {
    const double c = s.c[a];
    const double near = std::clamp(c, lo[a], hi[a]) - c;
    const double far = std::max(c - lo[a], hi[a] - c);
    dmin2 += near * near;
    dmax2 += far * far;
  }
  const double r2 = s.r * s.r;
  if (dmin2 >= r2) return Rel::outside;
  if (dmax2 <= r2) return Rel::inside;
  return Rel::boundary;
}

// Coverage of a unit-or-any box by one piece; returns -1 when the piece needs chord
// quadrature (cut by the sphere surface and a plane, or by two planes).
inline double piece_box(const Piece& pc, const Vec3& lo, const Vec3& hi) {
  const Rel rel = sphere_relation(pc.sphere, lo, hi);
  if (rel == Rel::outside) return 0;
  const HalfSpace* cut = nullptr;
  int ncut = 0;
  for (const HalfSpace& h : pc.planes) {
    double smin = -h.d, smax = -h.d;
    for (int a = 0; a < 3; ++a) {
      const double u = h.n[a] * lo[a], v = h.n[a] * hi[a];
      smin += std::min(u, v);
      smax += std::max(u, v);
    }
    if (smin >= 0) return 0;
    if (smax > 0) { cut = &h; ++ncut; }
  }
  const double vol = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
  if (ncut == 0) return rel == Rel::inside ? vol : sphere_box_volume(pc.sphere, lo, hi);
  if (ncut == 1 && rel == Rel::inside) return halfspace_box_volume(*cut, lo, hi);
  return -1;
}

}  // namespace detail

double sphere_box_volume(const Sphere& s, const Vec3& lo, const Vec3& hi) {
  using namespace detail;
  const double R = s.r;
  if (R <= 0) return 0;
  // Integrate along the axis on which the box is nearest the sphere's equator:
  // there ρ(z) varies least across the box, so there are fewest breakpoints.
  int a = 0;
  double best = 1e300;
  for (int d = 0; d < 3; ++d) {
    const double off = std::abs(0.5 * (lo[d] + hi[d]) - s.c[d]);
    if (off < best) { best = off; a = d; }
  }
  const int b = (a + 1) % 3, c = (a + 2) % 3;
  const double z0 = std::max(lo[a] - s.c[a], -R), z1 = std::min(hi[a] - s.c[a], R);
  if (z1 <= z0) return 0;
  const double u0 = lo[b] - s.c[b], u1 = hi[b] - s.c[b], v0 = lo[c] - s.c[c], v1 = hi[c] - s.c[c];
  if (u0 >= R || u1 <= -R || v0 >= R || v1 <= -R) return 0;
  const double R2 = R * R;
  // Breakpoints: ρ(z) equals an edge-line or corner distance.
  double bp[2 + 2 * 8];
  int nb = 0;
  bp[nb++] = z0;
  bp[nb++] = z1;
  const double d2s[8] = {u0 * u0, u1 * u1, v0 * v0, v1 * v1,
                         u0 * u0 + v0 * v0, u0 * u0 + v1 * v1, u1 * u1 + v0 * v0, u1 * u1 + v1 * v1};
  for (double d2 : d2s) {
    if (d2 >= R2) continue;
    const double t = std::sqrt(R2 - d2);
    if (t > z0 && t < z1) bp[nb++] = t;
    if (-t > z0 && -t < z1) bp[nb++] = -t;
  }
  std::sort(bp, bp + nb);
  const auto& g = gauss_legendre();
  const auto& xs = g.x[kSphereOrder];
  const auto& ws = g.w[kSphereOrder];
  double vol = 0;
  // z = R sin θ moves the pole singularity of A (at ρ = 0) away from the pieces'
  // ends; the smoothstep θ = a + L(3s² − 2s³) removes the breakpoint singularities.
  // Pieces longer than 0.4 rad are split further (large boxes, tiny spheres):
  // cos θ over a long piece needs more than 12 points.
  for (int q = 0; q + 1 < nb; ++q) {
    const double ta = std::asin(std::clamp(bp[q] / R, -1.0, 1.0));
    const double tb = std::asin(std::clamp(bp[q + 1] / R, -1.0, 1.0));
    if (tb <= ta) continue;
    const int parts = static_cast<int>(std::ceil((tb - ta) / 0.4));
    const double L = (tb - ta) / parts;
    for (int part = 0; part < parts; ++part) {
      const double a = ta + part * L;
      double sum = 0;
      for (int m = 0; m < kSphereOrder; ++m) {
        const double sv = xs[m];
        const double th = a + L * sv * sv * (3 - 2 * sv);
        const double rho = R * std::cos(th);
        const double jac = 6 * sv * (1 - sv) * rho;  // dz/ds = R cos θ · dθ/ds
        sum += ws[m] * jac * disc_rect_area(rho, u0, u1, v0, v1);
      }
      vol += sum * L;
    }
  }
  return vol;
}

double halfspace_box_volume(const HalfSpace& h, const Vec3& lo, const Vec3& hi) {
  // Map the box to the unit cube t ∈ [0,1]³: Σ a_i t_i <= c with a_i = n_i e_i;
  // flip t_i -> 1 − t_i where a_i < 0 so that every a_i >= 0.
  double a[3], c = h.d, sum = 0;
  const double vol = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
  for (int i = 0; i < 3; ++i) {
    a[i] = h.n[i] * (hi[i] - lo[i]);
    c -= h.n[i] * lo[i];
    if (a[i] < 0) { c -= a[i]; a[i] = -a[i]; }
    sum += a[i];
  }
  if (c <= 0) return 0;
  if (c >= sum) return vol;
  if (a[0] >= 1e-2 && a[1] >= 1e-2 && a[2] >= 1e-2) {
    double f = 0;
    for (int v = 0; v < 8; ++v) {
      const double s = c - ((v & 1) ? a[0] : 0) - ((v & 2) ? a[1] : 0) - ((v & 4) ? a[2] : 0);
      if (s > 0) f += ((__builtin_popcount(v) & 1) ? -1.0 : 1.0) * s * s * s;
    }
    return vol * f / (6 * a[0] * a[1] * a[2]);
  }
  // Degenerate normal: chord along the largest a_i, 64×64 Gauss–Legendre on the other two.
  int m = 0;
  for (int i = 1; i < 3; ++i)
    if (a[i] > a[m]) m = i;
  const int p = (m + 1) % 3, q = (m + 2) % 3;
  const auto& g = detail::gauss_legendre();
  constexpr int n = 64;
  double f = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double len = (c - a[p] * g.x[n][i] - a[q] * g.x[n][j]) / a[m];
      f += g.w[n][i] * g.w[n][j] * std::clamp(len, 0.0, 1.0);
    }
  return vol * f;
}

namespace detail {
// Volume of the union of p's pieces inside [lo, hi] (pores not removed): exact
// paths when at most one piece is partial and it needs no chords, otherwise
// split into 8 octants down to `depth` levels, then chord quadrature.
double union_box(const Particle& p, const Vec3& lo, const Vec3& hi, int depth, int order) {
  const double vol = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
  double val = 0;
  int partial = 0;
  bool needs_chords = false;
  for (const Piece& pc : p.pieces) {
    const double v = piece_box(pc, lo, hi);
    if (v >= vol) return vol;
    if (v < 0) needs_chords = true;
    if (v != 0) { val = v; ++partial; }
  }
  if (!needs_chords && partial <= 1) return val;
  if (depth == 0) return chord_quadrature(p, lo, hi, order);
  const Vec3 mid{0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
  double sum = 0;
  for (int o = 0; o < 8; ++o) {
    Vec3 a, b;
    for (int d = 0; d < 3; ++d) {
      const bool upper = (o >> d) & 1;
      a[d] = upper ? mid[d] : lo[d];
      b[d] = upper ? hi[d] : mid[d];
    }
    sum += union_box(p, a, b, depth - 1, order);
  }
  return sum;
}
}  // namespace detail

double box_coverage(const Particle& p, const Vec3& lo, const Vec3& hi, const CoverageOptions& opt) {
  double val = detail::union_box(p, lo, hi, opt.depth, opt.chord_order);
  for (const Sphere& s : p.pores) val -= sphere_box_volume(s, lo, hi);
  return std::max(val, 0.0);
}

double voxel_coverage(const Particle& p, int64_t k, int64_t j, int64_t i, const CoverageOptions& opt) {
  const Vec3 lo{double(k), double(j), double(i)}, hi{k + 1.0, j + 1.0, i + 1.0};
  double val = detail::union_box(p, lo, hi, opt.depth, opt.chord_order);
  if (val <= 0) return 0;
  for (const Sphere& s : p.pores)
    if (detail::sphere_relation(s, lo, hi) != detail::Rel::outside) val -= sphere_box_volume(s, lo, hi);
  return std::clamp(val, 0.0, 1.0);
}

double chord_volume(const Particle& p, const Vec3& lo, const Vec3& hi, int cells, int order, Vec3* moment) {
  if (order < 1 || order > 64 || cells < 1) throw UsageError("chord_volume: order must be in [1, 64], cells >= 1");
  const auto& g = detail::gauss_legendre();
  const auto& xs = g.x[order];
  const auto& ws = g.w[order];
  const double hy = (hi[1] - lo[1]) / cells, hx = (hi[2] - lo[2]) / cells;
  double vol = 0, mz = 0, my = 0, mx = 0;
  for (int cy = 0; cy < cells; ++cy)
    for (int a = 0; a < order; ++a) {
      const double y = lo[1] + hy * (cy + xs[a]);
      for (int cx = 0; cx < cells; ++cx)
        for (int b = 0; b < order; ++b) {
          const double x = lo[2] + hx * (cx + xs[b]);
          double zm = 0;
          const double len = detail::line_cover(p, y, x, lo[0], hi[0], &zm);
          const double w = ws[a] * ws[b];
          vol += w * len;
          mz += w * zm;
          my += w * len * y;
          mx += w * len * x;
        }
    }
  const double area = hy * hx;
  if (moment) *moment = {mz * area, my * area, mx * area};
  return vol * area;
}

}  // namespace tg::synth
