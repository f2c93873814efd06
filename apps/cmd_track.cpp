// `tomograin track`: follow every grain and fragment from one loading stage to
// the next and classify each breakage event (track/track.hpp has the method).
#include <fmt/core.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/command.hpp"
#include "core/atomic_file.hpp"
#include "core/errors.hpp"
#include "core/memory.hpp"
#include "track/track.hpp"

namespace cmd_track {
struct Opts {
  std::vector<std::string> in, scans;
  std::string out;
  bool any_order = false, no_refine = false, no_absorbed = false, no_glued = false, no_cut_by_count = false;
  double min_overlap = 0.2, chip_body = 0.7, surface_tol = 1.0, fallback_strain = 0, loss_sigmas = 4.0;
  int threads = 0;
};

// DIR/track.json: each stage's wall time (reading its labels and tracking them) and peak memory.
void write_costs(const tg::track::TrackResult& r, const std::string& dir) {
  nlohmann::json j;
  j["voxels_per_stage"] = r.voxels;
  double total = 0;
  int64_t peak = 0;
  for (size_t s = 0; s < r.stage_seconds.size(); ++s) {
    const double b = static_cast<double>(r.peak_rss_bytes[s]);
    j["stages"].push_back({{"name", r.stage_names[s]},
                           {"seconds", r.stage_seconds[s]},
                           {"peak_rss_bytes", r.peak_rss_bytes[s]},
                           {"peak_rss_bytes_per_voxel", r.voxels ? b / static_cast<double>(r.voxels) : 0.0},
                           {"peak_scope", r.own_peak ? "stage" : "process"}});
    total += r.stage_seconds[s];
    peak = std::max(peak, r.peak_rss_bytes[s]);
  }
  j["seconds_total"] = total;
  j["peak_rss_bytes"] = peak;
  j["peak_rss_bytes_per_voxel"] = r.voxels ? static_cast<double>(peak) / static_cast<double>(r.voxels) : 0.0;
  tg::write_file_atomic(std::filesystem::path(dir) / "track.json", j.dump(2) + "\n");
}
}  // namespace cmd_track

namespace cmd_track {
static tg::app::Registrar reg{{"track", 47,
      "Follow every grain and fragment through the label volumes of loading stages, and classify each\n"
      "breakage event.\n\n"
      "Give the stages' labels (u32, from `tomograin segment`; an .h5 file's /labels by default) in\n"
      "loading order; all must share the voxel size, not the shape (a scan cropped to its specimen at each\n"
      "stage is fine: the map takes up the offset). Between two stages the global map (an affine\n"
      "fitted by RANSAC to centroid matches: the specimen shortens under a platen, at either end) predicts\n"
      "where each particle went; its voxels, moved there, overlap its children in the next stage (a scan\n"
      "of a window inside the specimen: what entered the field since does not count against a child,\n"
      "and a particle that mostly entered takes as parent the sliver of it the faces cut before, if\n"
      "that sliver lands mostly in it or, left without child, lies within its equivalent sphere + 2\n"
      "voxels).\n"
      "Events:\n"
      "  intact         one child, volume kept within tol = max(0.1, 3 voxels / r_eq) (a lone child that\n"
      "                 lost more counts as a split whose twin is unseen when it kept <= 70 %, else chipping)\n"
      "  split          two children of comparable size\n"
      "  fragmentation  three or more children (a piece of >= 15 % of the parent inside a neighbour's\n"
      "                 label counts as one, when the parent's loss and the neighbour's gain confirm it;\n"
      "                 a child's label holding >= 15 % of another particle's voxels is weighed without them;\n"
      "                 a child its moved parent covers less than half of is no piece: `new`, the rest\n"
      "                 judged alone, e.g. two halves and a neighbour's crumb are a split)\n"
      "  chipping       a body keeping >= 70 % of the volume plus small pieces (each a `chip`); also a\n"
      "                 whole grain with one child whose chip a neighbour's label absorbed: more of its\n"
      "                 moved voxels land in that label than a boundary shift by d moves (d x the faces\n"
      "                 they shared + 2 pi r_eq d^2; d = hypot(1 voxel, strain increment x r_eq): a stage's\n"
      "                 compression presses contacts deeper),\n"
      "                 and it lost, or the neighbour gained, half of that\n"
      "                 (summary: chips_absorbed; events/lineage: absorbed_vox). Not chipping: a grain\n"
      "                 that grew > 3 % over its 1:1 steps since its last break (a fragment glued to it\n"
      "                 by the segmentation) and now sheds no more than that gain while its body keeps\n"
      "                 the volume before it:\n"
      "                 intact, the pieces `new` (--no-glued-pieces). Also chipping, its chips unseen: a\n"
      "                 whole grain whose one child lost more volume than the stage's whole grains do\n"
      "                 (median + 4 x 1.4826 MAD of their relative loss: the segmentation's own\n"
      "                 stage-to-stage spread, measured on the data; at least 1.5 %; off below 30\n"
      "                 such grains; --loss-sigmas 0 turns it off). Pieces its moved parent covers\n"
      "                 less than half of are no chips while the body loses no more than 0.6 of that\n"
      "                 limit: they are `new`\n"
      "  new            no parent (entered the field, or came up from below the detection limit)\n"
      "  lost           a particle with no child; events.csv's lost_as says where its voxels, moved by\n"
      "                 the map, mostly went: left_field (outside the next scan), merged (into the next\n"
      "                 stage's labels; into_label the one holding most: the segmentation joined it to a\n"
      "                 neighbour, it is still there), vanished (the void: below the detection limit)\n"
      "Fragments are tracked like grains and can break again. Stages given out of order are refused\n"
      "(the map would lengthen the specimen) unless --any-order.\n\n"
      "With --scans (the stages' grey scans, each its labels' shape) every particle with a parent\n"
      "gets its rotation since the previous stage: a rigid registration of its grey levels (Gauss-\n"
      "Newton, as SPAM's discrete DIC), from where its parent's motion puts it; lineage.csv's\n"
      "rz_deg,ry_deg,rx_deg (rotation vector: axis times angle, degrees, (z, y, x) voxel axes) and\n"
      "rotation_se_deg (its standard error: large where the grey holds too little to turn on, a\n"
      "featureless sphere). Without scans they are nan.\n\n"
      "Writes DIR/lineage.csv (stage,label,parent_label,grain,event, volume, centroid and displacement\n"
      "in voxels, match quality = fraction of the particle covered by its moved parent), DIR/events.csv\n"
      "(stage, parent label, grain, type, children, volume before/after, height fifth, lost_as,\n"
      "into_label) and DIR/summary.csv (per stage: grains still intact, % of intact grains broken,\n"
      "events by type, breakage by height fifth, lost (and lost_left_field, lost_merged,\n"
      "lost_vanished) and new, the map's axial scale = 1 - strain increment) and\n"
      "DIR/track.json (per stage: wall time reading and tracking it, peak memory in bytes and per voxel).\n\n"
      "Example (a synthetic oedometer series with its truth lineage, segmented, then tracked):\n"
      "  printf '[stages]\\nmotion = \"oedometer\"\\n' > motion.toml\n"
      "  tomograin synth --preset zeolite-stages --scene motion.toml --size 256 -o run.h5\n"
      "  for s in 0 1 2 3 4; do tomograin segment run_stage$s.h5 -o seg$s.h5; done\n"
      "  tomograin track seg0.h5 seg1.h5 seg2.h5 seg3.h5 seg4.h5 -o tracked\n"
      "  # tracked/summary.csv: pct_intact_broken per stage; run_lineage.csv is the truth",
      [](CLI::App* sub) -> tg::app::Runner {
  auto o = std::make_shared<Opts>();
  sub->add_option("labels", o->in, "Label volumes of the stages, in loading order")->required()->expected(1, -1);
  sub->add_option("-o,--output", o->out, "Output folder (lineage.csv, events.csv, summary.csv)")->required();
  sub->add_option("--scans", o->scans,
                  "Grey scans of the stages, same order and shapes as the labels (e.g. run_stage0.h5:/volume): "
                  "the particles' rotations")
      ->expected(1, -1);
  sub->add_flag("--any-order", o->any_order, "Accept stages whose map lengthens the specimen");
  sub->add_flag("--no-refine", o->no_refine, "One overlap pass (no per-particle residual shift)");
  sub->add_flag("--no-absorbed-chips", o->no_absorbed,
                "Never count a chip or a piece of a break from voxels found in a neighbour's label");
  sub->add_flag("--no-glued-pieces", o->no_glued,
                "Call chipping even where the pieces are what the particle gained at the stage before (a fragment "
                "the segmentation had glued to it, coming apart)");
  sub->add_flag("--no-cut-pieces-by-count", o->no_cut_by_count,
                "Judge a break of a particle the scan's faces cut by its pieces' visible shares even where the faces "
                "cut its smaller pieces too (by default such a break is split or fragmentation by its count of "
                "pieces: the faces hide an unknown part of each)");
  sub->add_option("--min-overlap", o->min_overlap, "Fraction of a child covered by its moved parent, at least")
      ->check(CLI::Range(0.0, 1.0))
      ->default_str("0.2");
  sub->add_option("--chip-body", o->chip_body, "Largest child's volume share at or above which a break is chipping")
      ->check(CLI::Range(0.5, 1.0))
      ->default_str("0.7");
  sub->add_option("--surface-tol-vox", o->surface_tol, "Segmentation surface uncertainty (voxels) behind the intact volume tolerance")
      ->check(CLI::NonNegativeNumber)
      ->default_str("1");
  sub->add_option("--loss-sigmas", o->loss_sigmas,
                  "Robust standard deviations above the median loss of the stage's whole grains at which a whole "
                  "grain with one child counts as chipping (0: never)")
      ->check(CLI::NonNegativeNumber)
      ->default_str("4");
  sub->add_option("--fallback-strain", o->fallback_strain,
                  "Strain increment of the map used when too few grains match (identity + axial compression)")
      ->check(CLI::Range(0.0, 0.99))
      ->default_str("0");
  tg::app::add_threads_option(sub, o->threads);
  return [o] {
    tg::track::TrackOptions to;
    to.allow_extension = o->any_order;
    to.refine = !o->no_refine;
    to.absorbed_chips = to.absorbed_pieces = !o->no_absorbed;
    to.glued_pieces = !o->no_glued;
    to.cut_pieces_by_count = !o->no_cut_by_count;
    to.min_overlap_fraction = o->min_overlap;
    to.chip_body_fraction = o->chip_body;
    to.surface_tolerance_vox = o->surface_tol;
    to.loss_outlier_sigmas = o->loss_sigmas;
    to.map.fallback_strain = o->fallback_strain;
    to.threads = o->threads;
    to.progress = true;
    const auto r = tg::track::track_files(o->in, to, o->scans);  // throws before anything is written
    tg::track::write_outputs(r, o->out);
    write_costs(r, o->out);
    for (const auto& s : r.summary)
      fmt::print("stage {}: {} particles, axial scale {:.4f} ({} {}), intact grains {}, broken {:.1f} %{}, "
                 "split {}, fragmentation {}, chipping {} ({} chips absorbed by a neighbour), lost {} (left the field {}, merged into a neighbour's label {}, "
                 "vanished {}), new {}, "
                 "{:.2f} s\n",
                 s.stage, s.particles, s.axial_scale, s.map_method, s.map_matches, s.grains_intact,
                 s.pct_intact_broken,
                 s.grains_cut ? fmt::format(" (of the grains the faces do not cut; {:.1f} % of all {} with the "
                                            "{} cut)",
                                            s.pct_intact_broken_all, s.grains_intact + s.grains_broken, s.grains_cut)
                              : std::string(),
                 s.split, s.fragmentation, s.chipping, s.chips_absorbed, s.lost, s.lost_left_field, s.lost_merged,
                 s.lost_vanished, s.new_particles,
                 r.seconds[static_cast<size_t>(s.stage)]);
    const int64_t peak = r.peak_rss_bytes.empty() ? 0 : *std::max_element(r.peak_rss_bytes.begin(), r.peak_rss_bytes.end());
    fmt::print("peak memory {} ({:.2f} B/voxel of one stage)\n", tg::human_bytes(static_cast<double>(peak)),
               r.voxels ? static_cast<double>(peak) / static_cast<double>(r.voxels) : 0.0);
    fmt::print("wrote {}/lineage.csv, events.csv, summary.csv, track.json\n", o->out);
    return 0;
  };
}}};
}  // namespace cmd_track
