#include "dem/calibration/objective.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/config.hpp"
#include "core/errors.hpp"
#include "dem/yield_stress.hpp"

namespace tg::dem::calibration {
namespace objective_detail {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

void read_curve(Target& t, const std::filesystem::path& csv, const std::string& where) {
  if (!std::filesystem::exists(csv)) throw InputError(where + ": stress-strain curve " + csv.string() + " not found");
  const Table c = read_csv(csv);
  const std::string stress = c.has("stress_Pa") ? "stress_Pa" : "top_stress_Pa";
  if (!c.has("strain") || !c.has(stress))
    throw InputError(csv.string() + ": a stress-strain curve needs columns strain and stress_Pa (or top_stress_Pa)");
  t.curve_file = csv.string();
  t.curve_strain = c.num("strain");
  t.curve_stress_Pa = c.num(stress);
  if (t.curve_strain.empty()) throw InputError(csv.string() + ": the stress-strain curve has no rows");
  for (size_t i = 0; i < t.curve_strain.size(); ++i) {
    if (!std::isfinite(t.curve_strain[i]) || !std::isfinite(t.curve_stress_Pa[i]) || t.curve_strain[i] < 0)
      throw InputError(csv.string() + ": row " + std::to_string(i + 2) + " is not a finite strain >= 0 and stress");
    if (i > 0 && !(t.curve_strain[i] > t.curve_strain[i - 1]))
      throw InputError(csv.string() + ": strain must increase from row to row (row " + std::to_string(i + 2) + ")");
  }
  double ss = 0;
  for (double s : t.curve_stress_Pa) ss += s * s;
  if (!(ss > 0)) throw InputError(csv.string() + ": the stress-strain curve is zero everywhere");
}

double rms(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x * x;
  return std::sqrt(s / static_cast<double>(v.size()));
}

}  // namespace objective_detail

std::vector<Parameter> default_parameters() {
  return {{"sigma_t0_Pa", "breakage.sigma_t0_Pa", 6.0e6, 24.0e6},
          {"bond_radius_multiplier", "breakage.bond_radius_multiplier", 0.8, 1.6}};
}

double Target::largest_strain() const {
  double e = 0;
  for (double x : curve_strain) e = std::max(e, x);
  for (double x : broken_strain) e = std::max(e, x);
  return e;
}

Target read_target(const std::filesystem::path& path) {
  using namespace objective_detail;
  const std::string src = path.string();
  if (!std::filesystem::exists(path)) throw InputError(src + ": target file not found");
  Target t;
  t.source = src;
  if (path.extension() == ".csv") {
    read_curve(t, path, src);
    return t;
  }
  Config cfg = Config::from_file(path);
  const std::string curve = cfg.get("target.stress_strain_csv", std::string());
  t.yield_stress_Pa = cfg.get("target.yield_stress_Pa", 0.0);
  t.broken_strain = cfg.get("target.broken_strain", std::vector<double>{});
  t.broken_fraction = cfg.get("target.broken_fraction", std::vector<double>{});
  t.broken_stress_Pa = cfg.get("target.broken_at_stress_Pa", std::vector<double>{});
  t.broken_fraction_at_stress = cfg.get("target.broken_fraction_at_stress", std::vector<double>{});
  t.bonds_broken_at_stress = cfg.get("target.bonds_broken_at_stress", std::vector<double>{});
  t.w_curve = cfg.get("weights.stress_strain", t.w_curve);
  t.w_yield = cfg.get("weights.yield_stress", t.w_yield);
  t.w_broken = cfg.get("weights.broken_fraction", t.w_broken);
  t.w_broken_stress = cfg.get("weights.broken_at_stress", t.w_broken_stress);
  t.w_bonds = cfg.get("weights.bonds_at_stress", t.w_bonds);
  t.w_crush = cfg.get("weights.crush", t.w_crush);
  const bool crush = cfg.has("crush.bonds_broken");
  t.crush_bonds_broken = cfg.get("crush.bonds_broken", t.crush_bonds_broken);
  t.crush_grains = cfg.get("crush.grains", t.crush_grains);
  t.crush_diameter_m = cfg.get("crush.diameter_m", t.crush_diameter_m);
  t.crush_travel = cfg.get("crush.travel", t.crush_travel);
  for (Parameter& p : t.parameters) {
    const std::string key = "parameters." + p.name;
    const std::vector<double> r = cfg.get(key, std::vector<double>{p.min, p.max});
    cfg.require(r.size() == 2 && r[0] > 0 && r[0] < r[1], key, "must be [min, max] with 0 < min < max");
    p.min = r[0];
    p.max = r[1];
  }
  cfg.finish();
  cfg.require(t.yield_stress_Pa >= 0, "target.yield_stress_Pa", "must be > 0 (or left out)");
  cfg.require(t.broken_strain.size() == t.broken_fraction.size(), "target.broken_fraction",
              "must have one value per target.broken_strain");
  for (size_t i = 0; i < t.broken_strain.size(); ++i) {
    cfg.require(t.broken_strain[i] > 0 && t.broken_strain[i] < 1, "target.broken_strain", "must be strains in (0, 1)");
    cfg.require(t.broken_fraction[i] >= 0 && t.broken_fraction[i] <= 1, "target.broken_fraction",
                "must be fractions in [0, 1]");
  }
  // At the stresses: grains, bonds or both, each list one value per stress.
  const size_t ns = t.broken_stress_Pa.size();
  cfg.require(t.broken_fraction_at_stress.empty() ? ns == 0 || !t.bonds_broken_at_stress.empty()
                                                  : t.broken_fraction_at_stress.size() == ns,
              "target.broken_fraction_at_stress", "must have one value per target.broken_at_stress_Pa");
  cfg.require(t.bonds_broken_at_stress.empty() || t.bonds_broken_at_stress.size() == ns, "target.bonds_broken_at_stress",
              "must have one value per target.broken_at_stress_Pa");
  for (size_t i = 0; i < ns; ++i)
    cfg.require(t.broken_stress_Pa[i] > 0 && std::isfinite(t.broken_stress_Pa[i]), "target.broken_at_stress_Pa",
                "must be stresses > 0 (Pa)");
  for (double f : t.broken_fraction_at_stress)
    cfg.require(f >= 0 && f <= 1, "target.broken_fraction_at_stress", "must be fractions in [0, 1]");
  for (double n : t.bonds_broken_at_stress)
    cfg.require(n >= 0 && std::isfinite(n), "target.bonds_broken_at_stress", "must be bond counts >= 0");
  cfg.require(t.w_curve >= 0, "weights.stress_strain", "must be >= 0");
  cfg.require(t.w_yield >= 0, "weights.yield_stress", "must be >= 0");
  cfg.require(t.w_broken >= 0, "weights.broken_fraction", "must be >= 0");
  cfg.require(t.w_broken_stress >= 0, "weights.broken_at_stress", "must be >= 0");
  cfg.require(t.w_bonds >= 0, "weights.bonds_at_stress", "must be >= 0");
  cfg.require(t.w_crush >= 0, "weights.crush", "must be >= 0");
  cfg.require(!crush || t.crush_bonds_broken > 0, "crush.bonds_broken", "must be > 0 (or left out)");
  cfg.require(t.crush_grains >= 1, "crush.grains", "must be >= 1");
  cfg.require(t.crush_diameter_m > 0, "crush.diameter_m", "must be > 0");
  cfg.require(t.crush_travel > 0 && t.crush_travel < 0.9, "crush.travel", "must be in (0, 0.9) (platen travel / diameter)");
  if (!curve.empty()) {
    const std::filesystem::path p = std::filesystem::path(curve).is_absolute() ? std::filesystem::path(curve)
                                                                                : path.parent_path() / curve;
    read_curve(t, p, src);
  }
  const bool any = (!t.curve_strain.empty() && t.w_curve > 0) || (t.yield_stress_Pa > 0 && t.w_yield > 0) ||
                   (!t.broken_strain.empty() && t.w_broken > 0) ||
                   (!t.broken_fraction_at_stress.empty() && t.w_broken_stress > 0) ||
                   (!t.bonds_broken_at_stress.empty() && t.w_bonds > 0) || (t.crush_bonds_broken > 0 && t.w_crush > 0);
  if (!any)
    throw InputError(src + ": no target with a positive weight (give target.stress_strain_csv, "
                           "target.yield_stress_Pa, target.broken_strain/broken_fraction, "
                           "target.broken_at_stress_Pa with broken_fraction_at_stress or bonds_broken_at_stress, "
                           "or crush.bonds_broken)");
  return t;
}

double interpolate(const std::vector<double>& x, const std::vector<double>& y, double v) {
  if (v <= x.front()) return y.front();
  if (v >= x.back()) return y.back();
  const size_t i = static_cast<size_t>(std::upper_bound(x.begin(), x.end(), v) - x.begin());  // x[i-1] <= v < x[i]
  const double w = (v - x[i - 1]) / (x[i] - x[i - 1]);
  return y[i - 1] + w * (y[i] - y[i - 1]);
}

RunScore score_run(const Target& t, const Table& history, double initial_grains, double crush_bonds_broken) {
  using namespace objective_detail;
  RunScore s;
  s.crush_bonds_broken = crush_bonds_broken;
  const std::vector<double>& e = history.num("strain");
  const std::vector<double>& sig = history.num("top_stress_Pa");
  if (e.empty()) {
    s.objective = kNaN;
    return s;
  }
  s.final_strain = e.back();
  s.peak_stress_Pa = *std::max_element(sig.begin(), sig.end());
  std::vector<double> mpa;
  for (double x : sig) mpa.push_back(x / 1e6);
  s.yield_stress_Pa = yield_stress_mpa(e, mpa) * 1e6;
  const bool broken = history.has("grains_broken") && initial_grains > 0;
  if (broken) s.final_broken_fraction = history.num("grains_broken").back() / initial_grains;
  // History rows come every few hundred steps: allow half a percent of the
  // target's strain short of it (the run ends on its own target strain).
  if (s.final_strain < t.largest_strain() * 0.995) {
    s.objective = kNaN;
    return s;
  }
  double j = 0;
  if (!t.curve_strain.empty()) {
    std::vector<double> d;
    for (size_t i = 0; i < t.curve_strain.size(); ++i) d.push_back(interpolate(e, sig, t.curve_strain[i]) - t.curve_stress_Pa[i]);
    s.curve_misfit = rms(d) / rms(t.curve_stress_Pa);
    j += t.w_curve * s.curve_misfit;
  }
  if (t.yield_stress_Pa > 0) {
    s.yield_misfit = std::isfinite(s.yield_stress_Pa) ? std::abs(s.yield_stress_Pa - t.yield_stress_Pa) / t.yield_stress_Pa : 1.0;
    j += t.w_yield * s.yield_misfit;
  }
  if (!t.broken_strain.empty()) {
    if (!broken) throw InputError(history.source + ": no grains_broken column (breakage off?) for the broken-fraction target");
    std::vector<double> f;
    for (double x : history.num("grains_broken")) f.push_back(x / initial_grains);
    std::vector<double> d;
    for (size_t i = 0; i < t.broken_strain.size(); ++i) d.push_back(interpolate(e, f, t.broken_strain[i]) - t.broken_fraction[i]);
    s.broken_misfit = rms(d);
    j += t.w_broken * s.broken_misfit;
  }
  // The first row at or above each target stress (-1: never reached). A
  // run that never reaches it misses by 1, the largest difference of two
  // fractions: failing to harden that far is as wrong as a count can be.
  std::vector<long> at_stress;
  for (double x : t.broken_stress_Pa) {
    const auto row = std::find_if(sig.begin(), sig.end(), [&](double v) { return v >= x; });
    at_stress.push_back(row == sig.end() ? -1L : static_cast<long>(row - sig.begin()));
  }
  if (!t.broken_fraction_at_stress.empty()) {
    if (!broken) throw InputError(history.source + ": no grains_broken column (breakage off?) for the broken-at-stress target");
    const std::vector<double>& g = history.num("grains_broken");
    std::vector<double> d;
    for (size_t i = 0; i < at_stress.size(); ++i)
      d.push_back(at_stress[i] < 0 ? 1.0 : g[static_cast<size_t>(at_stress[i])] / initial_grains - t.broken_fraction_at_stress[i]);
    s.broken_stress_misfit = rms(d);
    j += t.w_broken_stress * s.broken_stress_misfit;
  }
  if (!t.bonds_broken_at_stress.empty()) {
    if (!history.has("bonds_broken"))
      throw InputError(history.source + ": no bonds_broken column (breakage off?) for the bonds-at-stress target");
    const std::vector<double>& b = history.num("bonds_broken");
    std::vector<double> d;
    for (size_t i = 0; i < at_stress.size(); ++i)
      d.push_back(at_stress[i] < 0 ? 1.0
                                   : std::min(1.0, std::abs(std::log10((b[static_cast<size_t>(at_stress[i])] + 1) /
                                                                       (t.bonds_broken_at_stress[i] + 1)))));
    s.bonds_misfit = rms(d);
    j += t.w_bonds * s.bonds_misfit;
  }
  if (t.crush_bonds_broken > 0) {
    if (!std::isfinite(crush_bonds_broken)) {
      s.objective = kNaN;
      return s;
    }
    s.crush_misfit = std::abs(crush_bonds_broken - t.crush_bonds_broken) / t.crush_bonds_broken;
    j += t.w_crush * s.crush_misfit;
  }
  s.objective = j;
  return s;
}

}  // namespace tg::dem::calibration
