#include "study/summary.hpp"

#include <cmath>
#include <limits>

#include "core/errors.hpp"
#include "core/table.hpp"

namespace tg::study {
namespace fs = std::filesystem;
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The value of `column` in the last row whose `key` column equals `value`.
double last_where(const Table& t, const std::string& key, const std::string& value, const std::string& column) {
  if (!t.has(key) || !t.has(column)) return kNaN;
  const auto& k = t.text(key);
  const auto& c = t.num(column);
  double v = kNaN;
  for (size_t i = 0; i < k.size(); ++i)
    if (k[i] == value) v = c[i];
  return v;
}

double last(const Table& t, const std::string& column) {
  return t.has(column) && !t.num(column).empty() ? t.num(column).back() : kNaN;
}

Table read_if(const fs::path& p) { return fs::exists(p) ? read_csv(p) : Table{}; }

}  // namespace

void write_summary(const Study& s, const Plan& p, const fs::path& out_csv) {
  // The experiment: the last stage's grading, the lineage's broken share.
  const Stage& last_stage = s.stages.back();
  const Table psd = read_if(p.dir / "stages" / last_stage.name / "psd_summary.csv");
  const Table track = read_if(p.dir / "track" / "summary.csv");
  const double d50_x = last(psd, "d50_mm"), cu_x = last(psd, "cu");
  const double broken_x = last(track, "pct_intact_broken");

  RowTable t({"study", "variant", "stages", "final_strain", "d50_mm_experiment", "cu_experiment",
              "pct_broken_experiment", "d50_mm_dem", "cu_dem", "pct_broken_dem", "yield_mpa_dem", "peak_mpa_dem",
              "psd_ks", "fr_ks", "ar_ks"});
  const int64_t n = static_cast<int64_t>(s.stages.size());
  if (s.dem_config.empty()) {
    t.row({s.name, "", n, last_stage.strain, d50_x, cu_x, broken_x, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN});
  }
  for (size_t v = 0; v < s.variants.size() && !s.dem_config.empty(); ++v) {
    const std::string suffix = s.variants[v].name.empty() ? "" : "-" + s.variants[v].name;
    const fs::path rep = p.dir / ("report" + suffix);
    const Table sum = read_csv(rep / "summary.csv");
    const Table dist = read_csv(rep / "distances.csv");
    // The DEM as imaged (segmented like the scans) when the report has it, else its truth labels.
    const std::string dem_series = [&] {
      for (const auto& x : sum.text("series"))
        if (x == "dem_imaged") return std::string("dem_imaged");
      return std::string("dem_ideal");
    }();
    const std::string pair = dem_series == "dem_imaged" ? "experiment_vs_dem_imaged" : "experiment_vs_dem_ideal";
    const Table hist = read_if(p.dir / ("dem" + suffix) / "history.csv");
    std::vector<double> stress;
    if (hist.has("top_stress_Pa"))
      for (double x : hist.num("top_stress_Pa")) stress.push_back(x / 1e6);
    double peak = kNaN;
    for (double x : stress) peak = std::isnan(peak) ? x : std::max(peak, x);
    const double yield = hist.has("strain") ? yield_stress_mpa(hist.num("strain"), stress) : kNaN;
    t.row({s.name, s.variants[v].name, n, last_stage.strain, d50_x, cu_x, broken_x,
           last_where(sum, "series", dem_series, "d50_mm"), last_where(sum, "series", dem_series, "cu"),
           100 * last_where(sum, "series", "dem_ideal", "broken_fraction"), yield, peak,
           last_where(dist, "pair", pair, "psd_ks"), last_where(dist, "pair", pair, "fr_ks"),
           last_where(dist, "pair", pair, "ar_ks")});
  }
  write_csv(t.table(), out_csv);
}

}  // namespace tg::study
