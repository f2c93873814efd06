// The contact loop on 4 lanes; this file alone is compiled with -mavx2
// (and without FMA contraction: the same bits as the SSE2 kernel).
#include "dem/contact/pair_kernel.hpp"

namespace tg::dem {
int pair_part_avx2(const PairKernelArgs& a, int part, double* acc) { return pair_part<Lanes4>(a, part, acc); }
}  // namespace tg::dem
