// The contact loop on 8 lanes; this file alone is compiled with -mavx512f
// (and without FMA contraction: the same bits as the SSE2 kernel).
#include "dem/contact/pair_kernel.hpp"

namespace tg::dem {
int pair_part_avx512(const PairKernelArgs& a, int part, double* acc) { return pair_part<Lanes8>(a, part, acc); }
}  // namespace tg::dem
