#include "compare/stage_matching.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/errors.hpp"
#include "dem/run_folder.hpp"

namespace tg::compare {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// First numeric column present among `names`, or "".
std::string first_of(const Table& t, std::initializer_list<const char*> names) {
  for (const char* n : names)
    if (t.has(n) && !t.columns()[static_cast<size_t>(t.find(n))].is_text) return n;
  return "";
}

}  // namespace

size_t match_snapshot(std::span<const double> snap, double stage_strain, size_t n) {
  if (snap.empty()) throw UsageError("compare: no DEM snapshot to match");
  size_t m = std::min(n, snap.size() - 1);
  if (std::isfinite(stage_strain)) {
    double best = std::numeric_limits<double>::max();
    for (size_t q = 0; q < snap.size(); ++q)
      if (std::isfinite(snap[q]) && std::abs(snap[q] - stage_strain) < best) {
        best = std::abs(snap[q] - stage_strain);
        m = q;
      }
  }
  return m;
}

Curve read_curve(const std::filesystem::path& path) {
  Table t = read_csv(path);
  Curve c;
  const std::string e = first_of(t, {"axial_strain", "strain", "eps_zz", "strain_zz"});
  if (e.empty()) throw InputError(path.string() + ": no strain column (axial_strain or strain)");
  std::string s = first_of(t, {"axial_stress_Pa", "stress_zz_Pa", "sigma_zz_Pa", "top_stress_Pa", "stress_Pa",
                               "axial_stress_kPa", "stress_kPa", "axial_stress_MPa", "stress_MPa"});
  if (s.empty())
    for (const Column& col : t.columns())
      if (!col.is_text && col.name.find("stress") != std::string::npos) {
        s = col.name;
        break;
      }
  if (s.empty()) throw InputError(path.string() + ": no axial stress column (e.g. axial_stress_Pa)");
  double scale = 1e-6;  // Pa -> MPa (also for unitless names)
  if (s.ends_with("kPa")) scale = 1e-3;
  if (s.ends_with("MPa")) scale = 1;
  c.stress_column = s;
  c.strain = t.num(e);
  for (double v : t.num(s)) c.stress_mpa.push_back(v * scale);
  const std::string b = first_of(t, {"grains_broken", "broken_grains", "broken_particles", "broken"});
  if (!b.empty()) c.broken = t.num(b);
  return c;
}

Curve history_curve(const Table& h) {
  Curve c;
  if (h.columns().empty()) return c;
  c.stress_column = dem::kHistoryTopStress;
  c.strain = h.num(dem::kHistoryStrain);
  for (double v : h.num(dem::kHistoryTopStress)) c.stress_mpa.push_back(v * 1e-6);
  if (h.has(dem::kHistoryGrainsBroken)) c.broken = h.num(dem::kHistoryGrainsBroken);
  if (h.has(dem::kHistoryBondsBroken)) c.bonds = h.num(dem::kHistoryBondsBroken);
  return c;
}

double interpolate(const std::vector<double>& x, const std::vector<double>& y, double at) {
  if (x.empty()) return kNaN;
  size_t best = 0;
  for (size_t q = 1; q < x.size(); ++q)
    if (std::abs(x[q] - at) < std::abs(x[best] - at)) best = q;
  for (size_t q = 1; q < x.size(); ++q)
    if (x[q - 1] <= at && at <= x[q] && x[q] > x[q - 1])
      return y[q - 1] + (y[q] - y[q - 1]) * (at - x[q - 1]) / (x[q] - x[q - 1]);
  return y[best];
}

double count_growth_fraction(int64_t count, int64_t count0) {
  if (count0 <= 0) return kNaN;
  return std::clamp(static_cast<double>(count - count0) / static_cast<double>(count0), 0.0, 1.0);
}

BrokenEstimate dem_broken_fraction(const Curve& history, double strain, int64_t particles, int64_t initial) {
  if (!history.broken.empty() && std::isfinite(strain) && initial > 0)
    return {interpolate(history.strain, history.broken, strain) / static_cast<double>(initial),
            "history.csv broken grains / initial particles"};
  return {count_growth_fraction(particles, initial), "particle count growth (one extra particle per break)"};
}

}  // namespace tg::compare
