#include "track/evaluate.hpp"

#include <algorithm>
#include <set>
#include <tuple>

#include "core/errors.hpp"

namespace tg::track {

LabelMap correspondence(const Volume<uint32_t>& labels, const Volume<uint32_t>& truth) {
  if (labels.shape() != truth.shape()) throw UsageError("correspondence: label and truth volumes differ in shape");
  std::unordered_map<uint64_t, int64_t> count;
  const int64_t n = labels.size();
  uint64_t run_key = ~uint64_t{0};
  int64_t run = 0;
  for (int64_t q = 0; q < n; ++q) {
    const uint32_t l = labels.data()[q], t = truth.data()[q];
    if (!l || !t) continue;
    const uint64_t key = (static_cast<uint64_t>(l) << 32) | t;
    if (key != run_key) {
      if (run) count[run_key] += run;
      run_key = key, run = 0;
    }
    ++run;
  }
  if (run) count[run_key] += run;
  std::unordered_map<uint32_t, std::pair<int64_t, uint32_t>> best;
  for (const auto& [key, c] : count) {
    const uint32_t l = static_cast<uint32_t>(key >> 32), t = static_cast<uint32_t>(key);
    auto& b = best[l];
    if (c > b.first || (c == b.first && t < b.second)) b = {c, t};
  }
  LabelMap out;
  for (const auto& [l, b] : best) out[l] = b.second;
  return out;
}

namespace {

uint32_t map_label(const std::vector<LabelMap>& maps, int stage, uint32_t label) {
  if (maps.empty() || label == 0) return label;
  const auto& m = maps[static_cast<size_t>(stage)];
  auto it = m.find(label);
  return it == m.end() ? 0 : it->second;
}

}  // namespace

Accuracy evaluate(const TrackResult& tracked, const std::vector<LineageRow>& truth, const std::vector<LabelMap>& maps) {
  const int stages = static_cast<int>(tracked.summary.size());
  if (!maps.empty() && static_cast<int>(maps.size()) != stages) throw UsageError("evaluate: one label map per stage");
  std::map<std::pair<int, uint32_t>, const LineageRow*> truth_row;
  int truth_stages = 0;
  for (const auto& r : truth) {
    truth_row[{r.stage, r.label}] = &r;
    truth_stages = std::max(truth_stages, r.stage + 1);
  }
  if (truth_stages != stages) throw UsageError("evaluate: the truth lineage has another number of stages");
  Accuracy a;
  // Truth particles cut by the faces (stage, truth label): the truth lineage's `border` column.
  auto at_border = [&](int stage, uint32_t label) {
    auto it = truth_row.find({stage, label});
    return it != truth_row.end() && it->second->touches_border;
  };
  for (const auto& r : tracked.lineage) {
    if (r.stage == 0) continue;
    ++a.particles;
    const uint32_t q = map_label(maps, r.stage, r.label);
    auto it = truth_row.find({r.stage, q});
    const uint32_t tp = it == truth_row.end() ? 0 : it->second->parent_label;
    const uint32_t tg = it == truth_row.end() ? 0 : it->second->grain;
    const bool ok = map_label(maps, r.stage - 1, r.parent_label) == tp;
    a.right_parent += ok;
    if (!at_border(r.stage, q)) ++a.particles_interior, a.right_parent_interior += ok;
    if (!ok && a.mistakes.size() < 50)
      a.mistakes.push_back("stage " + std::to_string(r.stage) + " label " + std::to_string(r.label) + " (truth " +
                           std::to_string(q) + ", " + (it == truth_row.end() ? "-" : event_name(it->second->event)) +
                           "): parent " + std::to_string(r.parent_label) + " (truth " +
                           std::to_string(map_label(maps, r.stage - 1, r.parent_label)) + "), truth parent " +
                           std::to_string(tp) + ", tracked event " + event_name(r.event) + ", quality " +
                           std::to_string(r.quality) + ", volume " + std::to_string(r.volume_vox));
    a.right_grain += map_label(maps, 0, r.grain) == tg;
  }
  const auto truth_events = derive_events(truth, stages);
  std::set<std::tuple<int, uint32_t, Event>> truth_keys, tracked_keys;
  const std::vector<Event> types{Event::split, Event::fragmentation, Event::chipping, Event::lost};
  for (const auto& e : truth_events) truth_keys.insert({e.stage, e.parent_label, e.type});
  for (const auto& e : tracked.events)
    if (e.parent_label) tracked_keys.insert({e.stage, map_label(maps, e.stage - 1, e.parent_label), e.type});
  for (Event t : types) a.events[event_name(t)], a.events_interior[event_name(t)];
  for (const auto& e : truth_events) {
    if (std::find(types.begin(), types.end(), e.type) == types.end()) continue;
    auto& sc = a.events[event_name(e.type)];
    ++sc.truth;
    const bool hit = tracked_keys.count({e.stage, e.parent_label, e.type}) > 0;
    sc.found += hit;
    if (!at_border(e.stage - 1, e.parent_label)) {
      auto& si = a.events_interior[event_name(e.type)];
      ++si.truth;
      si.found += hit;
    }
    if (!hit && a.missed_events.size() < 50)
      a.missed_events.push_back("stage " + std::to_string(e.stage) + " parent " + std::to_string(e.parent_label) + " " +
                                event_name(e.type) + " (" + std::to_string(e.children.size()) + " children, volume " +
                                std::to_string(e.volume_before_vox) + " -> " + std::to_string(e.volume_after_vox) + ")");
  }
  for (const auto& e : tracked.events) {
    if (std::find(types.begin(), types.end(), e.type) == types.end()) continue;
    auto& sc = a.events[event_name(e.type)];
    ++sc.tracked;
    const uint32_t tp = map_label(maps, e.stage - 1, e.parent_label);
    const bool right = truth_keys.count({e.stage, tp, e.type}) > 0;
    sc.confirmed += right;
    if (e.type == Event::lost) {
      auto& l = a.lost_as[lost_as_name(e.lost_as)];
      ++l.first;
      l.second += right;
    }
    if (!at_border(e.stage - 1, tp)) {
      auto& si = a.events_interior[event_name(e.type)];
      ++si.tracked;
      si.confirmed += right;
    }
  }
  const auto truth_summary = summarise(truth, truth_events, stages);
  for (int s = 0; s < stages; ++s) {
    a.pct_broken.push_back(tracked.summary[s].pct_intact_broken);
    a.pct_broken_truth.push_back(truth_summary[s].pct_intact_broken);
  }
  return a;
}

}  // namespace tg::track
