#include "core/atomic_file.hpp"

#include <unistd.h>

#include <atomic>
#include <fstream>

#include "core/errors.hpp"

namespace tg {
namespace fs = std::filesystem;

AtomicPath::AtomicPath(fs::path target) : target_(std::move(target)) {
  static std::atomic<int> counter{0};
  fs::path dir = target_.parent_path();
  if (dir.empty()) dir = ".";
  if (!fs::is_directory(dir))
    throw InputError(target_.string() + ": output folder " + dir.string() + " does not exist");
  // A device, pipe or socket must not be replaced by the rename (`-o
  // /dev/null` once replaced the device node with a folder of slices).
  std::error_code ec;
  const fs::file_status st = fs::symlink_status(target_, ec);
  if (fs::exists(st) && !fs::is_regular_file(st) && !fs::is_directory(st) && !fs::is_symlink(st))
    throw UsageError(target_.string() + ": exists and is not a file or folder (a device, pipe or socket); give a file path");
  // Hidden, same folder (so rename is atomic on one file system), unique per process and call.
  std::string name(1, '.');  // built by append: GCC 12 warns falsely (-Wrestrict) on "." + string
  name += target_.filename().string();
  name += ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
  temp_ = dir / name;
}

AtomicPath::~AtomicPath() {
  if (!committed_) {
    std::error_code ec;
    fs::remove_all(temp_, ec);
  }
}

void AtomicPath::commit() {
  std::error_code ec;
  // A folder replaces an earlier output (file or folder), nothing else.
  const fs::file_status st = fs::symlink_status(target_, ec);
  if (fs::is_directory(temp_) && (fs::is_regular_file(st) || fs::is_directory(st))) fs::remove_all(target_, ec);
  fs::rename(temp_, target_, ec);
  if (ec) throw InputError(target_.string() + ": cannot write (" + ec.message() + ")");
  committed_ = true;
}

void write_file_atomic(const fs::path& path, std::string_view bytes) {
  AtomicPath out(path);
  {
    std::ofstream f(out.temp(), std::ios::binary);
    f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    f.close();
    if (!f) throw InputError(path.string() + ": cannot write");
  }
  out.commit();
}

}  // namespace tg
