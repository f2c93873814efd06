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
  if (fs::is_directory(temp_) && fs::exists(target_)) fs::remove_all(target_, ec);
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
