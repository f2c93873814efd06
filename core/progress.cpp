#include "core/progress.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>

namespace tg {

bool Progress::enabled() {
  return ::isatty(STDERR_FILENO) && std::getenv("TOMOGRAIN_QUIET") == nullptr && std::getenv("CI") == nullptr;
}

Progress::Progress(std::string label, double total, std::string unit)
    : label_(std::move(label)), unit_(std::move(unit)), total_(total), on_(enabled()),
      start_(std::chrono::steady_clock::now()), last_draw_(start_) {}

Progress::~Progress() { finish(); }

void Progress::update(double done) {
  done_ = done;
  if (!on_) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  draw(false);
}

void Progress::finish() {
  if (finished_) return;
  finished_ = true;
  if (!on_) return;
  done_ = total_;
  draw(true);
  std::fputc('\n', stderr);
}

void Progress::draw(bool final) {
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double frac = total_ > 0 ? std::min(1.0, done_ / total_) : 1.0;
  const int width = 30, filled = static_cast<int>(frac * width);
  std::string bar(filled, '#');
  bar.resize(width, '.');
  const double eta = frac > 0 && !final ? elapsed * (1 - frac) / frac : 0;
  std::fprintf(stderr, "\r%-20s [%s] %5.1f%%  %6.1fs elapsed", label_.c_str(), bar.c_str(), 100 * frac, elapsed);
  if (!final) std::fprintf(stderr, "  ETA %6.1fs", eta);
  std::fflush(stderr);
}

}  // namespace tg
