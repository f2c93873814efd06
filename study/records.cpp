#include "study/records.hpp"

#include <fcntl.h>
#include <fmt/core.h>
#include <sys/file.h>
#include <unistd.h>
#include <xxhash.h>

#include <algorithm>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/atomic_file.hpp"
#include "core/errors.hpp"

namespace tg::study {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string hex(XXH64_hash_t h) { return fmt::format("{:016x}", static_cast<unsigned long long>(h)); }

struct StateDeleter {
  void operator()(XXH3_state_t* s) const { XXH3_freeState(s); }
};

void hash_file_into(XXH3_state_t* st, const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  if (!f) throw InputError(p.string() + ": cannot read");
  std::vector<char> buf(size_t{1} << 22);
  while (f) {
    f.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    XXH3_64bits_update(st, buf.data(), static_cast<size_t>(f.gcount()));
  }
  if (f.bad()) throw InputError(p.string() + ": read error");
}

// The files behind a path: itself, or a folder's regular files in name order.
std::vector<fs::path> files_of(const fs::path& p) {
  if (!fs::is_directory(p)) return {p};
  std::vector<fs::path> v;
  for (const auto& e : fs::directory_iterator(p))
    if (e.is_regular_file()) v.push_back(e.path());
  std::sort(v.begin(), v.end());
  return v;
}

std::string stamp_of(const std::vector<fs::path>& files) {
  std::string s;
  for (const auto& f : files) {
    const auto t = fs::last_write_time(f).time_since_epoch().count();
    s += fmt::format("{}:{}:{};", f.filename().string(), fs::file_size(f), static_cast<long long>(t));
  }
  return s;
}

}  // namespace

HashCache::HashCache(fs::path run_dir) : file_(run_dir / "hashes.json") {
  std::ifstream f(file_);
  if (!f) return;
  try {
    const json j = json::parse(f);
    for (const auto& [path, e] : j.items()) entries_[path] = {e.at("stamp"), e.at("hash")};
  } catch (const std::exception&) {
    entries_.clear();  // a damaged cache is rebuilt, never trusted
  }
}

std::string HashCache::hash(const fs::path& p_in) {
  // "file.h5:/volume" names a dataset inside a file: hash the file.
  std::string ps = p_in.string();
  if (!fs::exists(p_in)) {
    const auto colon = ps.rfind(':');
    if (colon != std::string::npos) ps = ps.substr(0, colon);
  }
  const fs::path p(ps);
  if (!fs::exists(p)) throw InputError(ps + ": no such file or folder");
  const auto files = files_of(p);
  const std::string stamp = stamp_of(files);
  auto it = entries_.find(ps);
  if (it != entries_.end() && it->second.stamp == stamp) return it->second.hash;
  std::unique_ptr<XXH3_state_t, StateDeleter> st(XXH3_createState());
  XXH3_64bits_reset(st.get());
  for (const auto& f : files) {
    const std::string name = f.filename().string();
    if (files.size() > 1 || fs::is_directory(p)) XXH3_64bits_update(st.get(), name.c_str(), name.size() + 1);
    hash_file_into(st.get(), f);
  }
  const std::string h = hex(XXH3_64bits_digest(st.get()));
  entries_[ps] = {stamp, h};
  changed_ = true;
  return h;
}

void HashCache::save() const {
  if (!changed_) return;
  json j = json::object();
  for (const auto& [path, e] : entries_) j[path] = {{"stamp", e.stamp}, {"hash", e.hash}};
  try {
    fs::create_directories(file_.parent_path());
    write_file_atomic(file_, j.dump(1) + "\n");
  } catch (const std::exception&) {
  }
}

std::string hash_strings(const std::vector<std::string>& parts) {
  std::unique_ptr<XXH3_state_t, StateDeleter> st(XXH3_createState());
  XXH3_64bits_reset(st.get());
  for (const auto& s : parts) XXH3_64bits_update(st.get(), s.c_str(), s.size() + 1);
  return hex(XXH3_64bits_digest(st.get()));
}

std::string recorded_key(const fs::path& record) {
  std::ifstream f(record);
  if (!f) return "";
  try {
    return json::parse(f).at("key").get<std::string>();
  } catch (const std::exception&) {
    return "";
  }
}

void write_record(const fs::path& record, const std::string& step, const std::string& key, double seconds) {
  fs::create_directories(record.parent_path());
  const json j = {{"step", step}, {"key", key}, {"seconds", seconds}};
  write_file_atomic(record, j.dump(1) + "\n");
}

StepLock::StepLock(const fs::path& lock_file) {
  fs::create_directories(lock_file.parent_path());
  fd_ = ::open(lock_file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) throw InputError(lock_file.string() + ": cannot create the step's lock");
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd_);
    fd_ = -1;
    throw InputError(lock_file.string() + ": another process is running this step");
  }
}

StepLock::~StepLock() {
  if (fd_ >= 0) ::close(fd_);
}

}  // namespace tg::study
