// tomograin measure LABELS -o particles.csv   the particle table
// tomograin psd particles.csv [more...] -o psd.csv   gradings, shape classes, breakage
#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>

#include "apps/command.hpp"
#include "apps/jobs.hpp"
#include "core/errors.hpp"
#include "core/io/hdf5.hpp"
#include "core/io/volume_io.hpp"
#include "core/table.hpp"
#include "measure/particles.hpp"
#include "measure/psd.hpp"

namespace {

namespace fs = std::filesystem;
using namespace tg;

bool is_h5(const std::string& p) {
  const auto e = fs::path(p).extension().string();
  return e == ".h5" || e == ".hdf5";
}

// ---------------------------------------------------------------- measure


}  // namespace

namespace tg::app {

Volume<uint32_t> read_labels(const std::string& in, double voxel_um) {
  // An .h5 without a dataset name: its /labels (the file may also hold /volume).
  std::string spec = in;
  const auto [path, ds] = split_dataset_spec(in);
  if (format_of(in, false) == FileFormat::hdf5 && ds.empty() && H5Reader(path).has("/labels")) spec = path + ":/labels";
  ReadOptions ro;
  ro.voxel_um = voxel_um;
  Volume<uint32_t> labels = read_volume_as<uint32_t>(spec, ro);
  if (!labels.geometry().has_voxel_size()) throw InputError(in + ": no voxel size in the file; give --voxel-um");
  return labels;
}

int run_measure(const MeasureJob& o) {
  measure::ParticleOptions po;
  if (o.feret == "exact") {
    po.feret_exact = true;
  } else {
    try {
      size_t used = 0;
      po.feret_directions = std::stoi(o.feret, &used);
      if (used != o.feret.size()) throw std::invalid_argument(o.feret);
    } catch (const std::exception&) {
      throw UsageError("--feret must be a number of orientations (>= 3) or 'exact', got '" + o.feret + "'");
    }
  }
  po.sizing = o.sizing == "obb" ? measure::Sizing::obb : measure::Sizing::feret;
  po.stats.detection_limit_m = o.limit_mm * 1e-3;
  po.face_offset = o.face_offset;
  po.oriented_box = o.box || po.sizing == measure::Sizing::obb;
  po.contacts = !o.no_contacts;
  po.surface = o.surface;
  po.convex = o.convex;
  if (!o.columns.empty()) {
    const std::vector<std::string> known{"coordination", "surface", "sphericity", "convex", "solidity", "obb"};
    auto has = [&](const char* c) { return std::find(o.columns.begin(), o.columns.end(), c) != o.columns.end(); };
    for (const auto& c : o.columns)
      if (std::find(known.begin(), known.end(), c) == known.end())
        throw UsageError("--columns: unknown column group '" + c +
                         "' (valid: coordination, surface, sphericity, convex, solidity, obb)");
    po.contacts = has("coordination");
    po.surface = has("surface") || has("sphericity");
    po.convex = has("convex") || has("solidity");
    po.oriented_box = has("obb") || po.sizing == measure::Sizing::obb;
  }
  po.threads = o.threads;
  po.obb.random_seed = o.seed;
  for (const auto& out : o.out) {
    const auto e = fs::path(out).extension().string();
    if (e != ".csv" && !is_h5(out)) throw UsageError("-o " + out + ": expected a .csv or .h5 file");
  }

  const std::string path = split_dataset_spec(o.in).first;
  const Volume<uint32_t> labels = read_labels(o.in, o.voxel_um);

  const auto particles = measure::measure_particles(labels.view(), po);
  Table t = measure::particle_table(particles);
  const std::string sizing = measure::sizing_name(po);
  t.add_text("sizing", std::vector<std::string>(static_cast<size_t>(t.rows()), sizing));

  for (const auto& out : o.out) {
    if (!is_h5(out)) {
      write_csv(t, out);
      continue;
    }
    // The table beside the labels; writing into the input file keeps its
    // /volume but refuses to drop anything else.
    std::vector<std::pair<std::string, AnyVolume>> keep;
    if (fs::exists(out) && fs::exists(path) && fs::equivalent(out, path)) {
      H5Reader r(path);
      for (const auto& d : r.datasets()) {
        if (d == "/labels" || d.rfind("/particles/", 0) == 0) continue;
        if (d != "/volume")
          throw UsageError(out + " holds " + d + ", which rewriting it would drop: write the table to another .h5");
        keep.emplace_back(d, r.read_volume(d));
      }
    }
    H5Writer w(out);
    for (const auto& [name, v] : keep) w.write_volume(name, v);
    w.write_volume("/labels", labels);
    w.write_table("/particles", t);
    w.write_attribute("particles_sizing", sizing);
    w.commit();
  }
  int64_t below = 0, border = 0;
  for (const auto& p : particles) {
    below += p.stats.below_limit;
    border += p.stats.touches_border;
  }
  fmt::print("{}: {} particles ({} below {:g} mm, {} touching the border); d_max/d_med/d_min = {}\n", o.in,
             particles.size(), below, o.limit_mm, border,
             po.sizing == measure::Sizing::obb ? "oriented-box edges (obb)" : "Feret calipers (" + sizing + ")");
  for (const auto& out : o.out) fmt::print("wrote {}\n", out);
  return 0;
}

}  // namespace tg::app

namespace {

tg::app::Registrar reg_measure{{"measure", 40, [](CLI::App& app, CLI::App*& sub) -> tg::app::Runner {
  sub = app.add_subcommand(
      "measure",
      "Per-particle volume, centroid, size and shape from a label volume.\n\n"
      "Reads u32 labels (0 = void; an .h5 file's /labels by default) and writes one row per label:\n"
      "label, voxels, volume_mm3, cx_mm, cy_mm, cz_mm, d_eq_mm (equal-volume sphere), d_max_mm,\n"
      "d_min_mm, d_med_mm, fr = d_min/d_med, ar = d_max/d_min, obb_max/med/min_mm (CGAL oriented box),\n"
      "touches_border, below_limit, then the raw Feret calipers, bounding box and principal moments,\n"
      "the equivalent ellipsoid (ell_d1/2/3_mm, ell_axis1_z/y/x), convex_volume_mm3 and solidity with --convex,\n"
      "coordination (contacts with other labels, as `tomograin contacts` finds them), surface_mm2 and\n"
      "sphericity with --surface, and a `sizing` column naming the definition behind d_max/d_med/d_min.\n"
      "obb_* are 0 unless --box. fr is clamped to 1 where d_min > d_med (non-convex particles), and\n"
      "fr_clamped says where (docs/measure.md).\n"
      "Sizing 'feret' (default): calipers of the convex hull at --feret N quasi-uniform orientations\n"
      "(60, as in the reference study) or 'exact' (hull diameter and exact minimum widths: slower,\n"
      "the reference for N's bias); d_min is the smallest caliper perpendicular to d_max (its\n"
      "direction fitted over diameters within half a voxel of it, so flat fragments get their\n"
      "thickness) and d_med = 6V/(pi d_max d_min). Sizing 'obb': the oriented box's edges.\n"
      "Hull points sit a --face-offset fraction of half a voxel beyond each boundary voxel's\n"
      "centre, which keeps calipers of digitised spheres within ~0.3 % (measure/feret.hpp).\n"
      "Lengths in mm from the file's voxel size (or --voxel-um).\n\n"
      "Examples:\n"
      "  tomograin measure labels.h5 -o particles.csv\n"
      "  tomograin measure labels.h5 -o particles.csv -o particles.h5 --feret exact\n"
      "  tomograin measure labels.tif --voxel-um 11.6 --sizing obb -o particles.csv");
  auto o = std::make_shared<tg::app::MeasureJob>();
  sub->add_option("labels", o->in, "Label volume (u32): .h5[:/dataset], .tif, folder of slices, raw .json")->required();
  sub->add_option("-o,--output", o->out,
                  "Output table(s): .csv, or .h5 (/labels + /particles table; naming the input .h5 adds the "
                  "table to it). Repeatable: -o a.csv -o a.h5")
      ->required()
      ->allow_extra_args(false);  // one file per -o, so a positional after it stays the input
  sub->add_option("--feret", o->feret, "Feret orientations N (>= 3) or 'exact'")->default_str("60");
  sub->add_option("--sizing", o->sizing, "Definition behind d_max/d_med/d_min: feret or obb")
      ->check(CLI::IsMember({"feret", "obb"}))
      ->default_str("feret");
  sub->add_option("--detection-limit-mm", o->limit_mm, "Flag particles with d_eq below this (mm)")
      ->check(CLI::PositiveNumber)
      ->default_str("0.2");
  sub->add_option("--face-offset", o->face_offset,
                  "Hull points: boundary voxel centre + this x half a voxel towards each exposed face, in (0, 1] "
                  "(measure/feret.hpp explains the 0.3 default)")
      ->default_str("0.3");
  sub->add_flag("--box", o->box,
                "Also compute CGAL's oriented box (obb_* columns; implied by --sizing obb). Off by default: "
                "on real scans it took ~85 % of the time");
  sub->add_flag("--no-box", o->no_box, "Accepted for old scripts: the box is off unless --box");
  sub->add_flag("--no-contacts", o->no_contacts, "Skip the coordination column (contact search)");
  sub->add_option("--columns", o->columns,
                  "Optional column groups to compute, comma-separated, instead of the flags: coordination, "
                  "surface, sphericity, convex, solidity, obb (e.g. --columns coordination,sphericity; "
                  "the size/shape columns are always there)")
      ->delimiter(',');
  sub->add_flag("--convex", o->convex, "Also convex_volume_mm3 and solidity (builds the CGAL hull)");
  sub->add_flag("--surface", o->surface,
                "Also surface_mm2 (normal-weighted voxel faces, within 0.2 % on spheres of radius >= 20 voxels) "
                "and Wadell sphericity; costs several times the Feret step");
  sub->add_option("--seed", o->seed, "Random seed of CGAL's oriented-box optimiser")->default_str("42");
  sub->add_option("--threads", o->threads, "OpenMP threads (0 = all); results do not depend on it")
      ->check(CLI::NonNegativeNumber)
      ->default_str("0");
  tg::app::add_voxel_option(sub, o->voxel_um);
  return [o] { return tg::app::run_measure(*o); };
}}};

// ---------------------------------------------------------------- psd


Table read_particles(const std::string& file) {
  const std::vector<std::string> need{"volume_mm3", "d_med_mm", "d_eq_mm", "fr", "ar"};
  Table t;
  if (is_h5(file)) {
    const auto [path, ds] = split_dataset_spec(file);
    t = H5Reader(path).read_table(ds.empty() ? "/particles" : ds);
    t.source = file;
    for (const auto& c : need) t.num(c);  // throws naming the missing column
  } else {
    t = read_csv(file, need);
  }
  return t;
}

std::string num_name(double v) { return fmt::format("{:g}", v); }

std::vector<std::string> class_names(const std::string& what, const std::vector<double>& t) {
  std::vector<std::string> n;
  n.push_back(what + "_lt_" + num_name(t.front()) + "_pct");
  for (size_t k = 1; k < t.size(); ++k) n.push_back(what + "_" + num_name(t[k - 1]) + "_" + num_name(t[k]) + "_pct");
  n.push_back(what + "_ge_" + num_name(t.back()) + "_pct");
  return n;
}

}  // namespace

namespace tg::app {

int run_psd(PsdJob o) {
  if (o.sieves.empty()) o.sieves = measure::default_sieves_mm();
  if (o.names.size() != o.in.size()) o.names = o.in;
  std::sort(o.sieves.begin(), o.sieves.end());
  if (o.fr_bins.empty()) o.fr_bins = measure::fr_thresholds();
  if (o.ar_bins.empty()) o.ar_bins = measure::ar_thresholds();

  struct Stage {
    std::vector<double> mass, dmed, deq, fr, ar;
  };
  std::vector<Stage> stages;
  double largest = 0;
  for (const auto& f : o.in) {
    const Table t = read_particles(f);
    const std::vector<double> zero(static_cast<size_t>(t.rows()), 0.0);
    const auto& below = t.has("below_limit") ? t.num("below_limit") : zero;
    const auto& border = t.has("touches_border") ? t.num("touches_border") : zero;
    Stage s;
    for (int64_t r = 0; r < t.rows(); ++r) {
      if ((o.exclude_below && below[r] != 0) || (o.exclude_border && border[r] != 0)) continue;
      s.mass.push_back(t.num("volume_mm3")[r]);
      s.dmed.push_back(t.num("d_med_mm")[r]);
      s.deq.push_back(t.num("d_eq_mm")[r]);
      s.fr.push_back(t.num("fr")[r]);
      s.ar.push_back(t.num("ar")[r]);
      largest = std::max({largest, s.dmed.back(), s.deq.back()});
    }
    if (s.mass.empty()) throw InputError(f + ": no particles left to grade");
    stages.push_back(std::move(s));
  }
  // The coarsest sieve must pass everything: add the next R10 size if needed.
  if (largest > o.sieves.back()) o.sieves.push_back(std::pow(10.0, std::ceil(10 * std::log10(largest) - 1e-9) / 10));

  Table lng, sum;
  std::vector<double> st, sv, pmed, peq;
  std::vector<std::vector<double>> passing_med;
  std::vector<double> n, mass, d10, d50, d60, cu, d50eq, brh, bre;
  std::vector<std::vector<double>> frc(o.fr_bins.size() + 1), arc(o.ar_bins.size() + 1);
  for (size_t k = 0; k < stages.size(); ++k) {
    const auto& s = stages[k];
    const auto pm = measure::percent_passing(s.dmed, s.mass, o.sieves);
    const auto pe = measure::percent_passing(s.deq, s.mass, o.sieves);
    for (size_t q = 0; q < o.sieves.size(); ++q) {
      st.push_back(static_cast<double>(k + 1));
      sv.push_back(o.sieves[q]);
      pmed.push_back(pm[q]);
      peq.push_back(pe[q]);
    }
    passing_med.push_back(pm);
    const auto g = measure::grading_summary(o.sieves, pm);
    n.push_back(static_cast<double>(s.mass.size()));
    double m = 0;
    for (double v : s.mass) m += v;
    mass.push_back(m);
    d10.push_back(g.d10);
    d50.push_back(g.d50);
    d60.push_back(g.d60);
    cu.push_back(g.cu);
    d50eq.push_back(measure::grading_quantile(o.sieves, pe, 50));
    brh.push_back(measure::hardin_br(o.sieves, passing_med.front(), pm, o.hardin_cut));
    measure::EinavOptions eo;
    eo.fractal_dimension = o.fractal;
    eo.d_min = o.einav_dmin;
    bre.push_back(measure::einav_br(o.sieves, passing_med.front(), pm, eo));
    const auto fc = measure::class_percent(s.fr, o.fr_bins), ac = measure::class_percent(s.ar, o.ar_bins);
    for (size_t c = 0; c < fc.size(); ++c) frc[c].push_back(fc[c]);
    for (size_t c = 0; c < ac.size(); ++c) arc[c].push_back(ac[c]);
  }
  lng.add("stage", st);
  lng.add("sieve_mm", sv);
  lng.add("passing_dmed_pct", pmed);
  lng.add("passing_deq_pct", peq);
  sum.add("stage", [&] { std::vector<double> v; for (size_t k = 0; k < stages.size(); ++k) v.push_back(double(k + 1)); return v; }());
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
  const auto fn = class_names("fr", o.fr_bins), an = class_names("ar", o.ar_bins);
  for (size_t c = 0; c < fn.size(); ++c) sum.add(fn[c], frc[c]);
  for (size_t c = 0; c < an.size(); ++c) sum.add(an[c], arc[c]);

  const std::string summary =
      !o.summary.empty() ? o.summary : (fs::path(o.out).parent_path() / (fs::path(o.out).stem().string() + "_summary.csv")).string();
  write_csv(lng, o.out);
  write_csv(sum, summary);
  fmt::print("{:>5} {:>9} {:>8} {:>8} {:>6} {:>8} {:>8}  file\n", "stage", "particles", "D50 mm", "D10 mm", "Cu",
             "Br", "Br*");
  for (size_t k = 0; k < stages.size(); ++k)
    fmt::print("{:>5} {:>9} {:>8.4f} {:>8.4f} {:>6.3f} {:>8.4f} {:>8.4f}  {}\n", k + 1, n[k], d50[k], d10[k], cu[k],
               brh[k], bre[k], o.names[k]);
  fmt::print("wrote {} and {}\n", o.out, summary);
  return 0;
}

}  // namespace tg::app

namespace {

tg::app::Registrar reg_psd{{"psd", 45, [](CLI::App& app, CLI::App*& sub) -> tg::app::Runner {
  sub = app.add_subcommand(
      "psd",
      "Grading (PSD by mass), D10/D50/D60/Cu, FR/AR classes and breakage of one or more stages.\n\n"
      "Each input is a particle table from `tomograin measure` (.csv, or .h5 with a /particles table);\n"
      "the first is the initial grading. Mass = volume (uniform density). Percent passing at each\n"
      "sieve is by d_med (the study's size) and by d_eq; D-values interpolate log-linearly between\n"
      "sieves. Br (Hardin 1985) and Br* (Einav 2007, fractal ultimate grading) compare each stage\n"
      "with the first, on the d_med grading (formulas: measure/psd.hpp).\n"
      "Writes OUT (stage, sieve_mm, passing_dmed_pct, passing_deq_pct) and OUT_summary.csv (one row\n"
      "per stage: D-values, Cu, Br, Br*, % of particles in each FR and AR class).\n\n"
      "Examples:\n"
      "  tomograin psd particles.csv -o psd.csv\n"
      "  tomograin psd stage0.csv stage1.csv stage2.csv -o psd.csv --exclude-below-limit\n"
      "  tomograin psd p.csv -o psd.csv --sieves-mm 0.2,0.4,0.8,1.6 --fr-bins 0.5,0.7,0.9");
  auto o = std::make_shared<tg::app::PsdJob>();
  sub->add_option("tables", o->in, "Particle tables, initial stage first")->required()->check(CLI::ExistingFile);
  sub->add_option("-o,--output", o->out, "Grading table (.csv)")->required();
  sub->add_option("--summary", o->summary, "Per-stage summary (.csv; default OUT_summary.csv)");
  sub->add_option("--sieves-mm", o->sieves,
                  "Sieve sizes in mm, comma-separated (default R10 series 0.1 ... 2.5; a coarser one is added "
                  "when a particle exceeds the largest)")
      ->delimiter(',');
  sub->add_option("--fr-bins", o->fr_bins, "FR class thresholds (default 0.4,0.8,0.9)")->delimiter(',');
  sub->add_option("--ar-bins", o->ar_bins, "AR class thresholds (default 2,3)")->delimiter(',');
  sub->add_flag("--exclude-below-limit", o->exclude_below, "Leave out particles flagged below_limit");
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

}  // namespace
