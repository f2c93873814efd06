// tomograin voxelise SNAPSHOT -o scan.h5 --voxel-um 12.3 [--like SCAN]   DEM packing -> CT-like scan + truth
// tomograin compare --xct STAGES... --dem RUNDIR -o REPORT_DIR          experiment vs DEM report
#include <fmt/core.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "apps/command.hpp"
#include "compare/comparison.hpp"
#include "compare/imaging_estimate.hpp"
#include "compare/voxelise.hpp"
#include "core/errors.hpp"
#include "core/io/hdf5.hpp"
#include "core/io/volume_io.hpp"

namespace cmd_compare {

using namespace tg;

// ---------------------------------------------------------------- voxelise

struct VoxOpts {
  std::string in, out, like, field = "spheres", cluster_body = "hull";
  double voxel_um = 0, margin_vox = 3, cylinder_mm = 15;
  double void_grey = -1, solid_grey = -1, noise = -1, psf = -1;
  uint64_t seed = 1;
  bool no_grey = false, truth = false;
};

int run_voxelise(const VoxOpts& o) {
  if (!is_hdf5(o.out)) throw UsageError("-o " + o.out + ": expected an .h5 file");
  compare::VoxeliseOptions vo;
  vo.voxel_m = o.voxel_um * 1e-6;
  vo.field = o.field == "cylinder" ? compare::FieldOfView::cylinder : compare::FieldOfView::spheres;
  vo.margin_vox = o.margin_vox;
  vo.cylinder_diameter_m = o.cylinder_mm * 1e-3;
  vo.grey = !o.no_grey;
  vo.truth = o.truth;
  vo.cluster_body = compare::cluster_body_from_name(o.cluster_body);
  vo.imaging.seed = o.seed;
  std::string like_note = "data_synth defaults";
  if (!o.like.empty()) {
    ReadOptions ro;
    ro.progress = false;
    const auto [file, ds] = split_dataset_spec(o.like);
    const std::string spec = format_of(o.like, false) == FileFormat::hdf5 && ds.empty() ? file + ":/volume" : o.like;
    const auto e = compare::estimate_grey_levels(read_volume_as<uint16_t>(spec, ro));
    vo.imaging = compare::imaging_like(e, vo.imaging);
    like_note = fmt::format("estimated from {} ({}): void {:.0f}, solid {:.0f}, noise sigma {:.0f}", o.like,
                            e.method, e.void_grey, e.solid_grey, e.noise_sigma);
  }
  if (o.void_grey >= 0) vo.imaging.void_grey = o.void_grey;
  if (o.solid_grey >= 0) vo.imaging.solid_grey = o.solid_grey;
  if (o.noise >= 0) vo.imaging.noise_sigma = o.noise;
  if (o.psf >= 0) vo.imaging.psf_sigma = o.psf;

  const SphereTable s = read_spheres(o.in);
  compare::Voxelised v = compare::voxelise(s, vo);
  const nlohmann::json prov = compare::voxelise_json(o.in, vo, v, like_note);
  {
    H5Writer w(o.out);
    if (vo.grey) w.write_volume("/volume", v.grey);
    w.write_volume("/labels", v.labels);
    if (o.truth) w.write_table("/truth", v.truth);
    w.write_attribute("voxelise", prov.dump());
    w.commit();
  }
  const std::string truth_csv = tg::app::beside(o.out, "_truth.csv");
  if (o.truth) write_csv(v.truth, truth_csv);
  const Shape sh = v.labels.shape();
  fmt::print("voxelised {} spheres as {} particles ({} clusters as convex-hull bodies, {} as separate tangent spheres, "
             "{} as exact unions) into "
             "{}x{}x{} voxels of {} um (solid fraction {:.3f}) in {:.2f} s render + {:.2f} s imaging\ngrey: {}\n"
             "wrote {}{}\n",
             s.size(), v.particle_of_label.size() - 1, v.clusters_hull, v.clusters_split, v.clusters_union, sh.nz, sh.ny, sh.nx,
             o.voxel_um, v.solid_fraction, v.render_s, v.imaging_s, vo.grey ? like_note : "skipped (--no-grey)", o.out,
             o.truth ? " (/volume, /labels, /truth) and " + truth_csv : " (/volume, /labels)");
  return 0;
}

// ---------------------------------------------------------------- compare

struct CmpOpts {
  std::vector<std::string> xct, names, dem_snapshots;
  std::vector<double> xct_strains, dem_strains;
  std::string dem, out, curve, title = "tomograin: experiment vs DEM", notes, cluster_body = "hull";
  double voxel_um = 0, grain_radius_vox = 0;
  bool no_like = false, no_imaged = false, synthetic = false, no_plots = false, no_track = false,
       track_rotations = false;
  std::string feret = "60";
};

int run_compare(const CmpOpts& o) {
  compare::CompareInputs in;
  in.xct = o.xct;
  in.xct_strains = o.xct_strains;
  in.stage_names = o.names;
  in.dem_run = o.dem;
  in.dem_snapshots = o.dem_snapshots;
  in.dem_strains = o.dem_strains;
  in.experimental_curve = o.curve;
  in.report_dir = o.out;
  in.title = o.title;
  in.notes = o.notes;
  compare::CompareOptions opt;
  opt.voxel_um = o.voxel_um;
  opt.grain_radius_vox = o.grain_radius_vox;
  opt.like_scan = !o.no_like;
  opt.imaged_path = !o.no_imaged;
  opt.synthetic_xct = o.synthetic;
  opt.plots = !o.no_plots;
  opt.track = !o.no_track;
  opt.track_rotations = o.track_rotations;
  opt.voxelise.cluster_body = compare::cluster_body_from_name(o.cluster_body);
  tg::app::parse_feret_option(o.feret, opt.measure.feret_exact, opt.measure.feret_directions);
  const compare::Report r = compare::run_comparison(in, opt);
  for (const auto& st : r.stages)
    fmt::print("{}: {} experiment / {} DEM ideal / {} DEM imaged particles; KS exp-imaged PSD {:.3f} FR {:.3f} AR "
               "{:.3f}; segmentation bias (ideal-imaged) PSD KS {:.3f} W1 {:.4f} mm, FR KS {:.3f}, AR KS {:.3f}\n",
               st.name, st.n_experiment, st.n_ideal, st.n_imaged, st.exp_vs_imaged.psd_ks, st.exp_vs_imaged.fr_ks,
               st.exp_vs_imaged.ar_ks, st.ideal_vs_imaged.psd_ks, st.ideal_vs_imaged.psd_w1_mm,
               st.ideal_vs_imaged.fr_ks, st.ideal_vs_imaged.ar_ks);
  fmt::print("report: {} ({:.1f} s)\n", r.index_html.empty() ? (r.dir / "report.json").string() : r.index_html.string(),
             r.seconds);
  return 0;
}

}  // namespace cmd_compare

namespace cmd_compare {
static tg::app::Registrar reg_vox{{"voxelise", 70,
      "Turn a DEM snapshot or packing into a CT-like scan with exact truth labels.\n\n"
      "Input: CSV or HDF5 table (file.h5[:/group]) of spheres, columns x_m,y_m,z_m,r_m (metres; cylinder axis z,\n"
      "centre x=y=0, bottom platen z=0) and optionally `particle` (or `cluster`): spheres sharing an id are ONE\n"
      "particle (a bonded cluster/fragment), labelled once. The exact partial volume of every voxel comes from\n"
      "data_synth's renderer; the grey scan from its imaging model (grey = void + (solid - void) x fraction,\n"
      "Gaussian PSF, Gaussian noise, rounded to u16). Grey levels and noise are data_synth's defaults\n"
      "(9000 / 38000, sigma 900, PSF 0.7 voxel) or, with --like SCAN, estimated from that scan's histogram:\n"
      "Otsu split, the mode of each class = void/solid level, noise sigma from the outer half width at half\n"
      "maximum of both peaks (the PSF keeps its default).\n\n"
      "Output: HDF5 with /volume (u16 grey), /labels (u32, label l = l-th particle id met in the table); with\n"
      "--truth-table also /truth (exact volume, centroid, Feret per particle, plus the input `particle` id) and\n"
      "PATH_truth.csv (slow for clusters: ~0.1 s each). A cluster is imaged as the convex hull of its spheres\n"
      "(--cluster-body hull, default: the solid body a DEM fragment stands for) or as its spheres (members).\n"
      "Field of view: the spheres' bounding box (default) or the oedometer cylinder, plus --margin voxels.\n\n"
      "Examples:\n"
      "  tomograin voxelise run/snapshots/snap_0003.csv -o scan.h5 --voxel-um 12.3\n"
      "  tomograin voxelise snap.h5 -o scan.h5 --voxel-um 58.6 --like stage0.h5 --field cylinder",
      [](CLI::App* sub) -> tg::app::Runner {
  auto o = std::make_shared<VoxOpts>();
  sub->add_option("snapshot", o->in, "Spheres: .csv or .h5[:/group] with x_m,y_m,z_m,r_m[,particle]")->required();
  sub->add_option("-o,--output", o->out, "Output .h5 file")->required();
  sub->add_option("--voxel-um", o->voxel_um, "Voxel edge, micrometres")->required()->check(CLI::PositiveNumber);
  sub->add_option("--like", o->like, "Experimental scan whose grey levels and noise to imitate (.h5 uses /volume)");
  sub->add_option("--field", o->field, "Field of view: spheres (bounding box) or cylinder")
      ->check(CLI::IsMember({"spheres", "cylinder"}))
      ->capture_default_str();
  sub->add_option("--margin", o->margin_vox, "Void voxels around the field on every side")->capture_default_str();
  sub->add_option("--cylinder-mm", o->cylinder_mm, "Cylinder diameter for --field cylinder (mm)")
      ->capture_default_str();
  sub->add_option("--void-grey", o->void_grey, "Override the void grey level");
  sub->add_option("--solid-grey", o->solid_grey, "Override the solid grey level");
  sub->add_option("--noise", o->noise, "Override the Gaussian noise sigma (grey levels)");
  sub->add_option("--psf", o->psf, "Override the PSF sigma (voxels)");
  sub->add_option("--seed", o->seed, "Noise seed")->capture_default_str();
  sub->add_flag("--no-grey", o->no_grey, "Labels only (skip the imaging model)");
  sub->add_flag("--truth-table", o->truth, "Also write data_synth's exact truth table (/truth and PATH_truth.csv)");
  sub->add_option("--cluster-body", o->cluster_body, compare::kClusterBodyHelp)
      ->check(CLI::IsMember({"hull", "members"}))
      ->capture_default_str();
  return [o] { return run_voxelise(*o); };
}}};

static tg::app::Registrar reg_cmp{{"compare", 80,
      "Put XCT stages and DEM snapshots side by side, measured by the same code; write an HTML report.\n\n"
      "For every XCT stage (a grey scan, segmented with `segment`'s defaults and measured; or a particle\n"
      "CSV from `tomograin measure`) the DEM snapshot at the nearest axial strain is voxelised at the scan's\n"
      "voxel size with grey levels/noise estimated from that scan, then measured twice: 'ideal' (its truth\n"
      "labels) and 'imaged' (segment + measure, exactly like the scan). Compared per stage: PSD by mass on Dmed,\n"
      "D10/D50/Cu, FR and AR classes (FR < 0.4, 0.4-0.8, 0.8-0.9, >= 0.9; AR < 2, 2-3, >= 3; for the DEM also\n"
      "'dem_exact': every particle's shape from its spheres, however small, the count of the study's DEM\n"
      "figures), Hardin's relative breakage, fraction of grains broken, and Kolmogorov-Smirnov / Wasserstein-1\n"
      "distances (PSD weighted by mass, W1 in mm; FR, AR by number) for experiment-vs-imaged,\n"
      "experiment-vs-ideal and ideal-vs-imaged (= segmentation bias). Plus the DEM stress-strain curve\n"
      "(RUNDIR/history.csv) beside an experimental curve (--curve CSV with axial_strain and axial_stress_Pa/kPa/MPa).\n\n"
      "DEM run folder (--dem, written by `tomograin dem oedometer`): its snapshot index snapshots.csv\n"
      "(file, step, axial_strain, ...) and history.csv; or explicit sphere tables (--dem-snapshots, with\n"
      "--dem-strains or matched by order). XCT strains from --xct-strains or synth provenance; else by order.\n\n"
      "Output REPORT_DIR: index.html (self-contained, images embedded), PNGs, report.json, summary.csv, psd.csv,\n"
      "shape_classes.csv, distances.csv, stress_strain.csv, broken.csv, particles/*.csv, slices/*.npy; the contact\n"
      "fabric of experiment, DEM ideal, DEM imaged and DEM exact (its own sphere contacts): fabric.csv (N, anisotropy,\n"
      "share of normals within 30 deg of z), normals.csv (polar-angle density), coordination_by_size.csv, contacts/.\n"
      "Plots need Debian's /usr/bin/python3 with python3-matplotlib.\n\n"
      "Example:\n"
      "  tomograin compare --xct run_stage0.h5 run_stage1.h5 --dem dem_run -o report\n"
      "  tomograin compare --xct s0.csv s1.csv --xct-strains 0 0.044 --voxel-um 12.3 --dem dem_run -o report",
      [](CLI::App* sub) -> tg::app::Runner {
  auto o = std::make_shared<CmpOpts>();
  sub->add_option("--xct", o->xct, "XCT stages in loading order: scans (.h5/.tif/.json) or particle tables (.csv)")
      ->required();
  sub->add_option("--dem", o->dem, "DEM run folder (snapshots.csv index, snapshots, history.csv)");
  sub->add_option("-o,--output", o->out, "Report folder")->required();
  sub->add_option("--xct-strains", o->xct_strains, "Axial strain of each XCT stage (fraction, e.g. 0.044)");
  sub->add_option("--names", o->names, "Stage names shown in the report");
  sub->add_option("--dem-snapshots", o->dem_snapshots,
                  "Explicit sphere tables (x_m,y_m,z_m,r_m[,particle]) instead of the run folder's index");
  sub->add_option("--dem-strains", o->dem_strains, "Axial strain of each snapshot (overrides the index)");
  sub->add_option("--curve", o->curve, "Experimental stress-strain CSV");
  sub->add_option("--voxel-um", o->voxel_um, "Voxelising voxel size (default: each scan's own)");
  sub->add_option("--grain-radius-vox", o->grain_radius_vox,
                  "Segmentation scale (default: median particle of the first snapshot)");
  sub->add_option("--feret", o->feret, "Feret orientations N or 'exact'")->capture_default_str();
  sub->add_option("--title", o->title, "Report title")->capture_default_str();
  sub->add_option("--notes", o->notes, "Free text shown at the top of the report");
  sub->add_flag("--no-like", o->no_like, "Do not estimate grey levels from the scans (data_synth defaults)");
  sub->add_flag("--no-imaged", o->no_imaged, "Skip the imaged DEM path");
  sub->add_option("--cluster-body", o->cluster_body, compare::kClusterBodyHelp)
      ->check(CLI::IsMember({"hull", "members"}))
      ->capture_default_str();
  sub->add_flag("--synthetic", o->synthetic, "Mark the XCT inputs synthetic in the report");
  sub->add_flag("--no-plots", o->no_plots, "Write the CSV/JSON only (no Python)");
  sub->add_flag("--no-track", o->no_track,
                "Do not track the experiment's grains through the stages (REPORT/tracking/; by default the "
                "experiment's broken fraction comes from that lineage when the scans carry no truth)");
  sub->add_flag("--track-rotations", o->track_rotations,
                "Give the tracker the grey scans: each particle's rotation since the stage before "
                "(REPORT/tracking/lineage.csv rz_deg,ry_deg,rx_deg; about 2 s more per 256^3 stage, and the "
                "stage before's scan held, 2 B/voxel)");
  return [o] { return run_compare(*o); };
}}};
}  // namespace cmd_compare
