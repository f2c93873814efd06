// Google Benchmark: EDT, markers and watershed throughput (Mvox/s) on a
// packed-ball scene of N^3 voxels (N = 128, 256), grain radius 20 voxels.
// Target for the lead's bench/CMakeLists.txt:
//   add_executable(segmentation_bench segmentation/segmentation_bench.cpp)
//   target_link_libraries(segmentation_bench tomograin::segmentation benchmark::benchmark)
// Run: segmentation_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <random>

#include "segmentation/distance_transform.hpp"
#include "segmentation/markers.hpp"
#include "segmentation/watershed.hpp"

namespace {

// Balls of radius 20 on a jittered grid of pitch 38 (touching neighbours
// with necks), ~55 % solid.
tg::Volume<uint8_t> scene(int64_t n) {
  tg::Volume<uint8_t> m = tg::Volume<uint8_t>::filled(tg::Shape{n, n, n}, 0);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> jit(-2.0, 2.0);
  const double r = 20, pitch = 38;
  for (double cz = 10; cz < double(n) + r; cz += pitch)
    for (double cy = 10; cy < double(n) + r; cy += pitch)
      for (double cx = 10; cx < double(n) + r; cx += pitch) {
        const double z = cz + jit(rng), y = cy + jit(rng), x = cx + jit(rng);
        for (int64_t k = std::max<int64_t>(0, int64_t(z - r)); k < std::min<int64_t>(n, int64_t(z + r) + 1); ++k)
          for (int64_t j = std::max<int64_t>(0, int64_t(y - r)); j < std::min<int64_t>(n, int64_t(y + r) + 1); ++j)
            for (int64_t i = std::max<int64_t>(0, int64_t(x - r)); i < std::min<int64_t>(n, int64_t(x + r) + 1); ++i) {
              const double dz = double(k) - z, dy = double(j) - y, dx = double(i) - x;
              if (dz * dz + dy * dy + dx * dx <= r * r) m(k, j, i) = 1;
            }
      }
  return m;
}

void BM_Edt(benchmark::State& st) {
  const auto m = scene(st.range(0));
  tg::Volume<float> d;
  for (auto _ : st) tg::distance_transform(m, d);
  st.counters["Mvox/s"] = benchmark::Counter(double(m.size()) * double(st.iterations()) / 1e6, benchmark::Counter::kIsRate);
}

void BM_Markers(benchmark::State& st) {
  const auto m = scene(st.range(0));
  tg::Volume<float> d;
  tg::distance_transform(m, d);
  tg::Volume<uint32_t> lab;
  for (auto _ : st) benchmark::DoNotOptimize(tg::find_markers(d, m, lab, {0.7, 26}));
  st.counters["Mvox/s"] = benchmark::Counter(double(m.size()) * double(st.iterations()) / 1e6, benchmark::Counter::kIsRate);
}

void BM_Watershed(benchmark::State& st) {
  const auto m = scene(st.range(0));
  tg::Volume<float> d;
  tg::distance_transform(m, d);
  tg::Volume<uint32_t> markers;
  tg::find_markers(d, m, markers, {0.7, 26});
  tg::Volume<uint32_t> lab;
  for (auto _ : st) {
    st.PauseTiming();
    lab = markers.clone();
    st.ResumeTiming();
    tg::watershed(d, m, lab, {st.range(1) != 0, 26, 4.0});
  }
  st.counters["Mvox/s"] = benchmark::Counter(double(m.size()) * double(st.iterations()) / 1e6, benchmark::Counter::kIsRate);
}

}  // namespace

BENCHMARK(BM_Edt)->Arg(128)->Arg(256)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Markers)->Arg(128)->Arg(256)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Watershed)->Args({128, 1})->Args({256, 1})->Args({256, 0})->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
