#include "dem/checkpoint.hpp"

#include <cstring>
#include <fstream>
#include <type_traits>

#include "core/atomic_file.hpp"
#include "core/errors.hpp"

namespace tg::dem {

namespace {
constexpr char kMagic[8] = {'T', 'G', 'D', 'E', 'M', 'C', 'K', '1'};

template <class T>
void put(std::ostream& os, const T& v) {
  os.write(reinterpret_cast<const char*>(&v), sizeof(T));
}
void put_str(std::ostream& os, const std::string& s) {
  put<int64_t>(os, static_cast<int64_t>(s.size()));
  os.write(s.data(), static_cast<std::streamsize>(s.size()));
}
template <class T>
void put_vec(std::ostream& os, const std::vector<T>& v) {
  put<int64_t>(os, static_cast<int64_t>(v.size()));
  put<int64_t>(os, static_cast<int64_t>(sizeof(T)));
  os.write(reinterpret_cast<const char*>(v.data()), static_cast<std::streamsize>(v.size() * sizeof(T)));
}

struct Reader {
  std::ifstream is;
  std::string path;
  template <class T>
  T get() {
    T v{};
    if (!is.read(reinterpret_cast<char*>(&v), sizeof(T))) fail("truncated");
    return v;
  }
  std::string get_str() {
    const int64_t n = get<int64_t>();
    if (n < 0 || n > (1 << 30)) fail("corrupt string length");
    std::string s(static_cast<size_t>(n), '\0');
    if (!is.read(s.data(), n)) fail("truncated");
    return s;
  }
  template <class T>
  void get_vec(std::vector<T>& v, const std::string& what) {
    const int64_t n = get<int64_t>(), sz = get<int64_t>();
    if (n < 0 || sz != static_cast<int64_t>(sizeof(T))) fail("field '" + what + "' has the wrong element size");
    v.resize(static_cast<size_t>(n));
    if (!is.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(n * sz))) fail("truncated in '" + what + "'");
  }
  [[noreturn]] void fail(const std::string& m) { throw InputError(path + ": not a readable tomograin DEM checkpoint (" + m + ")"); }
};
}  // namespace

void save_checkpoint(const Engine& e, const std::string& scene, const std::filesystem::path& path) {
  AtomicPath out(path);
  {
    std::ofstream os(out.temp(), std::ios::binary);
    if (!os) throw InputError(path.string() + ": cannot write checkpoint");
    os.write(kMagic, 8);
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
    const Engine::PairHistory h = e.pair_history();
    put_vec(os, h.i);
    put_vec(os, h.j);
    put_vec(os, h.xi);
    put_str(os, scene);
    if (!os) throw InputError(path.string() + ": write failed");
  }
  out.commit();
}

CheckpointState load_checkpoint(const std::filesystem::path& path) {
  Reader r{std::ifstream(path, std::ios::binary), path.string()};
  if (!r.is) throw InputError(path.string() + ": cannot open checkpoint");
  char magic[8];
  if (!r.is.read(magic, 8) || std::memcmp(magic, kMagic, 8) != 0) r.fail("bad magic");
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
  r.get_vec(s.history.i, "pair i");
  r.get_vec(s.history.j, "pair j");
  r.get_vec(s.history.xi, "pair history");
  if (s.history.j.size() != s.history.i.size() || s.history.xi.size() != 3 * s.history.i.size()) r.fail("pair arrays disagree");
  s.scene = r.get_str();
  return s;
}

Engine resume_engine(CheckpointState& s, EngineOptions opt) {
  opt.walls.top_z = s.walls.top_z;
  opt.walls.top_vz = s.walls.top_vz;
  Engine e(std::move(s.particles), opt);
  e.restore(s.time, s.steps, s.history);
  return e;
}

}  // namespace tg::dem
