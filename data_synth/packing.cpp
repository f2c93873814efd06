#include "data_synth/packing.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/errors.hpp"
#include "data_synth/partial_volume.hpp"
#include "data_synth/rng.hpp"

namespace tg::synth {

double lognormal_sigma(double cu) {
  constexpr double z60_minus_z10 = 0.2533471031357997 + 1.2815515655446004;  // Φ⁻¹(0.6) − Φ⁻¹(0.1)
  return std::log(cu) / z60_minus_z10;
}

namespace {

constexpr double kPi = std::numbers::pi;

// Counting-sort cell grid over the container's bounding box.
struct CellGrid {
  double z0 = 0, y0 = 0, x0 = 0, cell = 1;
  int nz = 1, ny = 1, nx = 1;
  std::vector<int> start, items;

  int coord(double v, double o, int n) const {
    return std::clamp(static_cast<int>(std::floor((v - o) / cell)), 0, n - 1);
  }
  int cell_of(const Vec3& c) const {
    return (coord(c[0], z0, nz) * ny + coord(c[1], y0, ny)) * nx + coord(c[2], x0, nx);
  }
  void build(const std::vector<Sphere>& s) {
    start.assign(static_cast<size_t>(nz) * ny * nx + 1, 0);
    items.resize(s.size());
    for (const Sphere& sp : s) ++start[cell_of(sp.c) + 1];
    for (size_t q = 1; q < start.size(); ++q) start[q] += start[q - 1];
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (size_t q = 0; q < s.size(); ++q) items[fill[cell_of(s[q].c)]++] = static_cast<int>(q);
  }
  // Calls f(j) for every sphere j in the 27 cells around sphere centre c.
  template <class F>
  void around(const Vec3& c, F&& f) const {
    const int cz = coord(c[0], z0, nz), cy = coord(c[1], y0, ny), cx = coord(c[2], x0, nx);
    for (int a = std::max(0, cz - 1); a <= std::min(nz - 1, cz + 1); ++a)
      for (int b = std::max(0, cy - 1); b <= std::min(ny - 1, cy + 1); ++b)
        for (int d = std::max(0, cx - 1); d <= std::min(nx - 1, cx + 1); ++d) {
          const int cellid = (a * ny + b) * nx + d;
          for (int q = start[cellid]; q < start[cellid + 1]; ++q) f(items[q]);
        }
  }
};

struct Walls {
  const PackingOptions& o;
  // Largest radius scale that keeps sphere (c, r) inside; and the push inside.
  void push(Vec3& c, double r) const {
    c[0] = std::clamp(c[0], r, std::max(r, o.height - r));
    if (o.container == Container::cylinder) {
      const double R = 0.5 * o.diameter, rho = std::hypot(c[1], c[2]);
      if (rho + r > R && rho > 0) {
        const double f = std::max(0.0, R - r) / rho;
        c[1] *= f;
        c[2] *= f;
      }
    } else {
      c[1] = std::clamp(c[1], -0.5 * o.box_y + r, 0.5 * o.box_y - r);
      c[2] = std::clamp(c[2], -0.5 * o.box_x + r, 0.5 * o.box_x - r);
    }
  }
  double scale_limit(const Vec3& c, double r) const {
    double f = std::min(c[0], o.height - c[0]) / r;
    if (o.container == Container::cylinder)
      f = std::min(f, (0.5 * o.diameter - std::hypot(c[1], c[2])) / r);
    else
      f = std::min({f, (0.5 * o.box_y - std::abs(c[1])) / r, (0.5 * o.box_x - std::abs(c[2])) / r});
    return f;
  }
};

}  // namespace

double fraction_in_box(const std::vector<Sphere>& spheres, const Vec3& lo, const Vec3& hi) {
  double v = 0;
  for (const Sphere& s : spheres) v += sphere_box_volume(s, lo, hi);
  return v / ((hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]));
}

double max_overlap(const std::vector<Sphere>& s) {
  double worst = -1e300;
  for (size_t i = 0; i < s.size(); ++i)
    for (size_t j = i + 1; j < s.size(); ++j) {
      const double d = std::sqrt((s[i].c[0] - s[j].c[0]) * (s[i].c[0] - s[j].c[0]) +
                                 (s[i].c[1] - s[j].c[1]) * (s[i].c[1] - s[j].c[1]) +
                                 (s[i].c[2] - s[j].c[2]) * (s[i].c[2] - s[j].c[2]));
      worst = std::max(worst, s[i].r + s[j].r - d);
    }
  return worst;
}

Packing dense_packing(const PackingOptions& o) {
  const bool cyl = o.container == Container::cylinder;
  if (!(o.d50 > 0) || !(o.cu >= 1) || !(o.height > 0) || (cyl && !(o.diameter > 0)) ||
      (!cyl && !(o.box_y > 0 && o.box_x > 0)))
    throw InputError("packing: need d50 > 0, cu >= 1 and positive container sizes");
  if (!(o.target_fraction > 0 && o.target_fraction < 0.74))
    throw InputError("packing: target_fraction must be in (0, 0.74)");
  const double Vc = cyl ? kPi * 0.25 * o.diameter * o.diameter * o.height : o.height * o.box_y * o.box_x;
  const double sigma = lognormal_sigma(o.cu);
  const double wy = cyl ? o.diameter : o.box_y, wx = cyl ? o.diameter : o.box_x;
  if (o.d50 * std::exp(3 * sigma) >= std::min({o.height, wy, wx}))
    throw InputError("packing: the largest grains do not fit in the container");

  // 1. Sizes.
  Stream rng(o.seed, 0x5ac1);
  std::vector<Sphere> s;
  double vol = 0;
  while (vol < o.target_fraction * Vc) {
    const double z = std::clamp(rng.normal(), -3.0, 3.0);
    const double r = 0.5 * o.d50 * std::exp(sigma * z);
    s.push_back(Sphere{{0, 0, 0}, r});
    vol += 4.0 / 3.0 * kPi * r * r * r;
    if (s.size() > 50'000'000) throw InputError("packing: more than 5e7 grains; use a larger d50");
  }
  const std::vector<double> radius = [&] {
    std::vector<double> r;
    for (const Sphere& sp : s) r.push_back(sp.r);
    return r;
  }();
  std::vector<double> r0 = radius;
  // 2. Random centres.
  Walls walls{o};
  for (Sphere& sp : s) {
    do {
      sp.c = {rng.uniform(0, o.height), rng.uniform(-0.5 * wy, 0.5 * wy), rng.uniform(-0.5 * wx, 0.5 * wx)};
    } while (cyl && std::hypot(sp.c[1], sp.c[2]) > 0.5 * o.diameter);
  }
  CellGrid grid;
  const double rmax = *std::max_element(r0.begin(), r0.end());
  grid.cell = 2 * rmax;
  grid.z0 = 0;
  grid.y0 = -0.5 * wy;
  grid.x0 = -0.5 * wx;
  grid.nz = std::max(1, static_cast<int>(o.height / grid.cell));
  grid.ny = std::max(1, static_cast<int>(wy / grid.cell));
  grid.nx = std::max(1, static_cast<int>(wx / grid.cell));
  grid.cell = std::max({o.height / grid.nz, wy / grid.ny, wx / grid.nx});

  Packing out;
  // One Gauss–Seidel sweep at radius scale `scale`; returns the largest relative overlap.
  auto sweep = [&](double scale, std::vector<double>* load) {
    grid.build(s);
    double worst = 0;
    for (size_t i = 0; i < s.size(); ++i) {
      const double ri = scale * r0[i];
      grid.around(s[i].c, [&](int j) {
        if (static_cast<size_t>(j) <= i) return;
        const double rj = scale * r0[j];
        Vec3 d{s[j].c[0] - s[i].c[0], s[j].c[1] - s[i].c[1], s[j].c[2] - s[i].c[2]};
        double dist = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        const double delta = ri + rj - dist;
        if (delta <= 0) return;
        if (dist < 1e-12 * ri) {  // coincident centres: separate along a fixed direction
          d = {0, 0, 1};
          dist = 1;
        }
        const double m = 0.5 * delta / dist;
        for (int a = 0; a < 3; ++a) {
          s[i].c[a] -= m * d[a];
          s[j].c[a] += m * d[a];
        }
        worst = std::max(worst, delta / (0.5 * (ri + rj)));
        if (load) {
          (*load)[i] += delta;
          (*load)[j] += delta;
        }
      });
      walls.push(s[i].c, ri);
    }
    ++out.sweeps;
    return worst;
  };

  // 3. Growth with relaxation.
  double scale = 0.7;
  for (;;) {
    int k = 0;
    double worst = 1;
    for (; k < o.stage_sweeps; ++k) {
      worst = sweep(scale, nullptr);
      if (worst < o.tolerance) break;
    }
    if (worst >= o.tolerance) {
      // Jammed at this scale: remove the most loaded sphere and retry.
      std::vector<double> load(s.size(), 0.0);
      sweep(scale, &load);
      const size_t q = static_cast<size_t>(std::max_element(load.begin(), load.end()) - load.begin());
      s.erase(s.begin() + static_cast<long>(q));
      r0.erase(r0.begin() + static_cast<long>(q));
      ++out.removed;
      continue;
    }
    if (scale >= 1) break;
    scale = std::min(1.0, scale * 1.01);
  }
  // 4. Polish at full size, then remove any residual overlap by a uniform factor.
  for (int k = 0; k < 20 * o.stage_sweeps; ++k)
    if (sweep(1.0, nullptr) < 1e-7) break;
  double f = 1;
  grid.build(s);
  for (size_t i = 0; i < s.size(); ++i) {
    f = std::min(f, walls.scale_limit(s[i].c, r0[i]));
    grid.around(s[i].c, [&](int j) {
      if (static_cast<size_t>(j) <= i) return;
      const double d = std::sqrt((s[i].c[0] - s[j].c[0]) * (s[i].c[0] - s[j].c[0]) +
                                 (s[i].c[1] - s[j].c[1]) * (s[i].c[1] - s[j].c[1]) +
                                 (s[i].c[2] - s[j].c[2]) * (s[i].c[2] - s[j].c[2]));
      f = std::min(f, d / (r0[i] + r0[j]));
    });
  }
  f *= 1 - 1e-12;  // round-off margin
  out.final_scale = f;
  double vs = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    s[i].r = f * r0[i];
    vs += 4.0 / 3.0 * kPi * s[i].r * s[i].r * s[i].r;
  }
  out.fraction = vs / Vc;
  // Contacts and gaps.
  int64_t contacts = 0;
  double min_gap = 1e300;
  grid.build(s);
  for (size_t i = 0; i < s.size(); ++i)
    grid.around(s[i].c, [&](int j) {
      if (static_cast<size_t>(j) <= i) return;
      const double d = std::sqrt((s[i].c[0] - s[j].c[0]) * (s[i].c[0] - s[j].c[0]) +
                                 (s[i].c[1] - s[j].c[1]) * (s[i].c[1] - s[j].c[1]) +
                                 (s[i].c[2] - s[j].c[2]) * (s[i].c[2] - s[j].c[2]));
      const double gap = d - s[i].r - s[j].r;
      min_gap = std::min(min_gap, gap);
      if (gap < 1e-3 * o.d50) ++contacts;
    });
  out.mean_contacts = s.empty() ? 0 : 2.0 * static_cast<double>(contacts) / static_cast<double>(s.size());
  out.min_gap = min_gap;
  // Interior: one D50 from every wall (for the cylinder, the inscribed square).
  const double m = o.d50;
  const double hy = cyl ? (0.5 * o.diameter - m) / std::sqrt(2.0) : 0.5 * o.box_y - m;
  const double hx = cyl ? hy : 0.5 * o.box_x - m;
  if (hy > 0 && hx > 0 && o.height > 2 * m)
    out.interior_fraction = fraction_in_box(s, {m, -hy, -hx}, {o.height - m, hy, hx});
  out.spheres = std::move(s);
  return out;
}

}  // namespace tg::synth
