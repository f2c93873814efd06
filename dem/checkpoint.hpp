// Checkpoint: the complete engine state in one binary file, so that a run
// restarts and continues bit for bit. Contents: every Particles field (by
// the declared field list, so none can be forgotten), time, step count, the
// walls (top platen position and speed), the pair tangential histories, and
// an opaque text blob for the scene (strain reference, next snapshot...).
// Layout: magic "TGDEMCK4" (the last character is the format version),
// length-prefixed records, then a 64-bit FNV-1a checksum of the records.
// Doubles are stored raw (little-endian machines only; the magic check
// rejects others only by the field-size check). Written atomically (temp +
// rename), so a kill mid-write leaves the previous checkpoint; the records
// stream to the file and are read back in place (no copy of the state in
// memory: at 10^6 spheres a copy is ~300 MB). Loading checks
// magic, version and checksum before parsing: a truncated or bit-flipped file
// is an InputError naming it (tests/apps/crash_restart_test.py).
#pragma once
#include <filesystem>
#include <string>

#include "dem/engine.hpp"

namespace tg::dem {

struct CheckpointState {
  Particles particles;
  double time = 0;
  int64_t steps = 0;
  Walls walls;
  int64_t part_split = -1;  // Engine::part_split()
  Engine::PairHistory history;
  std::string scene;  // scene-defined text
};

void save_checkpoint(const Engine& e, const std::string& scene, const std::filesystem::path& path);
// Throws InputError naming the file when it is not a tomograin checkpoint.
CheckpointState load_checkpoint(const std::filesystem::path& path);
// An engine that continues the saved run (options as given, walls restored).
Engine resume_engine(CheckpointState& s, EngineOptions opt);

}  // namespace tg::dem
