// Grain strength of the sequential breakage model (reference study §4.2):
// a sphere of diameter d survives a stress σ = F_max/d² with probability
//   P_s(d, σ) = exp[−(d/d0)³ (σ/σt0)^m]          (Weibull, with size effect)
// so one strength per sphere is drawn by inversion of a uniform U ∈ (0, 1):
//   σ_strength = σt0 (d0/d)^(3/m) (−ln U)^(1/m).
// Table 1: σt0 = 12 MPa, m = 3; d0 = mean grain size of the initial packing.
// The median strength is σt0 (d0/d)^(3/m) (ln 2)^(1/m): smaller spheres are stronger.
//
// The uniform is a counter-based hash of (seed, sphere key) (splitmix64
// finaliser, Steele, Lea & Flood 2014, doi:10.1145/2714064.2660195): a
// sphere's strength never depends on the number of threads or on the order
// in which spheres were created. A sphere key must be unique and stable for
// the run (intact grains: their grain id; fragment spheres: derived from the
// mother's key and the template slot by fragment_key()). O(1) per draw.
#pragma once
#include <cmath>
#include <cstdint>

namespace tg::dem::breakage {

struct StrengthParams {
  double sigma_t0_Pa = 12e6;    // σt0, strength of a sphere of size d0 (Table 1)
  double weibull_modulus = 3;   // m (Table 1)
  double d0_m = 1e-3;           // reference size d0 = mean size of the grains (set by the scene)
  uint64_t seed = 1;            // run seed
};

// Throws tg::InputError naming the parameter.
void validate(const StrengthParams& p);

namespace detail {
inline uint64_t mix64(uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}
}  // namespace detail

// Uniform in (0, 1), never 0 or 1, a pure function of (seed, key).
inline double strength_uniform(uint64_t seed, uint64_t key) {
  const uint64_t h = detail::mix64(detail::mix64(seed ^ 0x5deece66dULL) + detail::mix64(key));
  return (static_cast<double>(h >> 11) + 0.5) * (1.0 / 9007199254740992.0);  // 2^-53
}

// Key of the sphere in template slot `slot` (0..33) of the fragments of the
// sphere whose key is `mother_key`: a hash, so keys of every generation stay
// distinct with overwhelming probability (2^-64 per pair).
inline uint64_t fragment_key(uint64_t mother_key, int slot) {
  return detail::mix64(mother_key * 0x100000001b3ULL + static_cast<uint64_t>(slot) + 0x9e37ULL);
}

// Strength (Pa) of a sphere of diameter d (m) from a given uniform u ∈ (0, 1).
inline double weibull_strength(const StrengthParams& p, double d, double u) {
  return p.sigma_t0_Pa * std::pow(p.d0_m / d, 3.0 / p.weibull_modulus) * std::pow(-std::log(u), 1.0 / p.weibull_modulus);
}

// Strength (Pa) of the sphere with this key and diameter d (m).
inline double sphere_strength(const StrengthParams& p, uint64_t key, double d) {
  return weibull_strength(p, d, strength_uniform(p.seed, key));
}

// Survival probability P_s(d, σ) of the law above (for tests and reports).
inline double survival_probability(const StrengthParams& p, double d, double sigma) {
  return std::exp(-std::pow(d / p.d0_m, 3.0) * std::pow(sigma / p.sigma_t0_Pa, p.weibull_modulus));
}

}  // namespace tg::dem::breakage
