#include "core/memory.hpp"

#include <sys/mman.h>
#include <unistd.h>
#include <omp.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <mutex>
#include <sstream>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/errors.hpp"

namespace tg {
namespace {

int64_t meminfo_field(const char* path, const std::string& key) {
  std::ifstream f(path);
  std::string line;
  while (std::getline(f, line)) {
    if (line.rfind(key, 0) == 0) {
      std::istringstream is(line.substr(key.size()));
      int64_t kb = 0;
      is >> kb;
      return kb * 1024;
    }
  }
  return -1;
}

int64_t cgroup_limit_bytes() {
  // cgroup v2, then v1; "max" or absurd values mean no limit.
  for (const char* p : {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
    std::ifstream f(p);
    std::string s;
    if (f >> s && s != "max") {
      char* end = nullptr;
      const long long v = std::strtoll(s.c_str(), &end, 10);
      if (end && *end == '\0' && v > 0 && v < (1LL << 60)) return v;
    }
  }
  return -1;
}

}  // namespace

int64_t available_memory_bytes() {
  int64_t avail = meminfo_field("/proc/meminfo", "MemAvailable:");
  if (avail < 0) avail = std::numeric_limits<int64_t>::max();
  if (const int64_t cg = cgroup_limit_bytes(); cg > 0 && cg < avail) avail = cg;
  if (const char* env = std::getenv("TOMOGRAIN_MEMORY_LIMIT")) {
    if (const int64_t lim = parse_byte_size(env); lim > 0 && lim < avail) avail = lim;
  }
  return avail;
}

void check_allocation(int64_t bytes, const std::string& what) {
  if (bytes < 0) throw ResourceError(what + ": negative allocation size");
  // Small requests are not checked: reading /proc/meminfo costs ~20 us, and
  // stages that allocate a box per grain (the face caps: thousands a scan)
  // spent 1.5 % of a 256^3 segmentation's CPU time on it. What they ask
  // for cannot decide whether a scan fits; a failed one still throws
  // (allocate_large).
  constexpr int64_t kCheckedFrom = int64_t(16) << 20;
  if (bytes < kCheckedFrom) return;
  const int64_t avail = available_memory_bytes();
  if (bytes > avail)
    throw ResourceError(what + " needs " + human_bytes(static_cast<double>(bytes)) + " but only " +
                        human_bytes(static_cast<double>(avail)) + " of memory is available");
}

int64_t parse_byte_size(const std::string& text) {
  const char* s = text.c_str();
  char* end = nullptr;
  const double v = std::strtod(s, &end);
  if (end == s || !(v > 0) || !std::isfinite(v)) return -1;
  std::string unit(end);
  while (!unit.empty() && unit.front() == ' ') unit.erase(unit.begin());
  for (char& c : unit) c = char(std::toupper(static_cast<unsigned char>(c)));
  if (unit.empty() || unit == "B") return v < 1 ? -1 : static_cast<int64_t>(v);
  const std::string prefixes = "KMGT";
  const size_t p = prefixes.find(unit[0]);
  if (p == std::string::npos) return -1;
  const std::string rest = unit.substr(1);
  double base = 0;
  if (rest.empty() || rest == "IB") base = 1024.0;  // K, KiB: binary (as the environment variable always took them)
  else if (rest == "B") base = 1000.0;             // KB, GB: decimal
  else return -1;
  const double bytes = v * std::pow(base, double(p + 1));
  if (bytes < 1 || bytes > 9.2e18) return -1;
  return static_cast<int64_t>(bytes);
}

int64_t peak_rss_bytes() { return meminfo_field("/proc/self/status", "VmHWM:"); }

bool reset_peak_rss() {
  std::FILE* f = std::fopen("/proc/self/clear_refs", "w");
  if (!f) return false;
  const bool ok = std::fputs("5", f) >= 0;
  return std::fclose(f) == 0 && ok;
}

std::string human_bytes(double b) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  int u = 0;
  while (b >= 1024.0 && u < 6) { b /= 1024.0; ++u; }
  char buf[32];
  std::snprintf(buf, sizeof buf, u == 0 ? "%.0f %s" : "%.2f %s", b, units[u]);
  return buf;
}

namespace {

// Freed large blocks kept for the next request of their size. A
// segmentation allocates and frees volumes of one shape stage after stage;
// each fresh block costs the kernel a page fault and a cleared page for
// every page first touched (at 256^3, ~0.2 s of CPU time of a ~2 s run).
// A cached block is reused for a request of its size (rounded to 2 MiB:
// volumes of one shape and type); any request the cache cannot serve
// empties the cache first, so idle blocks never sit beside a new large
// block; only smaller allocations (vectors, under 2 MiB) can meet them
// resident, until the next such request or release_idle_blocks() (256^3
// segmentation: peak 8.49 -> 8.65 B/voxel; 512^3 7.21 -> 7.23). (Reusing
// blocks up to 5/4 of the request, their excess pages given back, was as
// fast and raised the 256^3 peak to 8.72.) Not under AddressSanitizer
// (memory.hpp kLargeBlockCache).
constexpr bool kCacheBlocks = kLargeBlockCache;
constexpr size_t kHuge = size_t(2) << 20;
std::mutex block_mutex;
std::unordered_map<void*, size_t> live_blocks;      // large blocks handed out: their sizes
std::vector<std::pair<void*, size_t>> idle_blocks;  // freed large blocks kept

// A fresh block of >= 16 MiB has its pages faulted in right away, by all
// threads, 2 MiB at a time (dynamic schedule): the kernel clears each page
// on its first touch, and left to the first pass over the block, that cost
// falls on whichever thread's static share is slow to fault: on the 2-core
// VM one thread cleared most of a 64 MB distance map while the other waited
// at the barrier (perf: 0.1 s of one thread idle in a 0.75 s segmentation
// of 256^3). Interleaved medians, 256^3: EDT 0.068 -> 0.061 s, markers
// 0.035 -> 0.029, total 0.781 -> 0.746 (15 runs each; 2-4 % in three such
// comparisons); 512^3 unchanged; peak 8.72 -> 8.76 B/voxel. Every block of
// that size is written whole (volumes; the pore filter's run arrays), so
// no page is made resident that would not be.
constexpr size_t kPrefaultBytes = size_t(16) << 20;
void prefault(void* p, size_t bytes) {
  const int64_t chunks = int64_t(bytes / kHuge);
#pragma omp parallel for schedule(dynamic, 1) if (!omp_in_parallel())
  for (int64_t c = 0; c < chunks; ++c) {
    char* q = static_cast<char*>(p) + size_t(c) * kHuge;
    if (madvise(q, kHuge, MADV_POPULATE_WRITE) != 0)  // Linux >= 5.14; else one write a page
      for (size_t i = 0; i < kHuge; i += 4096) static_cast<volatile char*>(q)[i] = 0;
  }
}

}  // namespace

void* allocate_large(size_t bytes) {
  if (bytes < kHuge) {
    void* p = std::malloc(bytes ? bytes : 1);
    if (!p) throw ResourceError("out of memory allocating " + human_bytes(double(bytes)));
    return p;
  }
  const size_t rounded = (bytes + kHuge - 1) / kHuge * kHuge;
  if (kCacheBlocks) {
    std::lock_guard<std::mutex> lock(block_mutex);
    const auto it = std::find_if(idle_blocks.begin(), idle_blocks.end(),
                                 [rounded](const auto& b) { return b.second == rounded; });
    if (it != idle_blocks.end()) {
      void* p = it->first;
      live_blocks[p] = rounded;  // first: if this throws, the block stays idle
      idle_blocks.erase(it);
      return p;
    }
    for (const auto& [p, have] : idle_blocks) std::free(p);
    idle_blocks.clear();
  }
  void* p = nullptr;
  if (posix_memalign(&p, kHuge, rounded) != 0 || !p)
    throw ResourceError("out of memory allocating " + human_bytes(double(bytes)));
  madvise(p, rounded, MADV_HUGEPAGE);  // a hint: ignored where THP is off
  if (rounded >= kPrefaultBytes) prefault(p, rounded);
  if (kCacheBlocks) {
    std::lock_guard<std::mutex> lock(block_mutex);
    try {
      live_blocks[p] = rounded;
    } catch (...) {  // not recorded: free_large then gives it back instead of keeping it
    }
  }
  return p;
}

void release_idle_blocks() noexcept {
  if (!kCacheBlocks) return;
  std::lock_guard<std::mutex> lock(block_mutex);
  for (const auto& [p, have] : idle_blocks) std::free(p);
  idle_blocks.clear();
}

void free_large(void* p) noexcept {
  if (!p) return;
  if (kCacheBlocks) {
    std::lock_guard<std::mutex> lock(block_mutex);
    if (const auto it = live_blocks.find(p); it != live_blocks.end()) {
      try {
        idle_blocks.emplace_back(p, it->second);
        live_blocks.erase(it);
        return;
      } catch (...) {  // no room to keep it: give it back
        live_blocks.erase(it);
      }
    }
  }
  std::free(p);
}

void discard_pages(void* p, size_t bytes) noexcept {
  const size_t page = size_t(sysconf(_SC_PAGESIZE));
  const uintptr_t a = (reinterpret_cast<uintptr_t>(p) + page - 1) / page * page;
  const uintptr_t b = (reinterpret_cast<uintptr_t>(p) + bytes) / page * page;
  if (b > a) madvise(reinterpret_cast<void*>(a), b - a, MADV_DONTNEED);  // a hint: nothing lost if it fails
}

}  // namespace tg
