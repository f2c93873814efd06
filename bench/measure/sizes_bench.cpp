// measure_sizes_bench: FR, AR and D50 against grain diameter (voxels per
// grain diameter 10-110), against the exact truth of data_synth shapes.
//
// Per diameter D: 8 intact spheres, 8 half-spheres (cap height R: FR 0.5,
// AR 2) and 8 chips (cap height R/2: AR 3.46, FR 0.35), random
// orientations and sub-voxel centres (fixed seeds), one per cell of a
// 2.4 R grid, rendered with partial volume (data_synth/render.hpp) and
// measured with N = 60 (tie rule) and the exact mode. D50 = mass-weighted
// median of d_med (linear between particles), truth from the exact volumes
// and Dmed. Columns: mean FR - FR_truth and AR - AR_truth per kind (sphere,
// half, chip), D50 relative error, measure time (2 threads).
#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <numeric>
#include <vector>

#include "data_synth/geometry.hpp"
#include "data_synth/render.hpp"
#include "measure/particles.hpp"
#include "tests/measure/shapes.hpp"

using namespace tg;

namespace {

double d50(std::vector<std::pair<double, double>> dm) {  // (size, mass)
  std::sort(dm.begin(), dm.end());
  double total = 0;
  for (const auto& [d, m] : dm) total += m;
  double acc = 0;
  for (size_t k = 0; k < dm.size(); ++k) {
    const double next = acc + dm[k].second;
    if (next >= 0.5 * total) {
      if (k == 0) return dm[0].first;
      const double f = (0.5 * total - acc) / dm[k].second;
      return dm[k - 1].first + f * (dm[k].first - dm[k - 1].first);
    }
    acc = next;
  }
  return dm.back().first;
}

}  // namespace

int main() {
  std::printf("| D (vox) | mode | FR err sphere / half / chip | AR err sphere / half / chip | D50 err | time (s) |\n");
  std::printf("|---|---|---|---|---|---|\n");
  for (double D : {10.0, 20.0, 40.0, 70.0, 110.0}) {
    const double R = D / 2, cell = 2.4 * R;
    const int nx = 4, ny = 3, nz = 2;
    const int64_t sx = static_cast<int64_t>(std::ceil(nx * cell)), sy = static_cast<int64_t>(std::ceil(ny * cell)),
                  sz = static_cast<int64_t>(std::ceil(nz * cell));
    std::vector<synth::Particle> ps;
    std::vector<synth::Truth> truth;
    for (int c = 0; c < nx * ny * nz; ++c) {
      const unsigned seed = 300u + static_cast<unsigned>(c);
      const Eigen::Vector3d off = measure::test::random_offset(seed);
      const synth::Vec3 cen{(c / (nx * ny) + 0.5) * cell + off[0] - 0.5, ((c / nx) % ny + 0.5) * cell + off[1] - 0.5,
                            (c % nx + 0.5) * cell + off[2] - 0.5};
      const Eigen::Vector3d n = measure::test::random_rotation(seed).col(0);
      const uint32_t id = static_cast<uint32_t>(c + 1);
      const int kind = c % 3;
      if (kind == 0) {
        ps.push_back(synth::make_grain(id, cen, R));
      } else {
        // Cap {n.(p - c) >= offset}: height R - offset; offset 0 = half, R/2 = chip of height R/2.
        const double offset = kind == 1 ? 0.0 : 0.5 * R;
        // Centre the cap in its cell: shift the sphere back along n.
        const double shift = kind == 1 ? 0.4 * R : 0.7 * R;
        const synth::Vec3 sc{cen[0] - shift * n[0], cen[1] - shift * n[1], cen[2] - shift * n[2]};
        ps.push_back(synth::make_cap(id, kind == 1 ? synth::Kind::half : synth::Kind::chip, id, synth::Sphere{sc, R},
                                     {n[0], n[1], n[2]}, offset));
      }
      truth.push_back(synth::particle_truth(ps.back()));
    }
    auto r = synth::render(ps, Shape{sz, sy, sx}, Geometry::isotropic_m(1.0));
    for (int mode = 0; mode < 2; ++mode) {
      measure::ParticleOptions o;
      o.threads = 2;
      o.oriented_box = false;
      o.feret_exact = mode == 1;
      const auto t0 = std::chrono::steady_clock::now();
      const auto m = measure::measure_particles(r.labels.view(), o);
      const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      double fr[3] = {0, 0, 0}, ar[3] = {0, 0, 0};
      int cnt[3] = {0, 0, 0};
      std::vector<std::pair<double, double>> dm, dt;
      for (const auto& p : m) {
        const size_t k = p.stats.label - 1;
        const int kind = static_cast<int>(k % 3);
        fr[kind] += p.fr - truth[k].fr;
        ar[kind] += p.ar - truth[k].ar;
        ++cnt[kind];
        dm.push_back({p.d_med_m, p.stats.volume_m3});
        dt.push_back({truth[k].dmed, truth[k].volume});
      }
      std::printf("| %.0f | %s | %+.3f / %+.3f / %+.3f | %+.3f / %+.3f / %+.3f | %+.2f %% | %.3f |\n", D,
                  mode ? "exact" : "N=60", fr[0] / cnt[0], fr[1] / cnt[1], fr[2] / cnt[2], ar[0] / cnt[0],
                  ar[1] / cnt[1], ar[2] / cnt[2], 100 * (d50(dm) / d50(dt) - 1), t);
    }
  }
  return 0;
}
