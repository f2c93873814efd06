// Accuracy of a tracked lineage against a truth lineage in the same columns
// (data_synth writes PREFIX_lineage.csv), for tests and bench/track.
//
// Labels of a segmented stage are not the truth's: correspondence() maps each
// label to the truth particle covering most of its voxels (0 when it covers
// none). Then, for every tracked particle at stages >= 1 with truth particle
// q = T_s(label):
//   right parent  T_{s-1}(parent_label) equals q's truth parent (both 0 for a
//                 `new` particle or a label with no truth particle)
//   right grain   T_0(grain) equals q's truth grain
// Events (split, fragmentation, chipping, lost) are keyed by (stage, truth id
// of the parent): recall = truth events of a type found with that type at
// the same key / truth events of the type; precision = tracked events of a
// type whose key holds a truth event of that type / tracked events of it.
// The % of intact grains broken comes from summarise() on both lineages (over
// the grains the faces do not cut, step 7: where the truth lineage has no
// face_vox column, its every grain counts).
// events_interior: the same scores over the events whose truth parent does
// not touch the volume's faces, and right_parent_interior over the particles
// whose truth particle does not (the truth lineage's `border` column, when
// it has one; without it every particle counts): a parent cut by a face
// shows only part of its volume, so
// its children's visible shares may say chipping where the whole grain
// split (a scan of a window inside the specimen).
#pragma once
#include <cstdint>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/volume.hpp"
#include "track/track.hpp"

namespace tg::track {

using LabelMap = std::unordered_map<uint32_t, uint32_t>;

// Majority overlap: label -> truth id (ties: the smaller id). Same shape (UsageError).
LabelMap correspondence(const Volume<uint32_t>& labels, const Volume<uint32_t>& truth);

struct EventScore {
  int64_t truth = 0, tracked = 0, found = 0, confirmed = 0;  // found: truth events recalled; confirmed: tracked ones right
  double recall() const { return truth ? static_cast<double>(found) / static_cast<double>(truth) : 1.0; }
  double precision() const { return tracked ? static_cast<double>(confirmed) / static_cast<double>(tracked) : 1.0; }
};

struct Accuracy {
  int64_t particles = 0, right_parent = 0, right_grain = 0;  // tracked particles at stages >= 1
  int64_t particles_interior = 0, right_parent_interior = 0;  // those whose truth particle is clear of the faces
  std::map<std::string, EventScore> events;  // "split", "fragmentation", "chipping", "lost"
  std::map<std::string, EventScore> events_interior;  // the same, parents clear of the faces
  std::vector<double> pct_broken, pct_broken_truth;  // per stage
  // Tracked `lost` events by where they went (track.hpp step 8; "-" when unknown): how many,
  // and of those how many the truth also loses (a `merged` one should not be).
  std::map<std::string, std::pair<int64_t, int64_t>> lost_as;
  std::vector<std::string> mistakes;       // the first 50 wrong parents, for diagnosis
  std::vector<std::string> missed_events;  // the first 50 truth events not found
  double parent_fraction() const { return particles ? static_cast<double>(right_parent) / static_cast<double>(particles) : 1.0; }
  double grain_fraction() const { return particles ? static_cast<double>(right_grain) / static_cast<double>(particles) : 1.0; }
};

// maps[s]: tracked label -> truth id at stage s; an empty `maps` means the
// tracked labels are the truth's (tracker alone).
Accuracy evaluate(const TrackResult& tracked, const std::vector<LineageRow>& truth, const std::vector<LabelMap>& maps = {});

}  // namespace tg::track
