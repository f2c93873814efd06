// run_comparison: the steps of comparison.hpp's header, in order. Each step
// lives in its own file: the experiment's stage (xct_stage), the DEM's
// snapshots and imaging (dem_stage), pairing and broken fractions
// (stage_matching), the grading (measure/grading), the files (report_files).
#include "compare/comparison.hpp"

#include <fmt/core.h>

#include <chrono>
#include <cmath>

#include "core/clock.hpp"
#include "compare/dem_lineage.hpp"
#include "compare/dem_stage.hpp"
#include "compare/report_files.hpp"
#include "compare/xct_stage.hpp"
#include "dem/yield_stress.hpp"
#include "core/errors.hpp"
#include "core/memory.hpp"

namespace tg::compare {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

void check_inputs(const CompareInputs& in) {
  if (in.xct.empty()) throw UsageError("compare: give at least one XCT stage (--xct)");
  if (in.dem_run.empty() && in.dem_snapshots.empty()) throw UsageError("compare: give a DEM run folder (--dem)");
  if (in.report_dir.empty()) throw UsageError("compare: give the report folder (-o)");
  if (!in.xct_strains.empty() && in.xct_strains.size() != in.xct.size())
    throw UsageError("compare: give one XCT strain per stage (" + std::to_string(in.xct.size()) + ")");
  if (!in.stage_names.empty() && in.stage_names.size() != in.xct.size())
    throw UsageError("compare: give one stage name per XCT stage");
}

std::string stage_name(const CompareInputs& in, size_t n, double strain) {
  if (!in.stage_names.empty()) return in.stage_names[n];
  return fmt::format("stage {}{}", n, std::isfinite(strain) ? fmt::format(" (strain {:.2f} %)", 100 * strain) : "");
}

// A tracker's last labels go to disk until the next stage when they are
// large beside the memory left: the next stage's segmentation and, on the
// DEM side, its voxelised truth and imaged labels come before they are
// needed again. Five 1220^3 stages with the DEM lineage held two previous
// stages in memory and ran out at 21.6 GB (bench/scale/RESULTS.md). The
// lineage does not change; each spill costs a write and a read of the labels.
void spill_if_large(track::Tracker& t, const fs::path& file) {
  if (t.held_bytes() > available_memory_bytes() / 4) t.spill(file.string());
}

// Notes on what the report lacks, joined.
void add_note(std::string& notes, const std::string& s) { notes += (notes.empty() ? "" : "; ") + s; }

}  // namespace

Report run_comparison(const CompareInputs& in, const CompareOptions& opt) {
  const auto t_all = std::chrono::steady_clock::now();
  check_inputs(in);
  const DemInputs dem = load_dem_inputs(in);
  const Curve expc = in.experimental_curve.empty() ? Curve{} : read_curve(in.experimental_curve);
  const fs::path out(in.report_dir);
  fs::create_directories(out / "slices");
  fs::create_directories(out / "particles");
  // Segmentation scale and the initial grain count from the first snapshot.
  const ParticleScale scale0 = particle_scale(read_spheres(dem.snapshots.front()));

  Report rep;
  rep.dir = out;
  // The experiment's grains tracked stage to stage (track/): each stage's
  // labels go to the tracker once measured; it keeps only the previous one.
  std::optional<track::Tracker> tracker;
  if (opt.track && in.xct.size() >= 2) tracker.emplace(opt.tracking);
  std::vector<XctStage> xs;
  std::vector<Series> ideal(in.xct.size()), imaged(in.xct.size());
  std::vector<ContactSeries> exact(in.xct.size());  // the DEM's own contacts (from its spheres)
  std::vector<measure::GradingSample> exact_shapes(in.xct.size());  // and its particles' shapes
  // The DEM's lineage at the same stages (compare/dem_lineage.hpp): which
  // snapshot each stage is, and its truth labels; and the tracker run on the
  // imaged DEM labels, each stage put on the first stage's grid (a scanner's
  // one field of view), with each stage's imaged -> truth label map to score it.
  const bool dem_track = opt.track && in.xct.size() >= 2;
  std::vector<size_t> stage_snapshot;
  std::vector<std::map<int64_t, uint32_t>> label_of;
  std::optional<track::Tracker> dem_tracker;
  // The snapshots' order is the DEM's own (its index, by strain): the guard against stages given out of
  // order is not needed there, and would stop on the map's scatter between close snapshots (measured: an
  // axial scale of 1.003 between 0 and 1 % strain on the imaged path, docs/compare.md).
  track::TrackOptions dem_tracking = opt.tracking;
  dem_tracking.allow_extension = true;
  if (dem_track && opt.imaged_path) dem_tracker.emplace(dem_tracking);
  std::vector<track::LabelMap> dem_maps;
  Shape grid0;
  Geometry geom0;
  for (size_t n = 0; n < in.xct.size(); ++n) {
    const auto t0 = std::chrono::steady_clock::now();
    const bool own_peak = reset_peak_rss();
    const std::string stem = "stage" + std::to_string(n);
    XctStage x = load_xct_stage(in.xct[n], opt, scale0.median_radius_m, out / "slices", stem);
    const int64_t stage_voxels = x.labels.size();
    if (!in.xct_strains.empty()) x.strain = in.xct_strains[n];
    if (tracker && x.labels.empty()) {
      tracker.reset();
      rep.tracking_note = in.xct[n] + " is a particle table: no labels to track";
    }
    if (tracker) {
      try {
        tracker->add_stage(std::move(x.labels), in.xct[n], std::move(x.scan));
      } catch (const InputError& e) {  // the report goes on without a lineage, and says why
        tracker.reset();
        rep.tracking_note = std::string("tracking stopped: ") + e.what();
      }
    }
    x.labels = Volume<uint32_t>{};  // only the tracker keeps a stage's labels (the previous one), and its scan
    x.scan = Volume<uint16_t>{};
    const bool last = n + 1 == in.xct.size();
    if (tracker) last ? tracker->finish() : spill_if_large(*tracker, out / ".tracker_xct.h5");
    const size_t m = match_snapshot(dem.strains, x.strain, n);
    const double vox_m = opt.voxel_um > 0 ? opt.voxel_um * 1e-6 : x.geometry.voxel_size_m[0];
    if (!(vox_m > 0)) throw UsageError("compare: " + in.xct[n] + " has no voxel size: give --voxel-um");
    const bool like = opt.like_scan && x.grey;
    DemStage d = image_snapshot(dem.snapshots[m], vox_m, like ? imaging_like(*x.grey, opt.voxelise.imaging) : opt.voxelise.imaging,
                                like ? "estimated from the XCT scan: " + x.grey->method : "defaults", opt,
                                segment_options(opt, scale0.median_radius_m, vox_m), out / "slices", stem, dem_track);
    if (dem_track) {
      stage_snapshot.push_back(m);
      std::map<int64_t, uint32_t> labels;
      for (size_t l = 1; l < d.particle_of_label.size(); ++l) labels[d.particle_of_label[l]] = static_cast<uint32_t>(l);
      label_of.push_back(std::move(labels));
      if (n == 0) grid0 = d.truth_labels.shape(), geom0 = d.truth_labels.geometry();
      if (dem_tracker && std::abs(vox_m - geom0.voxel_size_m[0]) > 1e-6 * vox_m) {
        dem_tracker.reset();
        add_note(rep.dem_lineage_note, "imaged DEM path not tracked: the stages have different voxel sizes");
      }
      if (dem_tracker) {
        dem_maps.push_back(track::correspondence(d.imaged_labels, d.truth_labels));
        // Each volume goes as soon as it has served: at full size the stage's
        // truth, its imaged labels, their copy on the first grid and the
        // tracker's previous stage would be 16 B/voxel at once.
        d.truth_labels = Volume<uint32_t>{};
        Volume<uint32_t> imaged_on_grid0 = on_grid(d.imaged_labels, grid0, geom0);
        d.imaged_labels = Volume<uint32_t>{};
        try {
          dem_tracker->add_stage(std::move(imaged_on_grid0), dem.snapshots[m]);
        } catch (const InputError& e) {
          dem_tracker.reset();
          add_note(rep.dem_lineage_note, std::string("imaged DEM path not tracked: ") + e.what());
        }
      }
      d.truth_labels = Volume<uint32_t>{};
      d.imaged_labels = Volume<uint32_t>{};
      if (dem_tracker) last ? dem_tracker->finish() : spill_if_large(*dem_tracker, out / ".tracker_dem.h5");
    }
    const BrokenEstimate b = dem_broken_fraction(dem.history, dem.strains[m], d.particles, scale0.particles);
    ideal[n] = std::move(d.ideal);
    imaged[n] = std::move(d.imaged);
    exact[n] = std::move(d.exact);
    exact_shapes[n] = std::move(d.exact_shapes);
    ideal[n].broken_fraction = imaged[n].broken_fraction = b.fraction;
    ideal[n].broken_method = imaged[n].broken_method = b.method;

    StageReport st;
    st.name = stage_name(in, n, x.strain);
    st.xct_strain = x.strain;
    st.dem_strain = dem.strains[m];
    st.xct_source = in.xct[n];
    st.dem_snapshot = dem.snapshots[m];
    st.synthetic = x.synthetic;
    st.n_experiment = static_cast<int64_t>(x.s.sample.size_mm.size());
    st.n_ideal = static_cast<int64_t>(ideal[n].sample.size_mm.size());
    st.n_imaged = static_cast<int64_t>(imaged[n].sample.size_mm.size());
    st.exp_vs_ideal = sample_distances(x.s.sample, ideal[n].sample);
    st.exp_vs_imaged = sample_distances(x.s.sample, imaged[n].sample);
    st.ideal_vs_imaged = sample_distances(ideal[n].sample, imaged[n].sample);
    st.seconds = seconds_since(t0);
    st.peak_rss_bytes = peak_rss_bytes();
    st.own_peak = own_peak;
    st.voxels = stage_voxels;
    rep.stages.push_back(st);
    write_csv(x.s.particles, out / "particles" / (stem + "_experiment.csv"));
    write_csv(ideal[n].particles, out / "particles" / (stem + "_dem_ideal.csv"));
    if (opt.imaged_path) write_csv(imaged[n].particles, out / "particles" / (stem + "_dem_imaged.csv"));
    xs.push_back(std::move(x));
  }

  if (tracker) {
    rep.tracking = tracker->result();
    track::write_outputs(*rep.tracking, (out / "tracking").string());
  }
  if (dem_track) {
    const double lineage_vox = geom0.voxel_size_m[0];
    if (!in.dem_snapshots.empty()) {
      add_note(rep.dem_lineage_note,
               "explicit DEM snapshots: the exact lineage needs every snapshot of the run (give --dem RUNDIR)");
    } else {
      try {
        std::vector<SnapshotLineage> chain;
        for (const auto& p : dem.snapshots) chain.push_back(read_snapshot_lineage(p));
        rep.dem_exact = dem_lineage(chain, stage_snapshot, label_of, lineage_vox, opt.tracking);
        track::write_outputs(*rep.dem_exact, (out / "dem_lineage").string());
      } catch (const InputError& e) {  // the report goes on without it, and says why
        add_note(rep.dem_lineage_note, std::string("no exact DEM lineage: ") + e.what());
      } catch (const UsageError& e) {  // stages matched to snapshots out of order
        add_note(rep.dem_lineage_note, std::string("no exact DEM lineage: ") + e.what());
      }
    }
    if (dem_tracker) {
      rep.dem_imaged = dem_tracker->result();
      track::write_outputs(*rep.dem_imaged, (out / "dem_imaged_tracking").string());
      if (rep.dem_exact) rep.tracker_bias = track::evaluate(*rep.dem_imaged, rep.dem_exact->lineage, dem_maps);
    }
  }

  // One grading for every series, on sieves common to all of them; Br against each series' first stage.
  const size_t nseries = opt.imaged_path ? 3 : 2;
  auto series_of = [&](size_t n, size_t k) -> Series& { return k == 0 ? xs[n].s : k == 1 ? ideal[n] : imaged[n]; };
  std::vector<const measure::GradingSample*> all;
  for (size_t n = 0; n < xs.size(); ++n)
    for (size_t k = 0; k < nseries; ++k) all.push_back(&series_of(n, k).sample);
  rep.sieves_mm = measure::sieves_covering({}, all);
  for (size_t k = 0; k < nseries; ++k) {
    std::vector<measure::GradingSample> samples;
    for (size_t n = 0; n < xs.size(); ++n) samples.push_back(series_of(n, k).sample);
    const auto g = measure::grade_stages(samples, rep.sieves_mm);
    for (size_t n = 0; n < xs.size(); ++n) series_of(n, k).metrics = g[n];
  }
  for (size_t n = 0; n < xs.size(); ++n) {
    rep.stages[n].experiment = xs[n].s.metrics;
    rep.stages[n].ideal = ideal[n].metrics;
    rep.stages[n].imaged = imaged[n].metrics;
    if (rep.dem_exact) {  // the DEM's own lineage: exact, and the same definition as the experiment's
      ideal[n].broken_fraction = imaged[n].broken_fraction = rep.dem_exact->summary[n].pct_intact_broken / 100;
      ideal[n].broken_method = imaged[n].broken_method =
          "DEM lineage (compare/dem_lineage.hpp): grains of the first compared snapshot with a breakage event";
    }
    if (std::isfinite(xs[n].s.broken_fraction)) continue;  // synthetic truth
    if (rep.tracking) {  // the lineage: stage-0 grains with a breakage event in their chain
      xs[n].s.broken_fraction = rep.tracking->summary[n].pct_intact_broken / 100;
      xs[n].s.broken_method = "tracking (track/): stage-0 grains with a breakage event in their lineage";
    } else {  // the particle count's growth against stage 0
      xs[n].s.broken_fraction = count_growth_fraction(static_cast<int64_t>(xs[n].s.sample.size_mm.size()),
                                                      static_cast<int64_t>(xs[0].s.sample.size_mm.size()));
      xs[n].s.broken_method = "particle count growth against stage 0 (one extra particle per break)";
    }
  }

  ReportData data;
  data.report = &rep;
  for (size_t n = 0; n < xs.size(); ++n) {
    data.series.push_back({&xs[n].s, &ideal[n], opt.imaged_path ? &imaged[n] : nullptr});
    data.grey.push_back(xs[n].grey ? &*xs[n].grey : nullptr);
    data.exact.push_back(&exact[n]);
    data.exact_shapes.push_back(&exact_shapes[n]);
  }
  data.history = dem.history;
  data.experiment_curve = expc;
  data.initial_dem_particles = scale0.particles;
  write_report_tables(out, data);
  json meta;
  meta["title"] = in.title;
  meta["notes"] = in.notes;
  meta["dem_run"] = in.dem_run;
  meta["dem_snapshots"] = dem.snapshots;
  meta["sizing"] = measure::sizing_name(opt.measure);
  meta["imaged_path"] = opt.imaged_path;
  meta["tracking"] = rep.tracking ? json("tracking/ (lineage.csv, events.csv, summary.csv)") : json(rep.tracking_note);
  meta["dem_lineage"] = lineage_json(rep);
  meta["segmentation_grain_radius_m"] = opt.grain_radius_vox > 0 ? json(nullptr) : json(scale0.median_radius_m);
  // Yield of each curve by the one rule the study summary and calibration use (null: no yield found).
  auto yield_of = [](const Curve& c) {
    const double y = dem::yield_stress_mpa(c.strain, c.stress_mpa);
    return std::isfinite(y) ? json(y) : json(nullptr);
  };
  meta["yield"] = {{"dem_mpa", yield_of(dem.history)},
                   {"experiment_mpa", yield_of(expc)},
                   {"rule", "bilinear strain-log10(stress) fit above 0.1 MPa (dem/yield_stress.hpp)"}};
  rep.seconds = seconds_since(t_all);
  meta["compute_seconds"] = rep.seconds;
  write_report_json(out, data, meta);
  if (opt.plots) rep.index_html = run_plot_script(out, opt.python, opt.script);
  rep.seconds = seconds_since(t_all);
  return rep;
}

}  // namespace tg::compare
