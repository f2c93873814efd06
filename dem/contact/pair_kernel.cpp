// The SSE2 kernel (every x86-64; the generic one elsewhere) and the choice
// among the kernels at run time.
#include "dem/contact/pair_kernel.hpp"

#include <cstdlib>
#include <string_view>

#include "core/errors.hpp"

namespace tg::dem {

int pair_part_sse2(const PairKernelArgs& a, int part, double* acc) { return pair_part<Lanes2>(a, part, acc); }

namespace {
bool cpu_has(PairKernelIsa isa) {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  // __builtin_cpu_supports also checks that the OS saves the wide registers.
  if (isa == PairKernelIsa::kAvx2) return __builtin_cpu_supports("avx2");
  if (isa == PairKernelIsa::kAvx512) return __builtin_cpu_supports("avx512f");
#endif
  return isa == PairKernelIsa::kSse2;
}

bool built(PairKernelIsa isa) {
  switch (isa) {
    case PairKernelIsa::kSse2: return true;
#if defined(TOMOGRAIN_PAIR_KERNEL_AVX2)
    case PairKernelIsa::kAvx2: return true;
#endif
#if defined(TOMOGRAIN_PAIR_KERNEL_AVX512)
    case PairKernelIsa::kAvx512: return true;
#endif
    default: return false;
  }
}

PairKernelIsa resolve(PairKernelIsa isa) {
  if (isa != PairKernelIsa::kAuto) return isa;
  if (const char* env = std::getenv("TOMOGRAIN_SIMD"); env && *env) {
    const std::string_view e(env);
    if (e == "sse2") return PairKernelIsa::kSse2;
    if (e == "avx2") return PairKernelIsa::kAvx2;
    if (e == "avx512") return PairKernelIsa::kAvx512;
    throw InputError("TOMOGRAIN_SIMD = " + std::string(e) + ": expected sse2, avx2 or avx512");
  }
  for (PairKernelIsa c : {PairKernelIsa::kAvx512, PairKernelIsa::kAvx2})
    if (pair_kernel_available(c)) return c;
  return PairKernelIsa::kSse2;
}
}  // namespace

bool pair_kernel_available(PairKernelIsa isa) {
  if (isa == PairKernelIsa::kAuto) return true;
  return built(isa) && cpu_has(isa);
}

PairPartKernel pair_kernel(PairKernelIsa isa) {
  const PairKernelIsa c = resolve(isa);
  if (!pair_kernel_available(c))
    throw InputError("the " + pair_kernel_name(c) + " contact kernel is not available: " +
                     (built(c) ? "this CPU lacks the instructions" : "this build was compiled without it"));
  switch (c) {
#if defined(TOMOGRAIN_PAIR_KERNEL_AVX2)
    case PairKernelIsa::kAvx2: return pair_part_avx2;
#endif
#if defined(TOMOGRAIN_PAIR_KERNEL_AVX512)
    case PairKernelIsa::kAvx512: return pair_part_avx512;
#endif
    default: return pair_part_sse2;
  }
}

std::string pair_kernel_name(PairKernelIsa isa) {
  switch (isa == PairKernelIsa::kAuto ? resolve(isa) : isa) {
    case PairKernelIsa::kAvx2: return "avx2 (4 lanes)";
    case PairKernelIsa::kAvx512: return "avx512 (8 lanes)";
    default: return "sse2 (2 lanes)";
  }
}

}  // namespace tg::dem
