// The validation comparison: experiment (XCT stages) beside simulation (DEM
// snapshots) at matched axial strains, measured by the same code, and the
// report folder that shows it (../shared/DESIGN.md "Data flow";
// reference study §4.3, Figs. 9–14).
//
// Per XCT stage:
//   experiment   a scan (grey u16: segment() + measure, exactly the imaged
//                path below) or a particle table CSV (tomograin measure)
//   DEM snapshot the one whose axial strain is nearest (by order when strains
//                are unknown), voxelised at the scan's voxel size
//                (compare/voxelise.hpp) with grey levels and noise estimated
//                from that scan's histogram (compare/imaging_estimate.hpp)
//   dem_ideal    measure the voxelised TRUTH labels: the DEM particles as
//                they are, no segmentation
//   dem_imaged   segment() the voxelised grey scan and measure it, with the
//                same SegmentOptions and ParticleOptions as the experiment
//   dem_exact    the snapshot's own contacts (sphere pairs), for the contact
//                fabric (compare/fabric.hpp), and its particles' FR and AR
//                classes from their spheres, every particle however small
//   distances    KS and W1 of PSD (Dmed by mass), FR, AR for
//                experiment–dem_imaged, experiment–dem_ideal and
//                dem_ideal–dem_imaged (= the segmentation bias)
// Plus the stress–strain curve (DEM history.csv, optional experimental CSV)
// and broken grains versus strain.
//
// Report folder (every number behind every plot is a CSV/JSON file there):
//   report.json         metadata, stages, options, imaging estimates, timings
//   summary.csv         stage, series, strain, particles, D10/D50/D60/Cu, Br, broken fraction,
//                       mean coordination of interior particles (contacts from the labels)
//   tracking/           the experiment's lineage, events, summary (track/), with >= 2 volumes
//   dem_lineage/        the DEM's exact lineage between the compared snapshots (same tables),
//                       when the run's snapshots carry previous_particle (compare/dem_lineage.hpp)
//   dem_imaged_tracking/ the tracker run on the imaged DEM labels (same tables)
//   lineage.csv         stage, series (experiment | dem_exact | dem_imaged), particles,
//                       grains_intact, grains_broken, pct_intact_broken, split, fragmentation,
//                       chipping, chips, lost, new, breaks_band1..5, pct_broken_band1..5
//   tracker_bias.csv    stage ("all" or a stage), quantity, value, count: the tracker's bias on
//                       DEM data (dem_imaged scored against dem_exact by track::evaluate)
//   psd.csv             stage, series, sieve_mm, passing_pct
//   shape_classes.csv   stage, series, metric (fr|ar), class, percent; series adds
//                       dem_exact: every DEM particle's shape from its spheres, no
//                       detection limit (compare/dem_stage.hpp exact_shape_sample)
//   distances.csv       stage, pair, psd_ks, psd_w1_mm, fr_ks, fr_w1, ar_ks, ar_w1
//   stress_strain.csv   series, strain, stress_mpa
//   broken.csv          series, strain, broken_fraction, grains_broken, bonds_broken (DEM history counts)
//   fabric.csv          stage, series, n_contacts, N_zz, N_yy, N_xx, N_zy, N_zx, N_yx, anisotropy,
//                       near_axis_share, major_axis_tilt_deg (compare/fabric.hpp); series adds
//                       dem_exact: the DEM's own sphere contacts
//   normals.csv         stage, series, band, theta_from_deg, theta_to_deg, contacts, density
//   coordination_by_size.csv  stage, series, size_class, d_eq_from_mm, d_eq_to_mm, particles,
//                       coordination_mean
//   contacts/           one contact list (a, b, normal_z/y/x) per stage and series
//   particles/          one particle table per stage and series
//   slices/             orthogonal mid-slices (grey u16, labels u32) as .npy
//   *.png, index.html   made by compare/report/make_report.py (matplotlib),
//                       images embedded as base64: index.html opens offline.
//
// Usage (e.g. from the demo):
//   tg::compare::CompareInputs in;
//   in.xct = {"stage0.h5", "stage1.h5"};          // scans or particle CSVs
//   in.dem_run = "dem_run";                       // history.csv + snapshots
//   in.report_dir = "out/report";
//   tg::compare::CompareOptions opt;              // defaults: see below
//   tg::compare::Report r = tg::compare::run_comparison(in, opt);
//   // r.index_html is the page; r.stages[i].ideal_vs_imaged the segmentation bias
#pragma once
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "compare/distances.hpp"
#include "compare/imaging_estimate.hpp"
#include "compare/voxelise.hpp"
#include "measure/grading.hpp"
#include "measure/particles.hpp"
#include "segmentation/segment.hpp"
#include "track/evaluate.hpp"
#include "track/track.hpp"

namespace tg::compare {

struct CompareInputs {
  // XCT stages in loading order: .h5 scans (/volume u16 is segmented; a file
  // with only /labels is measured as is), other volume files (TIFF, raw+JSON)
  // or particle tables (.csv, columns of tomograin measure).
  std::vector<std::string> xct;
  std::vector<double> xct_strains;   // optional, one per stage; else the file's synth
                                     // provenance (axial_strain), else matched by order
  std::vector<std::string> stage_names;  // optional; default "stage N (ε = …)"
  // DEM run folder (dem/run_folder.hpp): its snapshot index (snapshots.csv:
  // file, axial_strain, …) and history.csv (strain, top_stress_Pa, optional
  // grains_broken), read through dem::read_run_folder.
  std::string dem_run;
  // Or explicit sphere tables (core/sphere_table.hpp) instead of the run
  // folder's index; their strains from dem_strains, else matched by order.
  std::vector<std::string> dem_snapshots;
  std::vector<double> dem_strains;  // optional: overrides the index's strains
  std::string experimental_curve;  // optional CSV: axial strain + axial stress columns
  std::string report_dir;          // output folder (created; files inside are replaced)
  std::string title = "tomograin: experiment vs DEM";
  std::string notes;               // free text shown at the top of the page (e.g. what the demo ran)
};

struct CompareOptions {
  double voxel_um = 0;        // voxelising voxel size; 0 = each XCT scan's own (needed for CSV inputs)
  bool like_scan = true;      // estimate grey levels/noise from each XCT scan (else data_synth defaults)
  bool imaged_path = true;    // run the imaged DEM path (segment + measure)
  bool synthetic_xct = false; // mark the XCT inputs synthetic even without synth provenance
  double grain_radius_vox = 0;  // segmentation scale; 0 = median particle of the first DEM snapshot
  SegmentOptions segment;     // shared by the experiment and dem_imaged (grain_radius_vox set as above)
  measure::ParticleOptions measure = default_measure();  // shared by all three series
  VoxeliseOptions voxelise;   // voxel_m and imaging are filled per stage
  bool track = true;          // track grains through the XCT stages (track/) when they are volumes
  bool track_rotations = false;  // give the tracker the grey scans: each particle's rotation (track/rigid_fit.hpp;
                                 // the previous stage's scan held, 2 B/voxel)
  track::TrackOptions tracking;
  bool plots = true;          // run the plotting script (index.html + PNGs)
  std::string python = "/usr/bin/python3";  // Debian's, with python3-matplotlib
  std::string script;         // default: $TOMOGRAIN_REPORT_SCRIPT, else the source tree's
                              // compare/report/make_report.py
  static measure::ParticleOptions default_measure() {
    measure::ParticleOptions p;
    p.oriented_box = false;   // Feret sizing is what is compared; the CGAL box is not needed
    p.contacts = true;        // coordination of the experiment beside the DEM's (ideal: its true contacts
                              // as voxelised; imaged: with the segmentation's bias)
    return p;
  }
};

struct StageReport {
  std::string name;
  double xct_strain = 0, dem_strain = 0;
  std::string xct_source, dem_snapshot;
  bool synthetic = false;
  int64_t n_experiment = 0, n_ideal = 0, n_imaged = 0;
  measure::StageGrading experiment, ideal, imaged;
  Distances exp_vs_imaged, exp_vs_ideal, ideal_vs_imaged;
  double seconds = 0;
  // Memory: the process's peak while this stage ran (own_peak: reset at its
  // start where the kernel allows, else the peak so far), and the voxels of
  // its XCT volume (0 for a particle table) for bytes per voxel.
  int64_t peak_rss_bytes = 0, voxels = 0;
  bool own_peak = false;
};

struct Report {
  std::filesystem::path dir, index_html;  // index_html empty when plots are off
  std::vector<StageReport> stages;
  std::optional<track::TrackResult> tracking;  // the experiment's lineage (REPORT/tracking/), when tracked
  std::string tracking_note;                   // why there is none, when tracking was asked for
  // The DEM's side of the lineage (compare/dem_lineage.hpp), when its snapshots carry it:
  std::optional<track::TrackResult> dem_exact;   // exact: previous_particle of the snapshots (REPORT/dem_lineage/)
  std::optional<track::TrackResult> dem_imaged;  // the tracker on the imaged DEM labels (REPORT/dem_imaged_tracking/)
  std::optional<track::Accuracy> tracker_bias;   // dem_imaged scored against dem_exact (track/evaluate.hpp)
  std::string dem_lineage_note;                  // why a part is missing
  std::vector<double> sieves_mm;
  double seconds = 0;
};

Report run_comparison(const CompareInputs& in, const CompareOptions& opt);

}  // namespace tg::compare
