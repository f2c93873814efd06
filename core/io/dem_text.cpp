#include "core/io/dem_text.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <sstream>
#include <string_view>
#include <unordered_set>
#include <vector>

#include "core/errors.hpp"

namespace tg {
namespace fs = std::filesystem;

namespace {

// The file's lines (without their end), read once.
struct Lines {
  std::string name;
  std::string text;
  std::vector<std::string_view> lines;
  explicit Lines(const std::string& path) : name(path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw InputError(path + ": cannot open");
    std::ostringstream s;
    s << f.rdbuf();
    text = s.str();
    size_t a = 0;
    while (a < text.size()) {
      size_t b = text.find('\n', a);
      if (b == std::string::npos) b = text.size();
      std::string_view l(text.data() + a, b - a);
      if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
      lines.push_back(l);
      a = b + 1;
    }
  }
  [[noreturn]] void fail(size_t i, const std::string& what) const {
    throw InputError(name + ":" + std::to_string(i + 1) + ": " + what);
  }
};

std::vector<std::string_view> words(std::string_view l) {
  std::vector<std::string_view> w;
  size_t a = 0;
  while (a < l.size()) {
    while (a < l.size() && (l[a] == ' ' || l[a] == '\t')) ++a;
    size_t b = a;
    while (b < l.size() && l[b] != ' ' && l[b] != '\t') ++b;
    if (b > a) w.push_back(l.substr(a, b - a));
    a = b;
  }
  return w;
}

bool number(std::string_view s, double& v) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

bool integer(std::string_view s, int64_t& v) {
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

bool starts_with(std::string_view s, std::string_view p) { return s.substr(0, p.size()) == p; }

std::string first_line(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::string l;
  if (f) std::getline(f, l);
  if (!l.empty() && l.back() == '\r') l.pop_back();
  return l;
}

// ---- LAMMPS / LIGGGHTS dump ---------------------------------------------

struct DumpBlock {
  int64_t step = 0;
  size_t atoms_header = 0;  // line of "ITEM: ATOMS ..."
  int64_t n = 0;
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  bool triclinic = false;
  double unit = 1.0;  // metres per length unit
};

// Every timestep's block, checked for its structure (not its atom rows).
// LAMMPS writes "ITEM: UNITS" once at the top (dump_modify units yes) and
// "ITEM: TIME" before a timestep (dump_modify time yes): the header items
// of a block come in any order before its ATOMS.
std::vector<DumpBlock> dump_blocks(const Lines& L) {
  std::vector<DumpBlock> blocks;
  const size_t n = L.lines.size();
  auto next = [&](size_t at, const char* what) -> std::string_view {
    if (at >= n) L.fail(at, std::string("file ends where ") + what + " was expected (truncated dump?)");
    return L.lines[at];
  };
  double unit = 1.0;  // metres per length unit, for every block after "ITEM: UNITS"
  size_t i = 0;
  while (i < n) {
    if (L.lines[i].empty()) {
      ++i;
      continue;
    }
    DumpBlock b;
    bool have_step = false, have_n = false, have_box = false;
    while (true) {
      const std::string_view l = next(i, "ITEM: ATOMS");
      if (l == "ITEM: TIMESTEP") {
        if (!integer(next(i + 1, "the timestep"), b.step)) L.fail(i + 1, "the timestep is not an integer");
        have_step = true;
        i += 2;
      } else if (l == "ITEM: NUMBER OF ATOMS") {
        if (!integer(next(i + 1, "the number of atoms"), b.n) || b.n < 0 || b.n > (int64_t(1) << 40))
          L.fail(i + 1, "the number of atoms is not a count");
        have_n = true;
        i += 2;
      } else if (starts_with(l, "ITEM: BOX BOUNDS")) {
        b.triclinic = l.find("xy") != std::string_view::npos;
        for (int d = 0; d < 3; ++d) {
          const auto w = words(next(i + 1 + d, "a box bound"));
          if (w.size() < 2 || !number(w[0], b.lo[d]) || !number(w[1], b.hi[d]) || !(b.hi[d] >= b.lo[d]))
            L.fail(i + 1 + d, "a box bound is not 'lo hi'");
        }
        have_box = true;
        i += 4;
      } else if (l == "ITEM: UNITS") {
        const std::string_view u = next(i + 1, "the unit style");
        if (u == "cgs")
          unit = 0.01;
        else if (u == "si")
          unit = 1.0;
        else
          L.fail(i + 1, "unit style '" + std::string(u) + "': si and cgs are read (lengths in metres or cm)");
        i += 2;
      } else if (l == "ITEM: TIME") {
        next(i + 1, "the time");
        i += 2;  // simulated time: not needed
      } else if (starts_with(l, "ITEM: ATOMS")) {
        if (!have_step) L.fail(i, "ITEM: ATOMS before ITEM: TIMESTEP");
        if (!have_n) L.fail(i, "ITEM: ATOMS before ITEM: NUMBER OF ATOMS");
        if (!have_box) L.fail(i, "ITEM: ATOMS before ITEM: BOX BOUNDS");
        b.atoms_header = i;
        b.unit = unit;
        i += 1 + size_t(b.n);
        if (i > n)
          L.fail(n, "file ends inside the atoms of timestep " + std::to_string(b.step) + " (" + std::to_string(b.n) +
                        " announced; truncated dump?)");
        break;
      } else {
        L.fail(i, "expected an 'ITEM:' line of a LAMMPS/LIGGGHTS dump, not '" + std::string(l.substr(0, 60)) + "'");
      }
    }
    blocks.push_back(b);
  }
  if (blocks.empty()) throw InputError(L.name + ": no timestep in the dump");
  return blocks;
}

Table dump_table(const Lines& L, const DumpBlock& b) {
  const auto head = words(L.lines[b.atoms_header]);  // "ITEM:" "ATOMS" col...
  std::vector<std::string_view> cols(head.begin() + 2, head.end());
  auto col = [&](std::initializer_list<std::string_view> names) -> int {
    for (std::string_view nm : names) {
      const auto it = std::find(cols.begin(), cols.end(), nm);
      if (it != cols.end()) return int(it - cols.begin());
    }
    return -1;
  };
  int pos[3];
  bool scaled = false;
  for (int d = 0; d < 3; ++d) {
    const std::string a(1, "xyz"[d]);
    pos[d] = col({a, a + "u"});
    if (pos[d] < 0) {
      pos[d] = col({a + "s"});
      scaled = pos[d] >= 0;
    }
    if (pos[d] < 0)
      L.fail(b.atoms_header, "no " + a + " column (dump x y z, xu yu zu or xs ys zs)");
  }
  if (scaled && b.triclinic) L.fail(b.atoms_header, "scaled positions in a triclinic box: dump x y z instead");
  const int rad = col({"radius"}), dia = col({"diameter"});
  if (rad < 0 && dia < 0) L.fail(b.atoms_header, "no radius or diameter column (dump ... radius)");
  const int id = col({"id"}), mol = col({"mol"});
  const size_t need = size_t(std::max({pos[0], pos[1], pos[2], rad, dia, id, mol})) + 1;

  const int64_t n = b.n;
  std::vector<double> x(n), y(n), z(n), r(n), part(mol >= 0 ? n : 0);
  std::vector<int64_t> ids(id >= 0 ? n : 0);
  for (int64_t q = 0; q < n; ++q) {
    const size_t li = b.atoms_header + 1 + size_t(q);
    const auto w = words(L.lines[li]);
    if (w.size() < need) L.fail(li, "atom row has " + std::to_string(w.size()) + " values, the header " +
                                        std::to_string(cols.size()));
    double v[3];
    for (int d = 0; d < 3; ++d) {
      if (!number(w[size_t(pos[d])], v[d])) L.fail(li, "position is not a number");
      if (scaled) v[d] = b.lo[d] + v[d] * (b.hi[d] - b.lo[d]);
    }
    double s = 0;
    if (!number(w[size_t(rad >= 0 ? rad : dia)], s)) L.fail(li, "radius is not a number");
    if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) L.fail(li, "position must be finite");
    if (!(s > 0) || !std::isfinite(s)) L.fail(li, "radius must be > 0");
    x[q] = v[0] * b.unit;
    y[q] = v[1] * b.unit;
    z[q] = v[2] * b.unit;
    r[q] = (rad >= 0 ? s : 0.5 * s) * b.unit;
    if (id >= 0 && !integer(w[size_t(id)], ids[q])) L.fail(li, "id is not an integer");
    if (mol >= 0) {
      int64_t m = 0;
      if (!integer(w[size_t(mol)], m)) L.fail(li, "mol is not an integer");
      part[q] = double(m);
    }
  }
  // Rows in id order (ranks write in any order); ids must be unique.
  std::vector<int64_t> order(static_cast<size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  if (id >= 0) {
    std::stable_sort(order.begin(), order.end(), [&](int64_t a, int64_t c) { return ids[a] < ids[c]; });
    for (int64_t q = 1; q < n; ++q)
      if (ids[order[q]] == ids[order[q - 1]])
        L.fail(b.atoms_header + 1 + size_t(order[q]), "atom id " + std::to_string(ids[order[q]]) + " appears twice");
  }
  auto by = [&](const std::vector<double>& v) {
    std::vector<double> o(v.size());
    for (size_t q = 0; q < v.size(); ++q) o[q] = v[size_t(order[q])];
    return o;
  };
  Table t;
  t.add("x_m", by(x));
  t.add("y_m", by(y));
  t.add("z_m", by(z));
  t.add("r_m", by(r));
  if (mol >= 0) t.add("particle", by(part));
  t.source = L.name + " (timestep " + std::to_string(b.step) + ")";
  return t;
}

Table read_lammps_dump(const std::string& path, std::optional<int64_t> step) {
  const Lines L(path);
  const std::vector<DumpBlock> blocks = dump_blocks(L);
  if (step) {
    for (const DumpBlock& b : blocks)
      if (b.step == *step) return dump_table(L, b);
    throw InputError(path + ": no timestep " + std::to_string(*step) + " (it has " + std::to_string(blocks.size()) +
                     ", from " + std::to_string(blocks.front().step) + " to " + std::to_string(blocks.back().step) + ")");
  }
  if (blocks.size() > 1)
    throw InputError(path + ": a dump of " + std::to_string(blocks.size()) + " timesteps (" +
                     std::to_string(blocks.front().step) + " to " + std::to_string(blocks.back().step) +
                     "): name one as " + path + ":STEP");
  return dump_table(L, blocks.front());
}

// ---- YADE export.text ---------------------------------------------------

Table read_yade_text(const std::string& path) {
  const Lines L(path);
  std::vector<double> x, y, z, r;
  for (size_t i = 0; i < L.lines.size(); ++i) {
    const std::string_view l = L.lines[i];
    if (l.empty() || l.front() == '#') continue;
    const auto w = words(l);
    if (w.empty()) continue;
    double v[4];
    if (w.size() < 4) L.fail(i, "expected x y z r");
    for (int k = 0; k < 4; ++k)
      if (!number(w[size_t(k)], v[k])) L.fail(i, "'" + std::string(w[size_t(k)]) + "' is not a number");
    if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) L.fail(i, "position must be finite");
    if (!(v[3] > 0) || !std::isfinite(v[3])) L.fail(i, "radius must be > 0");
    x.push_back(v[0]);
    y.push_back(v[1]);
    z.push_back(v[2]);
    r.push_back(v[3]);
  }
  Table t;
  t.add("x_m", std::move(x));
  t.add("y_m", std::move(y));
  t.add("z_m", std::move(z));
  t.add("r_m", std::move(r));
  t.source = path;
  return t;
}

}  // namespace

std::optional<Table> read_dem_text(const std::string& spec) {
  std::string path = spec;
  std::optional<int64_t> step;
  // "FILE:STEP" names a dump's timestep when FILE itself is not a file.
  const auto colon = spec.rfind(':');
  if (!fs::exists(spec) && colon != std::string::npos && colon + 1 < spec.size()) {
    int64_t s = 0;
    const std::string_view tail(spec.data() + colon + 1, spec.size() - colon - 1);
    if (integer(tail, s) && fs::is_regular_file(spec.substr(0, colon))) {
      path = spec.substr(0, colon);
      step = s;
    }
  }
  const std::string head = first_line(path);
  if (head == "ITEM: TIMESTEP" || head == "ITEM: UNITS" || head == "ITEM: TIME") return read_lammps_dump(path, step);
  if (step) throw InputError(spec + ": ':STEP' names a timestep of a LAMMPS/LIGGGHTS dump; " + path + " is not one");
  if (starts_with(head, "#format x_y_z_r")) return read_yade_text(path);
  return std::nullopt;
}

}  // namespace tg
