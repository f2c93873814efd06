// Counter-based random numbers: the value for (seed, key, n) is a pure hash,
// so a voxel's noise or a grain's fragmentation does not depend on the order
// in which threads visit them (same seed -> same result for any thread count).
// splitmix64 finaliser (Steele, Lea & Flood 2014, doi:10.1145/2714064.2660195).
#pragma once
#include <cmath>
#include <cstdint>
#include <numbers>

namespace tg::synth {

inline uint64_t mix64(uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// Uniform in (0, 1) for stream `key`, draw `n`.
inline double uniform01(uint64_t seed, uint64_t key, uint64_t n) {
  const uint64_t h = mix64(mix64(seed ^ mix64(key)) + n);
  return (static_cast<double>(h >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

// Standard normal (Box–Muller on draws n and n+1).
inline double normal01(uint64_t seed, uint64_t key, uint64_t n) {
  const double u1 = uniform01(seed, key, n), u2 = uniform01(seed, key, n + 1);
  return std::sqrt(-2 * std::log(u1)) * std::cos(2 * std::numbers::pi * u2);
}

// A small sequential generator for setup code (packings): a counter over one key.
class Stream {
 public:
  Stream(uint64_t seed, uint64_t key) : seed_(seed), key_(key) {}
  double uniform() { return uniform01(seed_, key_, n_++); }
  double uniform(double a, double b) { return a + (b - a) * uniform(); }
  double normal() {
    const double v = normal01(seed_, key_, n_);
    n_ += 2;
    return v;
  }

 private:
  uint64_t seed_, key_, n_ = 0;
};

}  // namespace tg::synth
