// measure_feret_bench: the speed/accuracy tables of measure/ (issue 5).
//
//   measure_feret_bench convention [lambda...]  errors of exact-mode Dmed, FR,
//       AR and of the mean caliper on digitised spheres and half-spheres vs
//       radius, for hull point conventions (face_offset lambda)
//   measure_feret_bench trade        Dmax, Dmin, FR, AR error of the sampled
//       mode vs the exact mode for N = 15, 30, 60, 120, 500, and time per particle
//   measure_feret_bench throughput [n] [grains]   particles/s on an n^3 label
//       volume (default 512, ~1000 grains), 1 and 2 threads
//   measure_feret_bench small [n] [count]   the same on >= 20 000 particles of
//       7-100 voxels (default 256^3, 24 000); TG_DUMP=file.raw saves the labels
//
// Shapes are drawn by voxel-centre inclusion with random sub-voxel centres
// and rotations (fixed seeds), as in tests/measure/shapes.hpp.
#include <omp.h>

#include <chrono>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <string>
#include <vector>

#include "measure/feret.hpp"
#include "measure/label_stats.hpp"
#include "measure/particles.hpp"
#include "measure/psd.hpp"
#include "tests/measure/shapes.hpp"

using namespace tg;
using namespace tg::measure;
using test::V3;

namespace {

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

struct One {
  ConvexHull hull;
  double volume;
};
One hull_of(const Volume<uint32_t>& v, double lambda) {
  const auto r = label_stats(v.view());
  return {convex_hull(caliper_points(r.surface_of(0), v.geometry().voxel_size_m, r.labels[0].box_lo, lambda)),
          r.labels[0].volume_m3};
}

struct Truth {
  const char* name;
  double r;
  Volume<uint32_t> vol;
  double fr, ar, dmed;  // analytic
};

std::vector<Truth> shapes(const std::vector<double>& radii, int reps) {
  std::vector<Truth> out;
  for (double r : radii)
    for (int s = 0; s < reps; ++s) {
      const unsigned seed = static_cast<unsigned>(1000 * r + s);
      out.push_back({"sphere", r, test::draw_one(r, [r](V3 c) { return test::sphere(c, r); }, seed, 1.0), 1, 1, 2 * r});
      const V3 n = test::random_rotation(seed).col(0);
      out.push_back({"half-sphere", r, test::draw_one(r, [&](V3 c) { return test::half_sphere(c, r, n); }, seed, 1.0),
                     0.5, 2, 2 * r});
    }
  return out;
}

void convention(std::vector<double> lambdas) {
  if (lambdas.empty()) lambdas = {0.3, 0.45, 0.6, 0.8, 1.0};
  const auto all = shapes({10, 15, 20, 24, 30}, 6);
  const auto dirs = half_sphere_directions(2000);
  std::printf("# exact mode (tie tolerance 0.5 voxel); mean (max |.|) over 6 random placements\n");
  std::printf("%-12s %4s %6s | %-17s %-17s %-17s %-17s\n", "shape", "r", "lambda", "mean caliper err", "Dmed err",
              "FR err", "AR err");
  for (double lam : lambdas)
    for (const char* name : {"sphere", "half-sphere"})
      for (double r : {10.0, 15.0, 20.0, 24.0, 30.0}) {
        double s[4] = {0, 0, 0, 0}, m[4] = {0, 0, 0, 0};
        int n = 0;
        for (const auto& t : all) {
          if (t.r != r || std::string(t.name) != name) continue;
          const auto h = hull_of(t.vol, lam);
          const auto f = feret_exact(h.hull, FeretExactOptions{0.5, 20.0});
          const double med = 6 * h.volume / (std::numbers::pi * f.d_max * f.d_min);
          double mc = 0;
          for (const auto& u : dirs) mc += caliper_width(h.hull, u);
          mc /= static_cast<double>(dirs.size());
          // mean caliper of a half-sphere: (2R + R)/2... only the sphere's is simple (2r)
          const double e[4] = {std::string(name) == "sphere" ? mc / (2 * r) - 1 : 0.0, med / t.dmed - 1,
                               f.d_min / med - t.fr, f.d_max / f.d_min - t.ar};
          for (int k = 0; k < 4; ++k) {
            s[k] += e[k];
            m[k] = std::max(m[k], std::abs(e[k]));
          }
          ++n;
        }
        std::printf("%-12s %4.0f %6.2f |", name, r, lam);
        for (int k = 0; k < 4; ++k) std::printf(" %+8.4f (%6.4f)", s[k] / n, m[k]);
        std::printf("\n");
      }
}

void trade() {
  // 10 each of spheres, half-spheres, ellipsoids, boxes, r 12-20 voxels.
  std::vector<Volume<uint32_t>> vols;
  for (int s = 0; s < 10; ++s) {
    const unsigned seed = 500u + static_cast<unsigned>(s);
    const double r = 12 + 8 * test::random_offset(seed)[0];
    const Eigen::Matrix3d R = test::random_rotation(seed);
    vols.push_back(test::draw_one(r, [r](V3 c) { return test::sphere(c, r); }, seed, 1.0));
    vols.push_back(test::draw_one(r, [&](V3 c) { return test::half_sphere(c, r, R.col(0)); }, seed, 1.0));
    const V3 ax(r, 0.6 * r, 0.35 * r);
    vols.push_back(test::draw_one(r, [&](V3 c) { return test::ellipsoid(c, ax, R); }, seed, 1.0));
    const V3 e(1.6 * r, r, 0.6 * r);
    vols.push_back(test::draw_one(e.norm() / 2, [&](V3 c) { return test::box(c, e, R); }, seed, 1.0));
  }
  std::vector<One> hulls;
  double t0 = now();
  for (const auto& v : vols) hulls.push_back(hull_of(v, 0.3));
  const double t_hull = (now() - t0) / static_cast<double>(vols.size());
  std::vector<FeretResult> ex;
  t0 = now();
  for (const auto& h : hulls) ex.push_back(feret_exact(h.hull, FeretExactOptions{0.5, 20.0}));
  const double t_exact = (now() - t0) / static_cast<double>(vols.size());
  auto frar = [](const One& h, const FeretResult& f, double& fr, double& ar) {
    const double med = 6 * h.volume / (std::numbers::pi * f.d_max * f.d_min);
    fr = f.d_min / med;
    ar = f.d_max / f.d_min;
  };
  std::printf("# %zu particles (spheres, half-spheres, ellipsoids 1:0.6:0.35, boxes 1.6:1:0.6; r 12-20 voxels)\n",
              vols.size());
  std::printf("# hull (label stats + points + CGAL hull): %.3f ms/particle; exact sizing: %.3f ms/particle\n",
              1e3 * t_hull, 1e3 * t_exact);
  std::printf("# errors vs exact mode: mean |rel| for Dmax, Dmin; mean |abs| for FR, AR; worst in ()\n");
  std::printf("# lit = the study's literal Dmin (perpendicular to the one sampled Dmax direction);\n"
              "# tie = perpendicular to the direction fitted to the sampled directions within 0.5 voxel of Dmax (the table's default; feret.hpp)\n");
  std::printf("%10s | %-17s %-17s %-17s %-17s | %-27s | %s\n", "N", "Dmax", "Dmin", "FR", "AR",
              "mean FR bias: sph half ell box", "sizing ms/particle");
  for (double tie : {0.0, 0.5})
  for (int N : {15, 30, 60, 120, 500}) {
    const auto dirs = half_sphere_directions(N);
    double s[4] = {0, 0, 0, 0}, m[4] = {0, 0, 0, 0}, fr_shape[4] = {0, 0, 0, 0};
    t0 = now();
    std::vector<FeretResult> fs;
    for (const auto& h : hulls) fs.push_back(feret_sampled(h.hull, dirs, FeretSampledOptions{0, tie, 20.0}));
    const double t = (now() - t0) / static_cast<double>(vols.size());
    for (size_t p = 0; p < hulls.size(); ++p) {
      double fr, ar, fre, are;
      frar(hulls[p], fs[p], fr, ar);
      frar(hulls[p], ex[p], fre, are);
      const double e[4] = {std::abs(fs[p].d_max / ex[p].d_max - 1), std::abs(fs[p].d_min / ex[p].d_min - 1),
                           std::abs(fr - fre), std::abs(ar - are)};
      for (int k = 0; k < 4; ++k) {
        s[k] += e[k];
        m[k] = std::max(m[k], e[k]);
      }
      fr_shape[p % 4] += (fr - fre) / (static_cast<double>(hulls.size()) / 4);
    }
    std::printf("%5d %s |", N, tie > 0 ? "tie " : "lit ");
    for (int k = 0; k < 4; ++k) std::printf(" %7.4f (%7.4f)", s[k] / static_cast<double>(hulls.size()), m[k]);
    std::printf(" | %+.3f %+.3f %+.3f %+.3f | %.4f\n", fr_shape[0], fr_shape[1], fr_shape[2], fr_shape[3], 1e3 * t);
  }
  // The study's FR and AR classes (measure/psd.hpp thresholds): share of the
  // 40 particles in each, per N (tie rule) and for the exact mode. The shapes
  // sit near class edges (half-spheres: FR 0.5, AR 2; ellipsoids: FR 0.58,
  // AR 2.86), as real fragments do, so the shares move with N.
  std::printf("\n# share of particles (%%) in the study's classes; FR <0.4 / 0.4-0.8 / 0.8-0.9 / >=0.9; AR <2 / 2-3 / >=3\n");
  auto classes = [&](const std::vector<FeretResult>& fs, const char* name) {
    std::vector<double> fr(hulls.size()), ar(hulls.size());
    for (size_t p = 0; p < hulls.size(); ++p) frar(hulls[p], fs[p], fr[p], ar[p]);
    const auto fc = class_percent(fr, fr_thresholds()), ac = class_percent(ar, ar_thresholds());
    std::printf("%10s | FR %5.1f %5.1f %5.1f %5.1f | AR %5.1f %5.1f %5.1f\n", name, fc[0], fc[1], fc[2], fc[3], ac[0], ac[1],
                ac[2]);
  };
  for (int N : {15, 30, 60, 120, 500}) {
    const auto dirs = half_sphere_directions(N);
    std::vector<FeretResult> fs;
    for (const auto& h : hulls) fs.push_back(feret_sampled(h.hull, dirs, FeretSampledOptions{0, 0.5, 20.0}));
    classes(fs, ("N=" + std::to_string(N)).c_str());
  }
  classes(ex, "exact");
}

// Times measure_particles on `v` (N = 60, then exact; box only when `box`),
// 1 and 2 threads, wall and CPU seconds (TG_NO_BOX=1 skips the box, the
// slowest by far); TG_DUMP=path writes the labels as
// raw u32 (z, y, x) for bench/measure/skimage_regionprops.py.
void time_measure(const Volume<uint32_t>& v, bool box) {
  if (const char* b = std::getenv("TG_NO_BOX")) box = box && std::atoi(b) == 0;
  if (const char* dump = std::getenv("TG_DUMP")) {
    std::FILE* f = std::fopen(dump, "wb");
    std::fwrite(v.data(), sizeof(uint32_t), static_cast<size_t>(v.size()), f);
    std::fclose(f);
    std::printf("# wrote %s (%lld x %lld x %lld u32)\n", dump, static_cast<long long>(v.shape().nz),
                static_cast<long long>(v.shape().ny), static_cast<long long>(v.shape().nx));
  }
  const char* names[4] = {"N=60, no hull (this session's path)", "N=60 through the CGAL hull (before)", "exact",
                          "N=60 + CGAL oriented box"};
  for (int mode = 0; mode < (box ? 4 : 3); ++mode)
    for (int threads : {1, 2}) {
      ParticleOptions o;
      o.threads = threads;
      o.force_hull = mode == 1;
      o.feret_exact = mode == 2;
      o.oriented_box = mode == 3;
      LabelStatsOptions so;
      so.threads = threads;
      auto cpu_now = [] { return std::clock() / static_cast<double>(CLOCKS_PER_SEC); };
      double t0 = now(), c0 = cpu_now();
      const auto ls = label_stats(v.view(), so);
      const double t_stats = now() - t0, c_stats = cpu_now() - c0;
      t0 = now();
      c0 = cpu_now();
      const auto ps = measure_particles(v.view(), o);
      const double t = now() - t0, cpu = cpu_now() - c0;
      // On a shared machine wall time is noisy; CPU time is what the work
      // costs. Geometry CPU = measure's CPU - label_stats' CPU (the scan);
      // its rate on `threads` cores = threads x particles / geometry CPU.
      const double geo_cpu = std::max(1e-9, cpu - c_stats);
      std::printf("threads %d, %s: %zu particles; measure %.2f s wall / %.2f s CPU; label_stats %.2f s wall / %.2f s CPU; "
                  "overall %.0f particles/s (wall); per-particle geometry %.1f us CPU each = %.0f particles/s on %d core(s)\n",
                  threads, names[mode], ps.size(), t, cpu, t_stats, c_stats, static_cast<double>(ps.size()) / t,
                  1e6 * geo_cpu / static_cast<double>(ps.size()), threads * static_cast<double>(ps.size()) / geo_cpu, threads);
    }
}

void throughput(int64_t n, int grains) {
  // Random spheres, ellipsoids and half-spheres, radius 12-30 voxels; later
  // grains overwrite earlier ones (some are cut, as real fragments are).
  auto v = Volume<uint32_t>::filled(Shape{n, n, n}, 0, Geometry::isotropic_m(1e-5));
  for (int g = 0; g < grains; ++g) {
    const unsigned seed = 9000u + static_cast<unsigned>(g);
    const V3 u = test::random_offset(seed), w = test::random_offset(seed + 77777);
    const double r = 12 + 18 * w[0];
    const V3 c = V3::Constant(r) + u * (static_cast<double>(n) - 2 * r);
    const Eigen::Matrix3d R = test::random_rotation(seed);
    test::Inside in = g % 3 == 0 ? test::sphere(c, r)
                      : g % 3 == 1 ? test::ellipsoid(c, V3(r, 0.7 * r, 0.5 * r), R)
                                   : test::half_sphere(c, r, R.col(0));
    const int64_t lo[3] = {std::max<int64_t>(0, static_cast<int64_t>(c[0] - r) - 1),
                           std::max<int64_t>(0, static_cast<int64_t>(c[1] - r) - 1),
                           std::max<int64_t>(0, static_cast<int64_t>(c[2] - r) - 1)};
    const int64_t hi[3] = {std::min<int64_t>(n, static_cast<int64_t>(c[0] + r) + 2),
                           std::min<int64_t>(n, static_cast<int64_t>(c[1] + r) + 2),
                           std::min<int64_t>(n, static_cast<int64_t>(c[2] + r) + 2)};
    for (int64_t k = lo[0]; k < hi[0]; ++k)
      for (int64_t j = lo[1]; j < hi[1]; ++j)
        for (int64_t i = lo[2]; i < hi[2]; ++i)
          if (in(V3(k + 0.5, j + 0.5, i + 0.5))) v(k, j, i) = static_cast<uint32_t>(g + 1);
  }
  std::printf("# %lld^3 label volume, %d grains drawn\n", static_cast<long long>(n), grains);
  time_measure(v, true);
}

// >= 20 000 small particles: ellipsoids of semi-axes 1.2-3 voxels (about 7
// to 100 voxels each), one per cell of an 8-voxel grid, random sub-cell
// centres and rotations, a fraction of the cells left empty.
void small(int64_t n, int count) {
  auto v = Volume<uint32_t>::filled(Shape{n, n, n}, 0, Geometry::isotropic_m(1e-5));
  const int64_t cells = n / 8;
  uint32_t id = 0;
  for (int64_t c = 0; c < cells * cells * cells && static_cast<int>(id) < count; ++c) {
    const unsigned seed = 5000u + static_cast<unsigned>(c);
    const V3 u = test::random_offset(seed), w = test::random_offset(seed + 99991);
    if (w[2] < 0.25) continue;
    const V3 semi(1.2 + 1.8 * w[0], 1.2 + 1.8 * w[1], 1.2 + 1.2 * w[0] * w[1]);
    const V3 cen(8.0 * static_cast<double>(c / (cells * cells)) + 4 + (u[0] - 0.5) * 1.5,
                 8.0 * static_cast<double>((c / cells) % cells) + 4 + (u[1] - 0.5) * 1.5,
                 8.0 * static_cast<double>(c % cells) + 4 + (u[2] - 0.5) * 1.5);
    const test::Inside in = test::ellipsoid(cen, semi, test::random_rotation(seed));
    bool any = false;
    ++id;
    for (int64_t k = static_cast<int64_t>(cen[0]) - 4; k <= static_cast<int64_t>(cen[0]) + 4; ++k)
      for (int64_t j = static_cast<int64_t>(cen[1]) - 4; j <= static_cast<int64_t>(cen[1]) + 4; ++j)
        for (int64_t i = static_cast<int64_t>(cen[2]) - 4; i <= static_cast<int64_t>(cen[2]) + 4; ++i)
          if (k >= 0 && j >= 0 && i >= 0 && k < n && j < n && i < n && in(V3(k + 0.5, j + 0.5, i + 0.5))) {
            v(k, j, i) = id;
            any = true;
          }
    if (!any) --id;
  }
  std::printf("# %lld^3 label volume, %u small particles drawn\n", static_cast<long long>(n), id);
  time_measure(v, false);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string what = argc > 1 ? argv[1] : "trade";
  if (what == "convention") {
    std::vector<double> l;
    for (int a = 2; a < argc; ++a) l.push_back(std::atof(argv[a]));
    convention(l);
  } else if (what == "trade") {
    trade();
  } else if (what == "small") {
    small(argc > 2 ? std::atoll(argv[2]) : 256, argc > 3 ? std::atoi(argv[3]) : 24000);
  } else if (what == "throughput") {
    throughput(argc > 2 ? std::atoll(argv[2]) : 512, argc > 3 ? std::atoi(argv[3]) : 1000);
  } else {
    std::fprintf(stderr, "usage: measure_feret_bench convention [lambda...] | trade | throughput [n] [grains] | small [n] [count]\n");
    return 2;
  }
  return 0;
}
