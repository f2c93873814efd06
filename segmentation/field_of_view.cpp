#include "segmentation/field_of_view.hpp"

#include <fmt/core.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "core/errors.hpp"
#include "segmentation/threshold.hpp"

namespace tg {
namespace {

struct Circle {
  double cy = 0, cx = 0, r = 0, rms = 0;
  bool ok = false;
};

// Kasa's algebraic fit: minimise sum (y^2 + x^2 + D y + E x + F)^2, a 3x3
// linear system in (D, E, F); centre (-D/2, -E/2), r^2 = cy^2 + cx^2 - F.
// Coordinates are centred on their mean first (conditioning).
Circle kasa_fit(const std::vector<std::array<double, 2>>& p) {
  Circle c;
  const double n = double(p.size());
  if (p.size() < 3) return c;
  double my = 0, mx = 0;
  for (const auto& q : p) my += q[0], mx += q[1];
  my /= n, mx /= n;
  double syy = 0, sxx = 0, syx = 0, syz = 0, sxz = 0, sz = 0;
  for (const auto& q : p) {
    const double y = q[0] - my, x = q[1] - mx, z = y * y + x * x;
    syy += y * y, sxx += x * x, syx += y * x, syz += y * z, sxz += x * z, sz += z;
  }
  // With centred coordinates the system for (D, E) decouples from F:
  // [syy syx; syx sxx] [D; E] = -[syz; sxz],  F = -sz / n.
  const double det = syy * sxx - syx * syx;
  if (!(std::abs(det) > 1e-12 * (syy * sxx + 1))) return c;
  const double D = (-syz * sxx + sxz * syx) / det;
  const double E = (-sxz * syy + syz * syx) / det;
  const double F = -sz / n;
  c.cy = -D / 2 + my;
  c.cx = -E / 2 + mx;
  const double r2 = D * D / 4 + E * E / 4 - F;
  if (!(r2 > 0)) return c;
  c.r = std::sqrt(r2);
  double ss = 0;
  for (const auto& q : p) {
    const double d = std::hypot(q[0] - c.cy, q[1] - c.cx) - c.r;
    ss += d * d;
  }
  c.rms = std::sqrt(ss / n);
  c.ok = true;
  return c;
}

FieldOfView no_fov(std::string why) {
  FieldOfView f;
  f.note = std::move(why);
  return f;
}

FieldOfView fit_field_of_view(const Shape& s, uint16_t c, const std::vector<int64_t>& xmin,
                              const std::vector<int64_t>& xmax) {
  const int64_t ny = s.ny, nx = s.nx;
  // Boundary points: row ends, and column ends derived from the rows (the
  // region is taken as convex along rows). Points on the slice border are
  // where the slice clips the circle: left out.
  std::vector<std::array<double, 2>> pts;
  std::vector<int64_t> ymin(size_t(nx), ny), ymax(size_t(nx), -1);
  for (int64_t j = 0; j < ny; ++j) {
    if (xmax[size_t(j)] < 0) continue;
    if (xmin[size_t(j)] > 0) pts.push_back({double(j), double(xmin[size_t(j)])});
    if (xmax[size_t(j)] < nx - 1) pts.push_back({double(j), double(xmax[size_t(j)])});
    for (int64_t i = xmin[size_t(j)]; i <= xmax[size_t(j)]; ++i) {
      ymin[size_t(i)] = std::min(ymin[size_t(i)], j);
      ymax[size_t(i)] = std::max(ymax[size_t(i)], j);
    }
  }
  for (int64_t i = 0; i < nx; ++i) {
    if (ymax[size_t(i)] < 0) continue;
    if (ymin[size_t(i)] > 0) pts.push_back({double(ymin[size_t(i)]), double(i)});
    if (ymax[size_t(i)] < ny - 1) pts.push_back({double(ymax[size_t(i)]), double(i)});
  }
  if (pts.size() < 16)
    return no_fov(pts.empty() ? "" : fmt::format("field of view: the slices' corners hold the constant {}, but its "
                                                 "boundary has too few points for a circle; none used", c));
  const Circle fit = kasa_fit(pts);
  if (!fit.ok || fit.rms > 1.5)
    return no_fov(fmt::format("field of view: the constant {} around the slices is not bounded by a circle (fit RMS "
                              "{:.2g} voxels > 1.5); none used",
                              c, fit.rms));
  FieldOfView f = circular_field_of_view(fit.cy, fit.cx, fit.r - 1.0, s);
  if (double(f.outside_voxels) / double(s.voxels()) < 0.01)
    return no_fov(fmt::format("field of view: the circle found (radius {:.1f} voxels) covers the slice; none used",
                              fit.r));
  f.source = "detected";
  f.outside_value = c;
  f.fit_rms = fit.rms;
  return f;
}

}  // namespace

FovScan::FovScan(int64_t ny, int64_t nx)
    : nx_(nx), xmin_(size_t(std::max<int64_t>(ny, 0)), nx), xmax_(size_t(std::max<int64_t>(ny, 0)), -1) {}

void FovScan::add(const Volume<uint16_t>& g) {
  const Shape s = g.shape();
  if (s.ny != int64_t(xmin_.size()) || s.nx != nx_)
    throw UsageError("field of view: a slab of " + s.str() + " does not match the scan's slices");
  if (s.empty() || !constant_) return;
  if (slices_ == 0) c_ = g(0, 0, 0);
  slices_ += s.nz;
  const uint16_t c = c_;
  for (int64_t k = 0; k < s.nz; ++k)
    if (g(k, 0, 0) != c || g(k, 0, s.nx - 1) != c || g(k, s.ny - 1, 0) != c || g(k, s.ny - 1, s.nx - 1) != c) {
      constant_ = false;  // no constant outside: nothing to detect, nothing to say
      return;
    }
  // The middle rows' grey levels, until there are 4 (finish: a few-level image has no field of view).
  for (int64_t k = 0; k < s.nz && levels_.size() < 4; ++k) {
    const uint16_t* row = &g(k, s.ny / 2, 0);
    for (int64_t i = 0; i < s.nx && levels_.size() < 4; ++i)
      if (std::find(levels_.begin(), levels_.end(), row[i]) == levels_.end()) levels_.push_back(row[i]);
  }
  // Per row y, the envelope over the slices of the first / last voxel != c
  // (carried from slab to slab: the envelope of a union is the envelope of
  // the parts' envelopes).
  const int64_t ny = s.ny, nx = s.nx;
#pragma omp parallel for schedule(static)
  for (int64_t j = 0; j < ny; ++j) {
    int64_t lo = xmin_[size_t(j)], hi = xmax_[size_t(j)];
    for (int64_t k = 0; k < s.nz; ++k) {
      const uint16_t* row = &g(k, j, 0);
      int64_t a = 0;
      while (a < std::min(lo, nx) && row[a] == c) ++a;
      if (a < lo && a < nx) lo = a;
      if (a >= nx) continue;  // the whole row is c (or left of what is known)
      int64_t b = nx - 1;
      while (b > hi && row[b] == c) --b;
      hi = std::max(hi, b);
    }
    xmin_[size_t(j)] = lo, xmax_[size_t(j)] = hi;
  }
}

FieldOfView FovScan::finish(const Shape& whole) const {
  if (whole.empty() || whole.ny < 8 || whole.nx < 8 || !constant_ || slices_ == 0) return no_fov("");
  if (levels_.size() < 4)
    return no_fov(fmt::format("field of view: the slices' corners hold the constant {}, but the image has under 4 grey "
                              "levels (binary or pre-thresholded): its outside is data, not cut away",
                              c_));
  return fit_field_of_view(whole, c_, xmin_, xmax_);
}

FieldOfView circular_field_of_view(double cy, double cx, double radius, const Shape& s) {
  FieldOfView f;
  f.active = true;
  f.source = "given";
  f.centre_y = cy, f.centre_x = cx, f.radius = radius;
  f.x0.assign(size_t(s.ny), 0);
  f.x1.assign(size_t(s.ny), 0);
  int64_t inside = 0;
  for (int64_t j = 0; j < s.ny; ++j) {
    const double dy = double(j) - cy, h2 = radius * radius - dy * dy;
    if (h2 < 0) continue;
    const double h = std::sqrt(h2);
    const int64_t a = std::max<int64_t>(0, int64_t(std::ceil(cx - h)));
    const int64_t b = std::min<int64_t>(s.nx, int64_t(std::floor(cx + h)) + 1);
    if (b > a) f.x0[size_t(j)] = a, f.x1[size_t(j)] = b, inside += b - a;
  }
  f.outside_voxels = (s.slice_voxels() - inside) * s.nz;
  return f;
}

FieldOfView given_field_of_view(const FovOptions& o, const Shape& s) {
  if (!(o.radius_vox > 0 || std::isfinite(o.centre_y) || std::isfinite(o.centre_x))) return {};
  if (!(o.radius_vox > 0) || !std::isfinite(o.radius_vox))
    throw UsageError("segment: a field-of-view centre needs a positive radius (--fov-radius-vox)");
  const double cy = std::isfinite(o.centre_y) ? o.centre_y : 0.5 * double(s.ny - 1);
  const double cx = std::isfinite(o.centre_x) ? o.centre_x : 0.5 * double(s.nx - 1);
  FieldOfView f = circular_field_of_view(cy, cx, o.radius_vox, s);
  if (f.outside_voxels == s.voxels())
    throw UsageError(fmt::format("segment: the field of view (centre y {:.1f}, x {:.1f}, radius {:.1f} voxels) holds "
                                 "no voxel of the {}x{} slice",
                                 cy, cx, o.radius_vox, s.ny, s.nx));
  if (f.outside_voxels == 0) f.active = false;  // covers the slice: the plain path
  return f;
}

FieldOfView find_field_of_view(const Volume<uint16_t>& grey, const FovOptions& o) {
  const Shape s = grey.shape();
  if (o.radius_vox > 0 || std::isfinite(o.centre_y) || std::isfinite(o.centre_x)) return given_field_of_view(o, s);
  if (!o.detect) return {};
  FovScan scan(s.ny, s.nx);
  scan.add(grey);
  return scan.finish(s);
}

std::vector<int64_t> histogram_in_fov(const Volume<uint16_t>& grey, const FieldOfView& fov) {
  return fov.active ? histogram_u16(grey, &fov.x0, &fov.x1) : histogram_u16(grey);
}

void clear_outside(Volume<uint8_t>& mask, const FieldOfView& fov) {
  if (!fov.active) return;
  const Shape s = mask.shape();
  const int64_t rows = s.nz * s.ny;
#pragma omp parallel for schedule(static)
  for (int64_t r = 0; r < rows; ++r) {
    const int64_t j = r % s.ny;
    uint8_t* row = mask.data() + r * s.nx;
    std::fill(row, row + fov.x0[size_t(j)], uint8_t(0));
    std::fill(row + fov.x1[size_t(j)], row + s.nx, uint8_t(0));
  }
}

std::string LevelScreen::action() const {
  std::string a;
  auto add = [&a](const std::string& s) { a += (a.empty() ? "" : "; ") + s; };
  if (zeros_premasked) add("zeros are pre-masked background: left out of the histogram, never solid");
  if (zeros_clipped) add("zeros (clipped void) left out of the histogram, kept void");
  if (top_saturated) add(fmt::format("level {} left out of the histogram, kept solid", top_level));
  return a.empty() ? "none" : a;
}

LevelScreen screen_levels(std::vector<int64_t>& hist, int top_level) {
  LevelScreen L;
  L.top_level = top_level;
  for (const int64_t c : hist) L.voxels += c;
  // Fewer than 4 grey levels: a constant, binary or few-phase image, not a
  // reconstruction; nothing is screened (the threshold handles it).
  int distinct = 0;
  for (size_t b = 0; b < hist.size() && distinct < 4; ++b) distinct += hist[b] > 0;
  if (distinct < 4) return L;
  const double n = double(L.voxels);
  L.zero_count = hist[0];
  L.top_count = top_level > 0 && size_t(top_level) < hist.size() ? hist[size_t(top_level)] : 0;
  if (L.zero_count > 0) {
    int64_t top = 0;
    for (int64_t b = int64_t(hist.size()) - 1; b > 0; --b)
      if (hist[size_t(b)]) {
        top = b;
        break;
      }
    const int64_t w = std::max<int64_t>(1, top / 256);
    int64_t above = 0;
    for (int64_t b = 1; b <= w && b < int64_t(hist.size()); ++b) above += hist[size_t(b)];
    L.zeros_premasked = double(L.zero_count) >= kPremaskedFraction * n && above * 100 < L.zero_count;
    L.zeros_clipped = !L.zeros_premasked && double(L.zero_count) > kSaturatedFraction * n;
  }
  L.top_saturated = double(L.top_count) > kSaturatedFraction * n;
  if (L.zeros_premasked)
    L.notes.push_back(fmt::format("{:.3g} % of the voxels are exactly 0 with almost none just above: pre-masked "
                                  "background or pores, left out of the threshold's histogram",
                                  100.0 * L.zero_fraction()));
  if (L.zeros_clipped)
    L.notes.push_back(fmt::format("{:.3g} % of the voxels clipped at 0: left out of the threshold's histogram (they "
                                  "stay void)",
                                  100.0 * L.zero_fraction()));
  if (L.top_saturated)
    L.notes.push_back(fmt::format("{:.3g} % of the voxels saturated at {}: left out of the threshold's histogram "
                                  "(they stay solid)",
                                  100.0 * L.top_fraction(), top_level));
  const int64_t saturated = (L.zeros_clipped ? L.zero_count : 0) + (L.top_saturated ? L.top_count : 0);
  if (2 * saturated > L.voxels)
    throw InputError(fmt::format("{:.3g} % of the voxels are saturated ({:.3g} % at {}, {:.3g} % at 0): a threshold "
                                 "chosen on the rest would be meaningless; rescan or re-normalise",
                                 100.0 * double(saturated) / n, 100.0 * L.top_fraction(), top_level,
                                 L.zeros_clipped ? 100.0 * L.zero_fraction() : 0.0));
  if (L.zeros_premasked || L.zeros_clipped) hist[0] = 0;
  if (L.top_saturated) hist[size_t(top_level)] = 0;
  return L;
}

}  // namespace tg
