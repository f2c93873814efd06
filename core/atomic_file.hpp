// Atomic outputs: write to a temporary beside the target, rename on success.
// An error (exception, early return) leaves no half-written output behind:
// the destructor removes the temporary unless commit() ran.
//
//   AtomicPath out("labels.h5");
//   write_everything(out.temp());   // may throw
//   out.commit();                   // rename(temp, "labels.h5")
#pragma once
#include <filesystem>
#include <string>
#include <string_view>

namespace tg {

class AtomicPath {
 public:
  explicit AtomicPath(std::filesystem::path target);
  ~AtomicPath();
  AtomicPath(const AtomicPath&) = delete;
  AtomicPath& operator=(const AtomicPath&) = delete;

  const std::filesystem::path& temp() const { return temp_; }
  const std::filesystem::path& target() const { return target_; }
  // Renames the temporary (file or folder) onto the target, replacing it.
  void commit();

 private:
  std::filesystem::path target_, temp_;
  bool committed_ = false;
};

// Removes the temporaries that AtomicPath left in `dir` (not recursive) when
// its process was killed before commit or destructor ran (".NAME.tmp-PID-N",
// PID no longer running): a restarted run would otherwise carry them. Returns
// how many it removed; a temporary of a live process is left alone.
int remove_stale_temporaries(const std::filesystem::path& dir);

// The one writer of small text or binary files (JSON, CSV, XDMF, .npy):
// `bytes` to a temporary beside `path`, checked, then renamed onto it.
// Throws InputError("PATH: cannot write") and leaves nothing behind on failure.
void write_file_atomic(const std::filesystem::path& path, std::string_view bytes);

}  // namespace tg
