// Wall-clock seconds for the timings that summaries report (stage_seconds,
// render_s, ...): one definition, so every module times the same way.
#pragma once
#include <chrono>

namespace tg {

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace tg
