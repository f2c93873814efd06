// The contact kernels on 4 lanes; this file alone is compiled with -mavx2
// (and without FMA contraction: the same bits as the SSE2 kernels).
#include "dem/contact/kernels.hpp"

namespace tg::dem {
ContactKernels kernels_avx2() { return kernels_for<Lanes4>(); }
}  // namespace tg::dem
