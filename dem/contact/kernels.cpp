// The SSE2 kernels (every x86-64; the generic ones elsewhere) and the
// choice among the kernels at run time.
#include "dem/contact/kernels.hpp"

#include <cstdlib>
#include <string_view>

#include "core/errors.hpp"

namespace tg::dem {

ContactKernels kernels_sse2() { return kernels_for<Lanes2>(); }

namespace {
bool cpu_has(KernelIsa isa) {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  // __builtin_cpu_supports also checks that the OS saves the wide registers.
  if (isa == KernelIsa::kAvx2) return __builtin_cpu_supports("avx2");
  if (isa == KernelIsa::kAvx512) return __builtin_cpu_supports("avx512f");
#endif
  return isa == KernelIsa::kSse2;
}

bool built(KernelIsa isa) {
  switch (isa) {
    case KernelIsa::kSse2: return true;
#if defined(TOMOGRAIN_KERNELS_AVX2)
    case KernelIsa::kAvx2: return true;
#endif
#if defined(TOMOGRAIN_KERNELS_AVX512)
    case KernelIsa::kAvx512: return true;
#endif
    default: return false;
  }
}

KernelIsa resolve(KernelIsa isa) {
  if (isa != KernelIsa::kAuto) return isa;
  if (const char* env = std::getenv("TOMOGRAIN_SIMD"); env && *env) {
    const std::string_view e(env);
    if (e == "sse2") return KernelIsa::kSse2;
    if (e == "avx2") return KernelIsa::kAvx2;
    if (e == "avx512") return KernelIsa::kAvx512;
    throw InputError("TOMOGRAIN_SIMD = " + std::string(e) + ": expected sse2, avx2 or avx512");
  }
  for (KernelIsa c : {KernelIsa::kAvx512, KernelIsa::kAvx2})
    if (kernels_available(c)) return c;
  return KernelIsa::kSse2;
}
}  // namespace

bool kernels_available(KernelIsa isa) {
  if (isa == KernelIsa::kAuto) return true;
  return built(isa) && cpu_has(isa);
}

ContactKernels contact_kernels(KernelIsa isa) {
  const KernelIsa c = resolve(isa);
  if (!kernels_available(c))
    throw InputError("the " + kernels_name(c) + " contact kernels are not available: " +
                     (built(c) ? "this CPU lacks the instructions" : "this build was compiled without them"));
  switch (c) {
#if defined(TOMOGRAIN_KERNELS_AVX2)
    case KernelIsa::kAvx2: return kernels_avx2();
#endif
#if defined(TOMOGRAIN_KERNELS_AVX512)
    case KernelIsa::kAvx512: return kernels_avx512();
#endif
    default: return kernels_sse2();
  }
}

std::string kernels_name(KernelIsa isa) {
  switch (isa == KernelIsa::kAuto ? resolve(isa) : isa) {
    case KernelIsa::kAvx2: return "avx2 (4 lanes)";
    case KernelIsa::kAvx512: return "avx512 (8 lanes)";
    default: return "sse2 (2 lanes)";
  }
}

}  // namespace tg::dem
