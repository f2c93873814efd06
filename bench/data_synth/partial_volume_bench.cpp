// Speed and speed-vs-accuracy of the partial-volume kernel (data_synth/partial_volume.hpp).
//   SphereSurfaceVoxel/R   cost of one sphere surface voxel (the exact integral)
//   HalfCutVoxel/depth     cost of a half-sphere rim voxel vs subdivision depth, with
//                          its mean absolute error against depth 6 as a counter
//   RenderGrain/R          whole renderer on one grain (voxels/s)
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "data_synth/partial_volume.hpp"
#include "data_synth/render.hpp"

using namespace tg::synth;

namespace {
// Surface voxels of a sphere (0 < coverage < 1).
std::vector<std::array<int64_t, 3>> surface_voxels(const Particle& p, int64_t n) {
  std::vector<std::array<int64_t, 3>> out;
  for (int64_t k = 0; k < n; ++k)
    for (int64_t j = 0; j < n; ++j)
      for (int64_t i = 0; i < n; ++i) {
        const double v = voxel_coverage(p, k, j, i);
        if (v > 0 && v < 1) out.push_back({k, j, i});
      }
  return out;
}
}  // namespace

static void SphereSurfaceVoxel(benchmark::State& st) {
  const double R = static_cast<double>(st.range(0));
  const int64_t n = static_cast<int64_t>(2 * R + 4);
  const Sphere s{{R + 1.3, R + 1.6, R + 1.1}, R};
  const auto vox = surface_voxels(make_grain(1, s.c, s.r), n);
  size_t q = 0;
  double sink = 0;
  for (auto _ : st) {
    const auto& v = vox[q++ % vox.size()];
    sink += sphere_box_volume(s, {double(v[0]), double(v[1]), double(v[2])}, {v[0] + 1.0, v[1] + 1.0, v[2] + 1.0});
  }
  benchmark::DoNotOptimize(sink);
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(SphereSurfaceVoxel)->Arg(2)->Arg(10)->Arg(50);

static void HalfCutVoxel(benchmark::State& st) {
  const int depth = static_cast<int>(st.range(0));
  const Particle half = make_cap(1, Kind::half, 1, {{21.3, 20.6, 20.1}, 20}, {0.3, 0.5, 0.8}, 0.75);
  std::vector<std::array<int64_t, 3>> rim;
  for (const auto& v : surface_voxels(half, 44)) {
    const Particle whole = make_grain(2, {21.3, 20.6, 20.1}, 20);
    const double a = voxel_coverage(half, v[0], v[1], v[2]), b = voxel_coverage(whole, v[0], v[1], v[2]);
    if (b > 0 && b < 1 && std::abs(a - b) > 1e-9) rim.push_back(v);  // cut by sphere and plane
  }
  double err = 0;
  for (const auto& v : rim)
    err += std::abs(voxel_coverage(half, v[0], v[1], v[2], {8, depth}) - voxel_coverage(half, v[0], v[1], v[2], {8, 6}));
  size_t q = 0;
  double sink = 0;
  for (auto _ : st) {
    const auto& v = rim[q++ % rim.size()];
    sink += voxel_coverage(half, v[0], v[1], v[2], {8, depth});
  }
  benchmark::DoNotOptimize(sink);
  st.counters["mean_abs_err"] = err / static_cast<double>(rim.size());
  st.counters["rim_voxels"] = static_cast<double>(rim.size());
}
BENCHMARK(HalfCutVoxel)->DenseRange(0, 5);

static void RenderGrain(benchmark::State& st) {
  const double R = static_cast<double>(st.range(0));
  const int64_t n = static_cast<int64_t>(2 * R + 4);
  const std::vector<Particle> ps{make_grain(1, {R + 1.3, R + 1.6, R + 1.1}, R)};
  for (auto _ : st) benchmark::DoNotOptimize(render(ps, tg::Shape{n, n, n}).solid.data());
  st.SetItemsProcessed(st.iterations() * n * n * n);
}
BENCHMARK(RenderGrain)->Arg(10)->Arg(25)->Arg(55)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
