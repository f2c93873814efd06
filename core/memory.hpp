// Check an allocation against the memory this machine can still give, so a
// too-large request fails with a clear message instead of the OOM killer.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <type_traits>

namespace tg {

// Bytes of memory available now (MemAvailable from /proc/meminfo; the cgroup
// limit if one is set and lower). Returns INT64_MAX when neither can be read.
int64_t available_memory_bytes();

// Throws ResourceError naming `what` if `bytes` exceeds what is available
// (requests from 16 MiB up; smaller ones are not checked).
// The environment variable TOMOGRAIN_MEMORY_LIMIT (bytes, accepts K/M/G
// suffix) lowers the limit, which tests and shared machines use.
void check_allocation(int64_t bytes, const std::string& what);

// A byte count from text: a plain number of bytes ("1073741824", "512B"),
// or a number with a binary unit ("16GiB", "16G", "1.5 MiB": powers of
// 1024) or a decimal one ("16GB": powers of 1000); K, M, G, T, any case.
// Returns -1 when the text is not such a size (the caller names the option).
int64_t parse_byte_size(const std::string& text);

// Peak resident set size of this process so far (VmHWM), in bytes.
int64_t peak_rss_bytes();

// Starts a new peak: VmHWM drops to the current resident size (Linux >= 4.0:
// "5" written to /proc/self/clear_refs), so that peak_rss_bytes() then reports
// the peak of what follows, e.g. one stage of a chained command. False where
// the kernel refuses; the peak then stays the whole process's.
bool reset_peak_rss();

std::string human_bytes(double bytes);

// Storage for large arrays (volumes): aligned to 2 MiB and, from 2 MiB up,
// marked for transparent huge pages (madvise), because first touching fresh
// memory in 4 KiB pages costs more than the work on it in several stages
// (measured on the CI VM: 2.9 s per GiB). Blocks from 2 MiB up that are
// freed are kept for a later request of about their size (fresh pages still
// cost a fault and a clearing each; memory.cpp says how the peak is kept).
// Uninitialised. Never returns null: throws ResourceError. Release with
// free_large (or LargeFree).
void* allocate_large(size_t bytes);
// Whether freed blocks are kept: not under AddressSanitizer, which must see
// every block freed. GCC says so by __SANITIZE_ADDRESS__, clang (the fuzz
// build) by __has_feature only: a block cached there was reported as leaked
// at exit, now and then (which blocks end in the cache depends on which
// inputs the available-memory check lets through).
#if defined(__SANITIZE_ADDRESS__)
#define TG_ADDRESS_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define TG_ADDRESS_SANITIZER 1
#endif
#endif
#if defined(TG_ADDRESS_SANITIZER)
inline constexpr bool kLargeBlockCache = false;
#else
inline constexpr bool kLargeBlockCache = true;
#endif
void free_large(void* p) noexcept;
// Gives the kept blocks back to the system: called where a long stage ends
// (a segmentation), so that what follows (measuring, writing) does not hold
// them resident beside its own memory.
void release_idle_blocks() noexcept;
// Gives the whole pages inside [p, p + bytes) back to the system; the
// range stays allocated and reads as zeros if touched again. For the unused
// tail of a buffer that a smaller result took over (see Volume::reuse_as).
void discard_pages(void* p, size_t bytes) noexcept;
struct LargeFree {
  void operator()(void* p) const noexcept { free_large(p); }
};
// An uninitialised array of n plain values from allocate_large (a scratch
// array as large as a volume reuses a freed volume's pages, and the reverse).
template <class T>
using LargeArray = std::unique_ptr<T[], LargeFree>;
template <class T>
LargeArray<T> large_array(size_t n) {
  static_assert(std::is_trivially_default_constructible_v<T> && std::is_trivially_destructible_v<T>);
  return LargeArray<T>(static_cast<T*>(allocate_large(n * sizeof(T))));
}

}  // namespace tg
