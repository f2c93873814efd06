#include "dem/checkpoint.hpp"

#include <cstring>
#include <fstream>
#include <type_traits>

#include "core/atomic_file.hpp"
#include "core/errors.hpp"

namespace tg::dem {

namespace {
// Version 2 added the checksum, version 3 the previous_particle field,
// version 4 the cut between the pair list's parts (it orders the force
// sums); older files are refused by name.
constexpr char kMagic[8] = {'T', 'G', 'D', 'E', 'M', 'C', 'K', '4'};

// 64-bit FNV-1a over the body. Each step (xor a byte, multiply by an odd
// constant) is a bijection of the state, so any change confined to one byte
// always changes the sum; other damage escapes with probability ~2^-64.
constexpr uint64_t kFnvOffset = 14695981039346656037ull;
uint64_t fnv1a_update(uint64_t h, const char* p, size_t n) {
  for (size_t k = 0; k < n; ++k) {
    h ^= static_cast<unsigned char>(p[k]);
    h *= 1099511628211ull;
  }
  return h;
}
uint64_t fnv1a(const char* p, size_t n) { return fnv1a_update(kFnvOffset, p, n); }

// The body goes straight to the file, hashed on the way: no copy of the
// state in memory (a buffered body doubled the run's peak memory at 10^6
// spheres, bench/dem/RESULTS.md, issue 23).
struct CheckpointWriter {
  std::ofstream& f;
  uint64_t hash = kFnvOffset;
  void write(const char* p, size_t n) {
    hash = fnv1a_update(hash, p, n);
    f.write(p, static_cast<std::streamsize>(n));
  }
};

template <class T>
void put(CheckpointWriter& os, const T& v) {
  os.write(reinterpret_cast<const char*>(&v), sizeof(T));
}
void put_str(CheckpointWriter& os, const std::string& s) {
  put<int64_t>(os, static_cast<int64_t>(s.size()));
  os.write(s.data(), s.size());
}
template <class T>
void put_vec(CheckpointWriter& os, const std::vector<T>& v) {
  put<int64_t>(os, static_cast<int64_t>(v.size()));
  put<int64_t>(os, static_cast<int64_t>(sizeof(T)));
  os.write(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}

// Reads the records in place from the file's bytes (no copy of the body:
// at 10^6 spheres each copy is a few hundred MB).
struct Reader {
  const char* at = nullptr;
  const char* end = nullptr;
  std::string path;
  void take(void* out, size_t n, const char* what) {
    if (static_cast<size_t>(end - at) < n) fail(what);
    if (n) std::memcpy(out, at, n);  // an empty vector's data() may be null (memcpy's arguments must not be)
    at += n;
  }
  template <class T>
  T get() {
    T v{};
    take(&v, sizeof(T), "truncated");
    return v;
  }
  std::string get_str() {
    const int64_t n = get<int64_t>();
    if (n < 0 || n > (1 << 30)) fail("corrupt string length");
    std::string s(static_cast<size_t>(n), '\0');
    take(s.data(), static_cast<size_t>(n), "truncated");
    return s;
  }
  template <class T>
  void get_vec(std::vector<T>& v, const std::string& what) {
    const int64_t n = get<int64_t>(), sz = get<int64_t>();
    if (n < 0 || sz != static_cast<int64_t>(sizeof(T))) fail("field '" + what + "' has the wrong element size");
    if (n > (end - at) / sz) fail("truncated in '" + what + "'");
    v.resize(static_cast<size_t>(n));
    take(v.data(), static_cast<size_t>(n * sz), "truncated");
  }
  [[noreturn]] void fail(const std::string& m) { throw InputError(path + ": not a readable tomograin DEM checkpoint (" + m + ")"); }
};
}  // namespace

void save_checkpoint(const Engine& e, const std::string& scene, const std::filesystem::path& path) {
  AtomicPath out(path);
  {
    std::ofstream f(out.temp(), std::ios::binary);
    if (!f) throw InputError(path.string() + ": cannot write checkpoint");
    f.write(kMagic, 8);
    CheckpointWriter os{f};
    const Particles& p = e.particles();
    put<int64_t>(os, p.size());
    p.for_each_field([&](std::string_view name, const auto& v) {
      put_str(os, std::string(name));
      put_vec(os, v);
    });
    put<double>(os, e.time());
    put<int64_t>(os, e.step_count());
    const Walls& w = e.options().walls;
    put<double>(os, w.top_z);
    put<double>(os, w.top_vz);
    put<int64_t>(os, e.part_split());
    const Engine::PairHistory h = e.pair_history();
    put_vec(os, h.i);
    put_vec(os, h.j);
    put_vec(os, h.xi);
    put_str(os, scene);
    const uint64_t sum = os.hash;
    f.write(reinterpret_cast<const char*>(&sum), sizeof sum);
    if (!f) throw InputError(path.string() + ": write failed");
  }
  out.commit();
}

CheckpointState load_checkpoint(const std::filesystem::path& path) {
  // Whole file first: magic, version and checksum are checked before any
  // field is parsed, so a damaged file never yields a plausible state.
  std::ifstream f(path, std::ios::binary);
  if (!f) throw InputError(path.string() + ": cannot open checkpoint");
  f.seekg(0, std::ios::end);
  const std::streamoff size = f.tellg();
  f.seekg(0, std::ios::beg);
  std::string all(size > 0 ? static_cast<size_t>(size) : 0, '\0');  // one allocation of the file's size
  if (size < 0 || !f.read(all.data(), size)) throw InputError(path.string() + ": cannot read checkpoint");
  Reader r{nullptr, nullptr, path.string()};
  if (all.size() < 8 || std::memcmp(all.data(), kMagic, 7) != 0) r.fail("bad magic");
  if (all[7] != kMagic[7])
    r.fail("format version " + all.substr(7, 1) + ", this tomograin reads version " + std::string(1, kMagic[7]));
  if (all.size() < 16) r.fail("truncated");
  const size_t nbody = all.size() - 16;
  uint64_t stored = 0;
  std::memcpy(&stored, all.data() + 8 + nbody, 8);
  if (fnv1a(all.data() + 8, nbody) != stored) r.fail("checksum mismatch: the file is damaged or truncated");
  r.at = all.data() + 8;  // parsed in place: the file was read once
  r.end = r.at + nbody;
  CheckpointState s;
  const int64_t n = r.get<int64_t>();
  s.particles.for_each_field([&](std::string_view name, auto& v) {
    if (r.get_str() != name) r.fail("field order differs: expected '" + std::string(name) + "'");
    r.get_vec(v, std::string(name));
    if (static_cast<int64_t>(v.size()) != n) r.fail("field '" + std::string(name) + "' has the wrong length");
  });
  s.time = r.get<double>();
  s.steps = r.get<int64_t>();
  s.walls.top_z = r.get<double>();
  s.walls.top_vz = r.get<double>();
  s.part_split = r.get<int64_t>();
  if (s.part_split < -1 || s.part_split > n) r.fail("part split out of range");
  r.get_vec(s.history.i, "pair i");
  r.get_vec(s.history.j, "pair j");
  r.get_vec(s.history.xi, "pair history");
  if (s.history.j.size() != s.history.i.size() || s.history.xi.size() != 3 * s.history.i.size()) r.fail("pair arrays disagree");
  s.scene = r.get_str();
  if (r.at != r.end) r.fail("trailing bytes after the scene");
  return s;
}

Engine resume_engine(CheckpointState& s, EngineOptions opt) {
  opt.walls.top_z = s.walls.top_z;
  opt.walls.top_vz = s.walls.top_vz;
  Engine e(std::move(s.particles), opt);
  e.restore(s.time, s.steps, s.history);
  e.set_part_split(s.part_split);
  return e;
}

}  // namespace tg::dem
