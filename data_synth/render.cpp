#include "data_synth/render.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_set>

#include <omp.h>

#include "core/errors.hpp"
#include "core/progress.hpp"

namespace tg::synth {

namespace {

struct IBox {
  int64_t z0, z1, y0, y1, x0, x1;  // half-open voxel ranges, clipped to the volume
};

}  // namespace

Rendered render(const std::vector<Particle>& particles, Shape shape, const Geometry& geometry,
                const RenderOptions& opt) {
  if (opt.slab < 1) throw UsageError("render: slab must be >= 1");
  if (opt.chord_order < 1 || opt.chord_order > 32) throw UsageError("render: chord_order must be in [1, 32]");
  if (opt.depth < 0 || opt.depth > 6) throw UsageError("render: depth must be in [0, 6]");
  {
    std::unordered_set<uint32_t> seen;
    for (const Particle& p : particles) {
      if (p.id == 0) throw UsageError("render: particle id 0 is reserved for void");
      if (!seen.insert(p.id).second) throw UsageError("render: duplicate particle id " + std::to_string(p.id));
      if (p.pieces.empty()) throw UsageError("render: particle " + std::to_string(p.id) + " has no pieces");
    }
  }
  Rendered out;
  out.solid = Volume<float>(shape, geometry);
  if (opt.labels) out.labels = Volume<uint32_t>(shape, geometry);
  if (shape.empty()) return out;

  // Integer bounding boxes, clipped.
  std::vector<IBox> boxes(particles.size());
  for (size_t q = 0; q < particles.size(); ++q) {
    Vec3 lo, hi;
    bounding_box(particles[q], lo, hi);
    const int64_t n[3] = {shape.nz, shape.ny, shape.nx};
    int64_t b[6];
    for (int a = 0; a < 3; ++a) {
      b[2 * a] = std::clamp<int64_t>(static_cast<int64_t>(std::floor(lo[a])), 0, n[a]);
      b[2 * a + 1] = std::clamp<int64_t>(static_cast<int64_t>(std::ceil(hi[a])), 0, n[a]);
    }
    boxes[q] = {b[0], b[1], b[2], b[3], b[4], b[5]};
  }

  const int64_t nslab = (shape.nz + opt.slab - 1) / opt.slab;
  const int64_t sv = shape.slice_voxels();
  const CoverageOptions cov{opt.chord_order, opt.depth};
  Progress bar("render", static_cast<double>(nslab), "slabs");
  int64_t done = 0;
#pragma omp parallel
  {
    std::vector<float> best;  // largest coverage so far in this slab
#pragma omp for schedule(static, 1)
    for (int64_t s = 0; s < nslab; ++s) {
      const int64_t k0 = s * opt.slab, k1 = std::min(shape.nz, k0 + opt.slab);
      float* solid = out.solid.data() + k0 * sv;
      uint32_t* lab = opt.labels ? out.labels.data() + k0 * sv : nullptr;
      const int64_t n = (k1 - k0) * sv;
      std::fill(solid, solid + n, 0.0f);
      if (lab) {
        std::fill(lab, lab + n, 0u);
        best.assign(static_cast<size_t>(n), 0.0f);
      }
      for (size_t q = 0; q < particles.size(); ++q) {
        const IBox& b = boxes[q];
        const int64_t z0 = std::max(b.z0, k0), z1 = std::min(b.z1, k1);
        if (z0 >= z1 || b.y0 >= b.y1 || b.x0 >= b.x1) continue;
        const Particle& p = particles[q];
        for (int64_t k = z0; k < z1; ++k)
          for (int64_t j = b.y0; j < b.y1; ++j) {
            const int64_t row = (k - k0) * sv + j * shape.nx;
            for (int64_t i = b.x0; i < b.x1; ++i) {
              const float v = static_cast<float>(voxel_coverage(p, k, j, i, cov));
              if (v <= 0) continue;
              solid[row + i] += v;
              if (lab && v > best[row + i]) {
                best[row + i] = v;
                lab[row + i] = p.id;
              }
            }
          }
      }
      for (int64_t q = 0; q < n; ++q) {
        solid[q] = std::min(solid[q], 1.0f);
        if (lab && solid[q] < 0.5f) lab[q] = 0;
      }
      if (opt.progress && omp_get_thread_num() == 0) {
        done = s + 1;
        bar.update(static_cast<double>(done));
      }
    }
  }
  bar.finish();
  return out;
}

double mean_solid_fraction(const Volume<float>& solid) {
  const Shape sh = solid.shape();
  std::vector<double> per(static_cast<size_t>(sh.nz), 0.0);
#pragma omp parallel for schedule(static)
  for (int64_t k = 0; k < sh.nz; ++k) {
    double a = 0;
    const float* p = solid.data() + k * sh.slice_voxels();
    for (int64_t q = 0; q < sh.slice_voxels(); ++q) a += p[q];
    per[static_cast<size_t>(k)] = a;
  }
  double tot = 0;
  for (double v : per) tot += v;
  return tot / static_cast<double>(std::max<int64_t>(1, solid.size()));
}

}  // namespace tg::synth
