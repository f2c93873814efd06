// Two doubles in one SSE2 register (GCC/Clang vector extension), so that the
// contact loop computes two contacts with each instruction: the contact law
// is a chain of dependent square roots and divisions whose latency, not the
// arithmetic, bounds the loop; two lanes halve the chains per contact.
// Lane arithmetic is IEEE double arithmetic, lane by lane: a contact gets
// the same bits in either lane and from the scalar form (x86-64 has no FMA
// in its baseline, so nothing is contracted differently).
//
// The helpers below have a double overload too, so that one template of the
// law (dem/contact/hertz_mindlin.hpp) serves walls (double) and pairs (Lanes2).
#pragma once
#include <cmath>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace tg::dem {

using Lanes2 = double __attribute__((vector_size(16)));
// What a comparison of Lanes2 gives: all ones or zero per lane.
using Mask2 = decltype(Lanes2{} > Lanes2{});

inline double select(bool m, double a, double b) { return m ? a : b; }
inline Lanes2 select(Mask2 m, Lanes2 a, Lanes2 b) { return m ? a : b; }
inline bool any(bool m) { return m; }
inline bool any(Mask2 m) { return (m[0] | m[1]) != 0; }
inline double lane_sqrt(double x) { return std::sqrt(x); }
inline Lanes2 lane_sqrt(Lanes2 x) {
#if defined(__SSE2__)
  return Lanes2(_mm_sqrt_pd(__m128d(x)));
#else
  return Lanes2{std::sqrt(x[0]), std::sqrt(x[1])};
#endif
}

}  // namespace tg::dem
