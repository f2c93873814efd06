// Shared by the libFuzzer harnesses: each input is written to a file and fed
// through the same entry point the CLI uses (read_volume, Config::from_file,
// read_csv), because the readers take paths. Library errors (tg::InputError,
// ResourceError, UsageError) are the expected answer to bad bytes; anything
// else (a crash, a sanitizer report, another exception) is a finding.
#pragma once
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <string>

#include "core/errors.hpp"
#include "core/io/volume_io.hpp"

namespace tg::fuzz {

// A per-process scratch folder in /dev/shm (memory) when available.
inline std::string scratch(const std::string& name) {
  static const std::string dir = [] {
    std::string d = (access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp") + std::string("/tg_fuzz_") +
                    std::to_string(getpid());
    std::system(("mkdir -p " + d).c_str());
    return d;
  }();
  return dir + "/" + name;
}

inline void write_file(const std::string& path, const uint8_t* data, size_t size) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
}

// Inputs may announce absurd sizes: the allocation check must refuse them
// cleanly, well below libFuzzer's RSS limit.
inline void limit_memory() { setenv("TOMOGRAIN_MEMORY_LIMIT", "256M", 1); }

// How the volume harnesses read: no progress output, and NaN/Inf voxels
// accepted, so that float inputs go on through the whole reader (their
// refusal is the commands' policy, tested in tests/apps).
inline tg::ReadOptions volume_read_options() {
  tg::ReadOptions ro;
  ro.progress = false;
  ro.nonfinite = tg::NonFinite::allow;
  return ro;
}

template <class F>
void expect_clean(F&& f) {
  try {
    f();
  } catch (const tg::InputError&) {
  } catch (const tg::ResourceError&) {
  } catch (const tg::UsageError&) {
  }
  // Any other exception escapes, and libFuzzer reports it as a crash.
}

}  // namespace tg::fuzz
