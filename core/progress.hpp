// Progress of long jobs: a one-line bar with rate and ETA on a terminal,
// nothing at all when stderr is not a terminal (pipes, CI) or when
// TOMOGRAIN_QUIET is set. Call update() from one thread (the master of an
// OpenMP loop, or between chunks); it redraws at most ~10 times a second.
#pragma once
#include <chrono>
#include <cstdint>
#include <string>

namespace tg {

class Progress {
 public:
  Progress(std::string label, double total, std::string unit = "");
  ~Progress();
  void update(double done);
  void set_label(std::string label) { label_ = std::move(label); }
  void finish();
  static bool enabled();

 private:
  void draw(bool final);
  std::string label_, unit_;
  double total_, done_ = 0;
  bool on_, finished_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace tg
