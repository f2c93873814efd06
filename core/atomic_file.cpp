#include "core/atomic_file.hpp"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <fstream>
#include <regex>
#include <vector>

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

int remove_stale_temporaries(const fs::path& dir) {
  static const std::regex temp_name(R"(\..+\.tmp-([0-9]+)-[0-9]+)");
  std::error_code ec;
  int removed = 0;
  std::vector<fs::path> stale;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    std::smatch m;
    const std::string name = entry.path().filename().string();
    if (!std::regex_match(name, m, temp_name)) continue;
    const long pid = std::stol(m[1].str());
    // kill(pid, 0) fails with ESRCH when no such process exists (EPERM: it
    // exists, owned by another user).
    if (pid > 0 && pid != long(::getpid()) && ::kill(pid_t(pid), 0) != 0 && errno == ESRCH)
      stale.push_back(entry.path());
  }
  for (const auto& p : stale)
    if (fs::remove_all(p, ec) > 0) ++removed;
  return removed;
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
