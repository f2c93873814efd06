// Grey stand-ins for the real-scan failures of issue 19 (field of view,
// saturation, uneven brightness): a random packing of balls whose truth is
// known voxel by voxel, imaged with the contrast (void 10000, solid
// 30000, Gaussian noise 1500), optional blur (partial volume) and a
// brightness field; and a ball split by an oblique plane gap (the grey
// evidence and the split repair).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <random>
#include <vector>

#include <array>

#include "core/volume.hpp"
#include "data_synth/imaging.hpp"
#include "segmentation/segment_chunked.hpp"

namespace tg::test {

// Balls of radius r (voxel centres within r) at uniform random centres
// until the solid fraction reaches `fraction` (overlaps allowed).
inline Volume<uint8_t> ball_packing(const Shape& s, double r, double fraction, unsigned seed) {
  auto m = Volume<uint8_t>::filled(s, 0);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uz(0, double(s.nz)), uy(0, double(s.ny)), ux(0, double(s.nx));
  int64_t solid = 0;
  const int64_t target = int64_t(fraction * double(s.voxels()));
  while (solid < target) {
    const double cz = uz(rng), cy = uy(rng), cx = ux(rng);
    for (int64_t k = std::max<int64_t>(0, int64_t(cz - r)); k <= std::min<int64_t>(s.nz - 1, int64_t(cz + r) + 1); ++k)
      for (int64_t j = std::max<int64_t>(0, int64_t(cy - r)); j <= std::min<int64_t>(s.ny - 1, int64_t(cy + r) + 1); ++j)
        for (int64_t i = std::max<int64_t>(0, int64_t(cx - r)); i <= std::min<int64_t>(s.nx - 1, int64_t(cx + r) + 1);
             ++i) {
          const double dz = double(k) - cz, dy = double(j) - cy, dx = double(i) - cx;
          if (dz * dz + dy * dy + dx * dx <= r * r && !m(k, j, i)) m(k, j, i) = 1, ++solid;
        }
  }
  return m;
}

// Separable Gaussian blur (sigma voxels, kernel to 3 sigma, edges clamped).
inline void blur(Volume<float>& v, double sigma) {
  const int rad = int(std::ceil(3 * sigma));
  std::vector<double> w(size_t(2 * rad + 1));
  double sum = 0;
  for (int d = -rad; d <= rad; ++d) sum += w[size_t(d + rad)] = std::exp(-0.5 * d * d / (sigma * sigma));
  for (auto& x : w) x /= sum;
  const Shape s = v.shape();
  const int64_t n[3] = {s.nz, s.ny, s.nx}, stride[3] = {s.ny * s.nx, s.nx, 1};
  std::vector<float> line;
  for (int a = 0; a < 3; ++a) {
    line.resize(size_t(n[a]));
    for (int64_t base = 0; base < s.voxels(); ++base) {
      // base runs over the first voxel of each line along axis a
      const auto c = s.coords(base);
      if (c[size_t(a)] != 0) continue;
      for (int64_t p = 0; p < n[a]; ++p) line[size_t(p)] = v[base + p * stride[a]];
      for (int64_t p = 0; p < n[a]; ++p) {
        double acc = 0;
        for (int d = -rad; d <= rad; ++d)
          acc += w[size_t(d + rad)] * line[size_t(std::clamp<int64_t>(p + d, 0, n[a] - 1))];
        v[base + p * stride[a]] = float(acc);
      }
    }
  }
}

// Brightness field: the grey of void and solid at a voxel, as offsets added
// to both phases (cupping and drift move both).
using Offset = std::function<double(int64_t k, int64_t j, int64_t i)>;

// The grey scan of a truth: phase levels 10000 / 30000, blur sigma (0: none),
// an offset field (may be null), Gaussian noise 1500, clipped to 16 bits.
inline Volume<uint16_t> image(const Volume<uint8_t>& truth, double sigma, const Offset& offset, unsigned seed) {
  const Shape s = truth.shape();
  Volume<float> f(s);
  for (int64_t q = 0; q < s.voxels(); ++q) f[q] = truth[q] ? 30000.f : 10000.f;
  if (sigma > 0) blur(f, sigma);
  Volume<uint16_t> g(s);
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, 1500);
  for (int64_t k = 0; k < s.nz; ++k)
    for (int64_t j = 0; j < s.ny; ++j)
      for (int64_t i = 0; i < s.nx; ++i) {
        const double x = f(k, j, i) + (offset ? offset(k, j, i) : 0.0) + noise(rng);
        g(k, j, i) = uint16_t(std::clamp(std::lround(x), 0L, 65535L));
      }
  return g;
}

// A scan of the solid that `solid(z, y, x)` (voxel coordinates, a voxel's
// centre at its index) says: partial volume by 4^3 supersampling, then
// data_synth's imaging (PSF sigma psf, Gaussian noise at CNR cnr), void
// 10000, solid 30000. solid may also return a number in [0, 1]: the point's
// contrast as a share of the solid's (grains of different brightness).
template <class Solid>
Volume<uint16_t> supersampled_scan(const Shape& s, Solid&& solid, double psf, double cnr, uint64_t seed) {
  Volume<float> phi = Volume<float>::filled(s, 0.f);
  for (int64_t k = 0; k < s.nz; ++k)
    for (int64_t j = 0; j < s.ny; ++j)
      for (int64_t i = 0; i < s.nx; ++i) {
        double in = 0;
        for (int a = 0; a < 4; ++a)
          for (int b = 0; b < 4; ++b)
            for (int d = 0; d < 4; ++d)
              in += double(solid(double(k) + (a + 0.5) / 4 - 0.5, double(j) + (b + 0.5) / 4 - 0.5,
                                 double(i) + (d + 0.5) / 4 - 0.5));
        phi(k, j, i) = float(in / 64.0);
      }
  synth::ImagingOptions im;
  im.void_grey = 10000, im.solid_grey = 30000, im.psf_sigma = psf, im.noise_sigma = cnr > 0 ? 20000.0 / cnr : 0.0;
  im.seed = seed;
  synth::apply_imaging(phi, im);
  return synth::to_u16(phi).volume;
}

// A ball of radius R centred in an n^3 volume, cut by a plane through its
// centre with normal (1, 0.3, 0.2) (oblique: the gap crosses voxels partly)
// and a gap `gap` voxels wide; `pores` void balls of radius 2 inside each
// half when gap < 0 (then no cut: an intact grain). Partial volume by 4^3
// supersampling; imaging as data_synth's (PSF, Gaussian noise at CNR cnr).
// offset: the cut plane's distance from the centre, in R (0: halves; 0.75:
// a chip, the cap beyond it, 0.25 R high).
inline Volume<uint16_t> split_ball_scan(int64_t n, double R, double gap, int pores, double psf, double cnr, uint64_t seed,
                                        double offset = 0) {
  const double c = double(n) / 2 - 0.5, nn = std::sqrt(1 + 0.09 + 0.04);
  std::vector<std::array<double, 3>> pore;  // on a ring at R/2 around the centre
  for (int p = 0; p < pores; ++p) {
    const double a = 2 * M_PI * p / pores;
    pore.push_back({0.3 * R * std::sin(2 * a), 0.5 * R * std::cos(a), 0.5 * R * std::sin(a)});
  }
  auto solid = [&](double zv, double yv, double xv) {
    const double z = zv - c, y = yv - c, x = xv - c;
    bool in = z * z + y * y + x * x <= R * R;
    if (gap > 0) in = in && std::abs((x + 0.3 * y + 0.2 * z) / nn - offset * R) > gap / 2;
    for (const auto& p : pore)
      in = in && (z - p[0]) * (z - p[0]) + (y - p[1]) * (y - p[1]) + (x - p[2]) * (x - p[2]) > 4.0;
    return in;
  };
  return supersampled_scan(Shape{n, n, n}, solid, psf, cnr, seed);
}

// Balls (centre z, y, x and radius, voxels) minus spherical pores (the
// same), imaged as supersampled_scan.
struct Sphere {
  double z, y, x, r;
};
inline Volume<uint16_t> porous_balls_scan(const Shape& s, const std::vector<Sphere>& balls,
                                          const std::vector<Sphere>& pores, double psf, double cnr, uint64_t seed) {
  auto in = [](const Sphere& b, double z, double y, double x) {
    return (z - b.z) * (z - b.z) + (y - b.y) * (y - b.y) + (x - b.x) * (x - b.x) <= b.r * b.r;
  };
  auto solid = [&](double z, double y, double x) {
    bool v = false;
    for (const auto& g : balls) v = v || in(g, z, y, x);
    for (const auto& p : pores) v = v && !in(p, z, y, x);
    return v;
  };
  return supersampled_scan(s, solid, psf, cnr, seed);
}

// `grey` segmented slab by slab (segment_chunked.hpp, through readers and
// writers over the volume in memory): cores of `core` slices, `margin`
// slices read below and above; the labels, and the result in *out.
inline Volume<uint32_t> segment_slab_by_slab(const Volume<uint16_t>& grey, const SegmentOptions& o, int64_t core,
                                             int64_t margin, ChunkedResult* out) {
  const Shape s = grey.shape();
  const int64_t sl = s.slice_voxels();
  auto labels = Volume<uint32_t>::filled(s, 0xffffffffu);
  auto read = [&](int64_t z0, int64_t nz) {
    Volume<uint16_t> v(Shape{nz, s.ny, s.nx}, grey.geometry());
    std::copy(grey.data() + z0 * sl, grey.data() + (z0 + nz) * sl, v.data());
    return v;
  };
  auto write = [&](int64_t z0, const Volume<uint32_t>& l, int64_t vz0, int64_t nz) {
    std::copy(l.data() + vz0 * sl, l.data() + (vz0 + nz) * sl, labels.data() + z0 * sl);
  };
  ChunkPlan plan;
  plan.in_memory = false;
  plan.core = core;
  plan.margin = margin;
  *out = segment_chunked(s, grey.geometry(), read, write, o, plan);
  return labels;
}

// A window onto balls (face_caps_test, face_slivers_test): centres in window
// voxel coordinates, possibly outside it, the grey rendered kPad voxels
// beyond the window on every side and then cropped, so blur reaches in from
// grains outside it as in a window of a larger scan; or, with pad 0, the
// window imaged alone, its blur replicating the border voxels (as
// bench/segmentation/blind_scene.py images its scans).
struct Ball {
  double z, y, x, r;
};

inline constexpr size_t kMaxBalls = 16;
inline constexpr int64_t kPad = 6;  // rendered beyond the window on every side, then cropped: a window of a larger scan

// Truth (ball index + 1, 0 void) and grey of a window `s` onto balls (centres
// in window voxel coordinates, possibly outside it), minus the voxels where
// `slot` is true. Partial volume by 3^3 supersampling, PSF 0.7 voxel,
// contrast 10000 / 30000, noise 1538 (CNR 13).
struct Scene {
  Volume<uint32_t> truth;
  Volume<uint16_t> grey;
};
template <class Slot>
Scene render(const Shape& s, const std::vector<Ball>& balls, Slot slot, uint64_t seed, int64_t pad = kPad) {
  if (balls.size() > kMaxBalls) throw UsageError("render: at most 16 balls");
  const Shape p{s.nz + 2 * pad, s.ny + 2 * pad, s.nx + 2 * pad};
  Volume<float> phi = Volume<float>::filled(p, 0.f);
  Scene out{Volume<uint32_t>::filled(s, 0u), Volume<uint16_t>(s, Geometry::isotropic_m(10e-6))};
  for (int64_t k = 0; k < p.nz; ++k)
    for (int64_t j = 0; j < p.ny; ++j)
      for (int64_t i = 0; i < p.nx; ++i) {
        int in = 0;
        std::array<int, kMaxBalls> of{};
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b)
            for (int d = 0; d < 3; ++d) {
              const double z = double(k - pad) + (a + 0.5) / 3, y = double(j - pad) + (b + 0.5) / 3,
                           x = double(i - pad) + (d + 0.5) / 3;  // voxel (k, j, i) covers [k, k+1)
              if (slot(z, y, x)) continue;
              for (size_t q = 0; q < balls.size(); ++q) {
                const Ball& c = balls[q];
                if ((z - c.z) * (z - c.z) + (y - c.y) * (y - c.y) + (x - c.x) * (x - c.x) <= c.r * c.r) {
                  ++in, ++of[q];
                  break;
                }
              }
            }
        phi(k, j, i) = float(in) / 27.f;
        const int64_t wk = k - pad, wj = j - pad, wi = i - pad;
        if (s.contains(wk, wj, wi) && in >= 14) {
          size_t best = 0;
          for (size_t q = 1; q < balls.size(); ++q)
            if (of[q] > of[best]) best = q;
          out.truth(wk, wj, wi) = uint32_t(best + 1);
        }
      }
  synth::ImagingOptions im;
  im.void_grey = 10000, im.solid_grey = 30000, im.psf_sigma = 0.7, im.noise_sigma = 20000.0 / 13;
  im.seed = seed;
  synth::apply_imaging(phi, im);
  const Volume<uint16_t> g = synth::to_u16(phi).volume;
  for (int64_t k = 0; k < s.nz; ++k)
    for (int64_t j = 0; j < s.ny; ++j)
      for (int64_t i = 0; i < s.nx; ++i) out.grey(k, j, i) = g(k + pad, j + pad, i + pad);
  return out;
}

// IoU of truth particle t with the label holding most of it.
inline double best_iou(const Volume<uint32_t>& truth, const Volume<uint32_t>& labels, uint32_t t) {
  std::map<uint32_t, int64_t> both, size;
  int64_t nt = 0;
  for (int64_t q = 0; q < truth.size(); ++q) {
    if (labels[q]) ++size[labels[q]];
    if (truth[q] != t) continue;
    ++nt;
    if (labels[q]) ++both[labels[q]];
  }
  double best = 0;
  for (const auto& [l, c] : both) best = std::max(best, double(c) / double(nt + size[l] - c));
  return best;
}

// Balls on a grid, each of its own brightness (split_labels_test,
// grain_levels_test).
struct BrightnessScene {
  Volume<uint16_t> grey;
  Volume<uint32_t> truth;
};

// g^3 balls of radius R, one a cell of `cell` voxels (3 voxels of margin
// round the grid); ball b (z-major) is label b + 1, and those split(b)
// says are cut by an oblique 1-voxel gap, their far halves labelled g^3 + 1,
// g^3 + 2, .. in the order of b; brightness(b): the ball's share of the
// solid's contrast. Imaged as supersampled_scan (PSF 0.7, CNR 13).
template <class Split, class Brightness>
BrightnessScene grid_of_balls(int g, int64_t cell, double R, Split&& split, Brightness&& brightness, uint64_t seed) {
  const int64_t pad = 3, n = g * cell + 2 * pad;
  const double nn = std::sqrt(1 + 0.09 + 0.04);
  std::vector<uint32_t> half(size_t(g * g * g), 0);  // the far half's label of a split ball, 0: whole
  uint32_t next = uint32_t(g * g * g) + 1;
  for (int b = 0; b < g * g * g; ++b)
    if (split(b)) half[size_t(b)] = next++;
  // The one ball a point can lie in is its cell's.
  auto at = [&](double z, double y, double x, uint32_t* label) {
    auto cell_of = [&](double v) { return std::clamp(int(std::floor((v - double(pad)) / double(cell))), 0, g - 1); };
    const int cz = cell_of(z), cy = cell_of(y), cx = cell_of(x), b = g * g * cz + g * cy + cx;
    auto centre = [&](int c) { return double(pad) + double(cell) * c + 0.5 * double(cell) - 0.5; };
    const double dz = z - centre(cz), dy = y - centre(cy), dx = x - centre(cx);
    if (dz * dz + dy * dy + dx * dx > R * R) return 0.0;
    uint32_t l = uint32_t(b + 1);
    if (half[size_t(b)]) {
      const double u = (dx + 0.3 * dy + 0.2 * dz) / nn;
      if (std::abs(u) <= 0.5) return 0.0;  // the gap
      if (u > 0) l = half[size_t(b)];
    }
    if (label) *label = l;
    return brightness(b);
  };
  BrightnessScene s;
  s.grey = supersampled_scan(Shape{n, n, n}, [&](double z, double y, double x) { return at(z, y, x, nullptr); },
                                   0.7, 13, seed);
  s.truth = Volume<uint32_t>::filled(Shape{n, n, n}, 0u);
  for (int64_t k = 0; k < n; ++k)
    for (int64_t j = 0; j < n; ++j)
      for (int64_t i = 0; i < n; ++i) {
        uint32_t l = 0;
        if (at(double(k), double(j), double(i), &l) > 0) s.truth(k, j, i) = l;
      }
  return s;
}

}  // namespace tg::test
