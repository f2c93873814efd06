// The contact kernels on 8 lanes; this file alone is compiled with
// -mavx512f (and without FMA contraction: the same bits as the SSE2 kernels).
#include "dem/contact/kernels.hpp"

namespace tg::dem {
ContactKernels kernels_avx512() { return kernels_for<Lanes8>(); }
}  // namespace tg::dem
