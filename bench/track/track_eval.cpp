// track_eval: scores a tracked lineage (DIR/lineage.csv of `tomograin track`)
// against data_synth's truth lineage (PREFIX_lineage.csv), for bench/track/run.sh.
//
//   track_eval TRUTH_LINEAGE TRACKED_LINEAGE [--labels L0.h5 ... --truth T0.h5 ...]
//
// Without --labels the tracked labels are the truth's (the tracker alone);
// with them, each stage's labels are mapped to the truth particle covering
// most of their voxels (track/evaluate.hpp). Prints one CSV row per figure.
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "core/io/volume_io.hpp"
#include "core/table.hpp"
#include "track/evaluate.hpp"

using namespace tg;
using namespace tg::track;

namespace {
Volume<uint32_t> labels_of(const std::string& f) { return read_label_volume(f + ":/labels"); }
}  // namespace

int main(int argc, char** argv) try {
  if (argc < 3) {
    std::fprintf(stderr, "usage: track_eval TRUTH_LINEAGE TRACKED_LINEAGE [--labels L... --truth T...]\n");
    return 2;
  }
  std::vector<std::string> seg, truth;
  std::vector<std::string>* into = nullptr;
  for (int a = 3; a < argc; ++a) {
    const std::string s = argv[a];
    if (s == "--labels") into = &seg;
    else if (s == "--truth") into = &truth;
    else if (into) into->push_back(s);
  }
  const auto truth_lineage = read_lineage(read_csv(argv[1]));
  TrackResult r;
  r.lineage = read_lineage(read_csv(argv[2]));
  int stages = 0;
  for (const auto& x : r.lineage) stages = std::max(stages, x.stage + 1);
  // Where the lost went (track.hpp step 8): events.csv beside the lineage, when it says.
  std::vector<LostRow> lost;
  const auto events_csv = std::filesystem::path(argv[2]).parent_path() / "events.csv";
  if (std::filesystem::exists(events_csv)) {
    const Table ev = read_csv(events_csv.string());
    if (ev.has("lost_as")) {
      const auto &type = ev.text("type"), &as = ev.text("lost_as");
      for (int64_t i = 0; i < ev.rows(); ++i) {
        if (type[i] != "lost") continue;
        LostRow l;
        l.stage = static_cast<int>(ev.num("stage")[i]);
        l.label = static_cast<uint32_t>(ev.num("parent_label")[i]);
        for (LostAs x : {LostAs::left_field, LostAs::merged, LostAs::vanished})
          if (as[i] == lost_as_name(x)) l.as = x;
        lost.push_back(l);
      }
    }
  }
  r.events = derive_events(r.lineage, stages, lost);
  r.summary = summarise(r.lineage, r.events, stages);
  std::vector<LabelMap> maps;
  if (!seg.empty()) {
    if (seg.size() != truth.size() || static_cast<int>(seg.size()) != stages)
      throw UsageError("give one --labels and one --truth file per stage");
    for (size_t s = 0; s < seg.size(); ++s) maps.push_back(correspondence(labels_of(seg[s]), labels_of(truth[s])));
  }
  const Accuracy a = evaluate(r, truth_lineage, maps);
  std::printf("figure,value\n");
  std::printf("particles,%lld\nright_parent,%.4f\nright_grain,%.4f\n", static_cast<long long>(a.particles),
              a.parent_fraction(), a.grain_fraction());
  for (const auto& [name, e] : a.events)
    std::printf("%s_truth,%lld\n%s_tracked,%lld\n%s_recall,%.4f\n%s_precision,%.4f\n", name.c_str(),
                static_cast<long long>(e.truth), name.c_str(), static_cast<long long>(e.tracked), name.c_str(),
                e.recall(), name.c_str(), e.precision());
  std::printf("particles_interior,%lld\nright_parent_interior,%.4f\n", static_cast<long long>(a.particles_interior),
              a.particles_interior ? static_cast<double>(a.right_parent_interior) / static_cast<double>(a.particles_interior)
                                   : 1.0);
  for (const auto& [name, e] : a.events_interior)
    std::printf("%s_interior_truth,%lld\n%s_interior_recall,%.4f\n%s_interior_precision,%.4f\n", name.c_str(),
                static_cast<long long>(e.truth), name.c_str(), e.recall(), name.c_str(), e.precision());
  for (size_t s = 0; s < a.pct_broken.size(); ++s)
    std::printf("pct_intact_broken_stage%zu,%.2f\npct_intact_broken_truth_stage%zu,%.2f\n", s, a.pct_broken[s], s,
                a.pct_broken_truth[s]);
  for (const auto& [as, n] : a.lost_as)
    std::printf("lost_as_%s_tracked,%lld\nlost_as_%s_truth_lost,%lld\n", as.c_str(), static_cast<long long>(n.first),
                as.c_str(), static_cast<long long>(n.second));
  for (const auto& m : a.mistakes) std::fprintf(stderr, "wrong: %s\n", m.c_str());
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "track_eval: %s\n", e.what());
  return 2;
}
