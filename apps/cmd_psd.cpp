// tomograin psd particles.csv [more...] -o psd.csv   gradings, shape classes, breakage
// The grading itself is measure/grading.hpp (the same one the report uses).
#include <fmt/core.h>

#include <memory>

#include "apps/command.hpp"
#include "apps/jobs.hpp"
#include "core/errors.hpp"
#include "core/io/hdf5.hpp"
#include "core/io/volume_io.hpp"
#include "core/table.hpp"
#include "measure/grading.hpp"

namespace cmd_psd {

using namespace tg;

Table read_particles(const std::string& file) {
  const std::vector<std::string> need{"volume_mm3", "d_med_mm", "d_eq_mm", "fr", "ar"};
  if (!is_hdf5(file)) return read_csv(file, need);
  const auto [path, ds] = split_dataset_spec(file);
  Table t = H5Reader(path).read_table(ds.empty() ? "/particles" : ds);
  t.source = file;
  for (const auto& c : need) t.num(c);  // throws naming the missing column
  return t;
}

}  // namespace cmd_psd

namespace tg::app {

int run_psd(PsdJob o) {
  if (o.names.size() != o.in.size()) o.names = o.in;
  measure::SampleRules rules;
  rules.exclude_below_limit = o.exclude_below;
  rules.exclude_border = o.exclude_border;
  std::vector<measure::GradingSample> stages;
  for (const auto& f : o.in) {
    stages.push_back(measure::grading_sample(cmd_psd::read_particles(f), rules));
    if (stages.back().size_mm.empty()) throw InputError(f + ": no particles left to grade");
  }
  std::vector<const measure::GradingSample*> all;
  for (const auto& s : stages) all.push_back(&s);
  const std::vector<double> sieves = measure::sieves_covering(o.sieves, all);
  measure::GradingOptions go;
  if (!o.fr_bins.empty()) go.fr_bins = o.fr_bins;
  if (!o.ar_bins.empty()) go.ar_bins = o.ar_bins;
  go.hardin_cutoff_mm = o.hardin_cut;
  go.einav.fractal_dimension = o.fractal;
  go.einav.d_min = o.einav_dmin;
  const std::vector<measure::StageGrading> g = measure::grade_stages(stages, sieves, go);

  Table lng, sum;
  std::vector<double> st, sv, pmed, peq;
  std::vector<double> k1, n, mass, d10, d50, d60, cu, d50eq, brh, bre;
  std::vector<std::vector<double>> frc(go.fr_bins.size() + 1), arc(go.ar_bins.size() + 1);
  for (size_t k = 0; k < g.size(); ++k) {
    for (size_t q = 0; q < sieves.size(); ++q) {
      st.push_back(static_cast<double>(k + 1));
      sv.push_back(sieves[q]);
      pmed.push_back(g[k].passing[q]);
      peq.push_back(g[k].passing_eq[q]);
    }
    k1.push_back(static_cast<double>(k + 1));
    n.push_back(static_cast<double>(g[k].particles));
    mass.push_back(g[k].mass);
    d10.push_back(g[k].d.d10);
    d50.push_back(g[k].d.d50);
    d60.push_back(g[k].d.d60);
    cu.push_back(g[k].d.cu);
    d50eq.push_back(g[k].d50_eq);
    brh.push_back(g[k].hardin_br);
    bre.push_back(g[k].einav_br);
    for (size_t c = 0; c < frc.size(); ++c) frc[c].push_back(g[k].fr_classes[c]);
    for (size_t c = 0; c < arc.size(); ++c) arc[c].push_back(g[k].ar_classes[c]);
  }
  lng.add("stage", st);
  lng.add("sieve_mm", sv);
  lng.add("passing_dmed_pct", pmed);
  lng.add("passing_deq_pct", peq);
  sum.add("stage", k1);
  sum.add_text("file", o.names);
  sum.add("particles", n);
  sum.add("volume_mm3", mass);
  sum.add("d10_mm", d10);
  sum.add("d50_mm", d50);
  sum.add("d60_mm", d60);
  sum.add("cu", cu);
  sum.add("d50_eq_mm", d50eq);
  sum.add("br_hardin", brh);
  sum.add("br_einav", bre);
  const auto fn = measure::class_columns("fr", go.fr_bins), an = measure::class_columns("ar", go.ar_bins);
  for (size_t c = 0; c < fn.size(); ++c) sum.add(fn[c], frc[c]);
  for (size_t c = 0; c < an.size(); ++c) sum.add(an[c], arc[c]);

  const std::string summary = !o.summary.empty() ? o.summary : beside(o.out, "_summary.csv");
  write_csv(lng, o.out);
  write_csv(sum, summary);
  fmt::print("{:>5} {:>9} {:>8} {:>8} {:>6} {:>8} {:>8}  file\n", "stage", "particles", "D50 mm", "D10 mm", "Cu",
             "Br", "Br*");
  for (size_t k = 0; k < g.size(); ++k)
    fmt::print("{:>5} {:>9} {:>8.4f} {:>8.4f} {:>6.3f} {:>8.4f} {:>8.4f}  {}\n", k + 1, n[k], d50[k], d10[k], cu[k],
               brh[k], bre[k], o.names[k]);
  fmt::print("wrote {} and {}\n", o.out, summary);
  return 0;
}

}  // namespace tg::app

namespace cmd_psd {

tg::app::Registrar reg_psd{{"psd", 45,
      "Grading (PSD by mass), D10/D50/D60/Cu, FR/AR classes and breakage of one or more stages.\n\n"
      "Each input is a particle table from `tomograin measure` (.csv, or .h5 with a /particles table);\n"
      "the first is the initial grading. Mass = volume (uniform density). D-values come from the sorted\n"
      "table (exact whatever the sieves: log-linear between the two particles that bracket the percent);\n"
      "percent passing at each sieve is by d_med (the study's size) and by d_eq. Particles flagged below\n"
      "the detection limit count in the mass but not in the FR/AR classes (their shape is not resolved).\n"
      "Br (Hardin 1985) and Br* (Einav 2007, fractal ultimate grading) compare each stage with the first,\n"
      "on the d_med sieve curve (formulas: measure/psd.hpp; rules: measure/grading.hpp).\n"
      "Writes OUT (stage, sieve_mm, passing_dmed_pct, passing_deq_pct) and OUT_summary.csv (one row\n"
      "per stage: D-values, Cu, Br, Br*, % of particles in each FR and AR class).\n\n"
      "Examples:\n"
      "  tomograin psd particles.csv -o psd.csv\n"
      "  tomograin psd stage0.csv stage1.csv stage2.csv -o psd.csv --exclude-below-limit\n"
      "  tomograin psd p.csv -o psd.csv --sieves-mm 0.2,0.4,0.8,1.6 --fr-bins 0.5,0.7,0.9",
      [](CLI::App* sub) -> tg::app::Runner {
  auto o = std::make_shared<tg::app::PsdJob>();
  sub->add_option("tables", o->in, "Particle tables, initial stage first")->required();  // a missing file: read_particles says which (and "f.h5:/particles" is no file name)
  sub->add_option("-o,--output", o->out, "Grading table (.csv)")->required();
  sub->add_option("--summary", o->summary, "Per-stage summary (.csv; default OUT_summary.csv)");
  sub->add_option("--sieves-mm", o->sieves,
                  "Sieve sizes in mm, comma-separated (default: the R40 series 10^(k/40) from 0.1 to 2.5 mm); "
                  "R40 sizes are added so that the largest sieve passes 100 % and the smallest lies at or "
                  "below the finest particle")
      ->delimiter(',');
  sub->add_option("--fr-bins", o->fr_bins, "FR class thresholds (default 0.4,0.8,0.9)")->delimiter(',');
  sub->add_option("--ar-bins", o->ar_bins, "AR class thresholds (default 2,3)")->delimiter(',');
  sub->add_flag("--exclude-below-limit", o->exclude_below,
                "Leave particles flagged below_limit out of everything (by default they count in the mass only)");
  sub->add_flag("--exclude-border", o->exclude_border, "Leave out particles touching the volume's border");
  sub->add_option("--hardin-cutoff-mm", o->hardin_cut, "Hardin's cut-off size (mm)")
      ->check(CLI::PositiveNumber)
      ->default_str("0.074");
  sub->add_option("--fractal-dimension", o->fractal, "Einav's ultimate grading fractal dimension (< 3)")
      ->default_str("2.6");
  sub->add_option("--einav-dmin-mm", o->einav_dmin, "Smallest size of Einav's integrals (0 = smallest sieve)")
      ->default_str("0");
  return [o] { return tg::app::run_psd(*o); };
}}};

}  // namespace cmd_psd
