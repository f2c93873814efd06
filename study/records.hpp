// What makes a study's step "done": a record DIR/.run/STEP.json, written
// last (atomically) after the step's outputs, holding the step's key, a hash
// of everything the outputs depend on (the command's arguments, the content
// of its input files, the keys of the steps it reads, the program version).
// A step whose record is missing or holds another key runs again from
// scratch; a kill at any moment therefore leaves either a record that is true
// or none, never a half-written output taken for a finished one.
#pragma once
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace tg::study {

// Content hashes (XXH3-64, hex) of input files or folders (a TIFF slice
// folder: names and bytes of its files in order). Hashing a 3.6 GB scan takes
// seconds, so the hashes are kept in DIR/.run/hashes.json by path, size and
// modification time, and a file is read again only when one of those changes.
class HashCache {
 public:
  explicit HashCache(std::filesystem::path run_dir);  // DIR/.run
  std::string hash(const std::filesystem::path& p);
  void save() const;  // best effort: the cache only saves time

 private:
  struct Entry {
    std::string stamp, hash;
  };
  std::filesystem::path file_;
  std::map<std::string, Entry> entries_;
  bool changed_ = false;
};

// XXH3-64 of a list of strings (each followed by a NUL), hex.
std::string hash_strings(const std::vector<std::string>& parts);

// The step's record, if any: its key ("" when absent or unreadable).
std::string recorded_key(const std::filesystem::path& record);
void write_record(const std::filesystem::path& record, const std::string& step, const std::string& key,
                  double seconds);

// An exclusive lock on DIR/.run/STEP.lock (flock), held while the step runs,
// so that two processes never run one step at once (InputError if another
// holds it). Released by the destructor or when the process dies.
class StepLock {
 public:
  explicit StepLock(const std::filesystem::path& lock_file);
  ~StepLock();
  StepLock(const StepLock&) = delete;
  StepLock& operator=(const StepLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace tg::study
