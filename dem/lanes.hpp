// Lanes of doubles (GCC/Clang vector extension): Lanes2 in one SSE2
// register, Lanes4 (AVX) and Lanes8 (AVX-512) where the file is compiled
// for them, so that the contact kernels (dem/contact/kernels.hpp) compute
// 2, 4 or 8 contacts with each instruction: the contact law is a chain of
// dependent square roots and divisions whose latency, not the arithmetic,
// bounds the loop. Lane arithmetic is IEEE double arithmetic, lane by lane:
// a contact gets the same bits in any lane, at any width and from the
// scalar form (the kernels' files are compiled without FMA contraction).
//
// The helpers below have a double overload too, so that one template of the
// law (dem/contact/hertz_mindlin.hpp) serves a double and any lane type.
#pragma once
#include <cmath>
#include <cstdint>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__AVX__)
#include <immintrin.h>
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
// Lanes' values base[idx[l]]; an index vector is the mask type (64-bit
// integers per lane). Gather instructions where the lanes are AVX2/AVX-512.
inline Lanes2 lane_gather(const double* base, Mask2 idx) { return Lanes2{base[idx[0]], base[idx[1]]}; }
inline Mask2 lane_gather(const int64_t* base, Mask2 idx) { return Mask2{base[idx[0]], base[idx[1]]}; }
// base[idx[l]] = v[l] for the lanes where `on` is set (distinct indices).
template <class V, class IV>
inline void lane_scatter(double* base, IV idx, V v, IV on) {
  for (int l = 0; l < int(sizeof(V) / sizeof(double)); ++l)
    if (on[l]) base[idx[l]] = v[l];
}
// Writes the lanes of v where `on` is set to out[0], out[1], ... in lane
// order and returns how many; may write up to the lane count (out has room).
template <class IV>
inline int lane_compress(int64_t* out, IV v, IV on) {
  int c = 0;
  for (int l = 0; l < int(sizeof(IV) / sizeof(int64_t)); ++l) {
    out[c] = v[l];
    c += int(on[l] != 0);
  }
  return c;
}
inline Lanes2 lane_sqrt(Lanes2 x) {
#if defined(__SSE2__)
  return Lanes2(_mm_sqrt_pd(__m128d(x)));
#else
  return Lanes2{std::sqrt(x[0]), std::sqrt(x[1])};
#endif
}

// Four and eight doubles: one AVX or AVX-512 register. Declared only where
// the file is compiled for that instruction set (dem/contact/kernels_*.cpp).
#if defined(__AVX__)
using Lanes4 = double __attribute__((vector_size(32)));
using Mask4 = decltype(Lanes4{} > Lanes4{});
inline Lanes4 select(Mask4 m, Lanes4 a, Lanes4 b) { return m ? a : b; }
inline bool any(Mask4 m) { return _mm256_movemask_pd(__m256d(m)) != 0; }
inline Lanes4 lane_sqrt(Lanes4 x) { return Lanes4(_mm256_sqrt_pd(__m256d(x))); }
#if defined(__AVX2__)
inline Lanes4 lane_gather(const double* base, Mask4 idx) { return Lanes4(_mm256_i64gather_pd(base, __m256i(idx), 8)); }
inline Mask4 lane_gather(const int64_t* base, Mask4 idx) {
  return Mask4(_mm256_i64gather_epi64(reinterpret_cast<const long long*>(base), __m256i(idx), 8));
}
#endif
#endif
#if defined(__AVX512F__)
using Lanes8 = double __attribute__((vector_size(64)));
using Mask8 = decltype(Lanes8{} > Lanes8{});
inline Lanes8 select(Mask8 m, Lanes8 a, Lanes8 b) { return m ? a : b; }
inline bool any(Mask8 m) {
  const __m512i v = __m512i(m);
  return _mm512_test_epi64_mask(v, v) != 0;
}
// The zero-masking form with every lane kept: _mm512_sqrt_pd starts from an
// "undefined" vector that GCC 12 reports as maybe uninitialised.
inline Lanes8 lane_sqrt(Lanes8 x) { return Lanes8(_mm512_maskz_sqrt_pd(__mmask8(0xFF), __m512d(x))); }
// (The masked forms from zero: the plain ones start from an "undefined" vector, as above.)
inline Lanes8 lane_gather(const double* base, Mask8 idx) {
  return Lanes8(_mm512_mask_i64gather_pd(_mm512_setzero_pd(), __mmask8(0xFF), __m512i(idx), base, 8));
}
inline Mask8 lane_gather(const int64_t* base, Mask8 idx) {
  return Mask8(_mm512_mask_i64gather_epi64(_mm512_setzero_si512(), __mmask8(0xFF), __m512i(idx), base, 8));
}
inline void lane_scatter(double* base, Mask8 idx, Lanes8 v, Mask8 on) {
  _mm512_mask_i64scatter_pd(base, _mm512_test_epi64_mask(__m512i(on), __m512i(on)), __m512i(idx), __m512d(v), 8);
}
// The register form of the compress and a full store (the memory form is
// slow on some CPUs).
inline int lane_compress(int64_t* out, Mask8 v, Mask8 on) {
  const __mmask8 k = _mm512_test_epi64_mask(__m512i(on), __m512i(on));
  _mm512_storeu_si512(out, _mm512_maskz_compress_epi64(k, __m512i(v)));
  return __builtin_popcount(unsigned(k));
}
#endif

}  // namespace tg::dem
