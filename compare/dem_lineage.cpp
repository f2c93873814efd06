#include "compare/dem_lineage.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/errors.hpp"
#include "core/io/hdf5.hpp"
#include "core/io/volume_io.hpp"
#include "core/table.hpp"

namespace tg::compare {

SnapshotLineage read_snapshot_lineage(const std::string& path) {
  Table t = is_hdf5(path) ? H5Reader(path).read_table("spheres") : read_csv(path, {"x_m", "y_m", "z_m", "r_m"});
  if (t.source.empty()) t.source = path;
  SnapshotLineage s;
  s.source = path;
  s.spheres = spheres_from_table(t);
  if (t.has("previous_particle")) {
    for (double v : t.num("previous_particle")) s.previous_particle.push_back(static_cast<int64_t>(v));
  }
  return s;
}

namespace {

// Particle id -> its particle at the previous snapshot, from its spheres.
std::map<int64_t, int64_t> previous_of(const SnapshotLineage& s) {
  if (s.previous_particle.empty())
    throw InputError(s.source + ": no previous_particle column (a DEM run written before the lineage column existed)");
  std::map<int64_t, int64_t> out;
  for (size_t q = 0; q < s.spheres.size(); ++q) {
    const auto [it, fresh] = out.emplace(s.spheres.particle[q], s.previous_particle[q]);
    if (!fresh && it->second != s.previous_particle[q])
      throw InputError(s.source + ": row " + std::to_string(q + 1) + ": the spheres of particle " +
                       std::to_string(it->first) + " disagree on previous_particle");
  }
  return out;
}

// One row per particle of a snapshot (label, exact volume and centroid in voxels), ordered by label.
std::vector<track::LineageRow> particle_rows(const SphereTable& s, int stage, const std::map<int64_t, uint32_t>& label_of,
                                             double voxel_m, std::vector<int64_t>& ids) {
  struct Acc {
    double v = 0, z = 0, y = 0, x = 0;
  };
  std::map<int64_t, Acc> acc;
  for (size_t q = 0; q < s.size(); ++q) {
    const double v = 4.0 / 3.0 * std::numbers::pi * std::pow(s.r_m[q] / voxel_m, 3);  // tangent spheres: volumes add
    Acc& a = acc[s.particle[q]];
    a.v += v, a.z += v * s.z_m[q] / voxel_m, a.y += v * s.y_m[q] / voxel_m, a.x += v * s.x_m[q] / voxel_m;
  }
  std::vector<track::LineageRow> rows;
  ids.clear();
  for (const auto& [id, a] : acc) {
    track::LineageRow r;
    r.stage = stage;
    const auto it = label_of.find(id);
    r.label = it != label_of.end() ? it->second : static_cast<uint32_t>(id + 1);
    r.volume_vox = std::llround(a.v);
    r.centroid_vox = {a.z / a.v, a.y / a.v, a.x / a.v};
    rows.push_back(r);
    ids.push_back(id);
  }
  std::vector<size_t> order(rows.size());
  for (size_t n = 0; n < order.size(); ++n) order[n] = n;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return rows[a].label < rows[b].label; });
  std::vector<track::LineageRow> sorted_rows;
  std::vector<int64_t> sorted_ids;
  for (size_t n : order) sorted_rows.push_back(rows[n]), sorted_ids.push_back(ids[n]);
  ids = std::move(sorted_ids);
  return sorted_rows;
}

}  // namespace

track::TrackResult dem_lineage(const std::vector<SnapshotLineage>& chain, const std::vector<size_t>& stage_snapshot,
                               const std::vector<std::map<int64_t, uint32_t>>& label_of, double voxel_m,
                               const track::TrackOptions& o) {
  if (stage_snapshot.empty() || label_of.size() != stage_snapshot.size())
    throw UsageError("dem_lineage: one label map per stage");
  if (!(voxel_m > 0)) throw UsageError("dem_lineage: voxel size must be > 0");
  track::TrackResult r;
  const int stages = static_cast<int>(stage_snapshot.size());
  std::vector<track::LineageRow> prev;
  std::vector<int64_t> prev_ids;
  for (int s = 0; s < stages; ++s) {
    const size_t m = stage_snapshot[static_cast<size_t>(s)];
    if (m >= chain.size() || (s > 0 && m < stage_snapshot[static_cast<size_t>(s) - 1]))
      throw UsageError("dem_lineage: stage snapshots out of order");
    std::vector<int64_t> ids;
    std::vector<track::LineageRow> rows = particle_rows(chain[m].spheres, s, label_of[static_cast<size_t>(s)], voxel_m, ids);
    if (s == 0) {
      for (auto& row : rows) {
        row.grain = row.label;
        row.displacement_vox = {NAN, NAN, NAN};
      }
    } else {
      // Each particle's id at the previous compared snapshot: the maps of the snapshots in between, composed.
      const size_t m0 = stage_snapshot[static_cast<size_t>(s) - 1];
      std::vector<int64_t> back = ids;
      for (size_t k = m; k > m0; --k) {
        const auto prev_map = previous_of(chain[k]);
        for (int64_t& id : back) {
          const auto it = prev_map.find(id);
          if (it == prev_map.end())
            throw InputError(chain[k].source + ": no particle " + std::to_string(id) + ", named by " + chain[k + 1].source);
          id = it->second;
        }
      }
      std::map<int64_t, int32_t> index_of_prev;
      for (size_t a = 0; a < prev_ids.size(); ++a) index_of_prev[prev_ids[a]] = static_cast<int32_t>(a);
      std::vector<int32_t> parent(rows.size(), -1);
      for (size_t q = 0; q < rows.size(); ++q) {
        const auto it = index_of_prev.find(back[q]);
        if (it == index_of_prev.end())
          throw InputError(chain[m].source + ": particle " + std::to_string(ids[q]) + " descends from particle " +
                           std::to_string(back[q]) + ", absent from " + chain[m0].source);
        parent[q] = it->second;
      }
      track::link_stage(prev, rows, parent, o);
      for (auto& row : rows) row.quality = 1;  // exact
    }
    r.stage_names.push_back(chain[m].source);
    r.maps.push_back(track::StageMap{});
    r.seconds.push_back(0);
    r.lineage.insert(r.lineage.end(), rows.begin(), rows.end());
    prev = std::move(rows);
    prev_ids = std::move(ids);
  }
  r.events = track::derive_events(r.lineage, stages);
  r.summary = track::summarise(r.lineage, r.events, stages);
  for (auto& row : r.summary) row.map_method = "exact";
  return r;
}

Volume<uint32_t> on_grid(const Volume<uint32_t>& v, const Shape& shape, const Geometry& g) {
  auto out = Volume<uint32_t>::filled(shape, 0, g);
  int64_t off[3];
  for (int a = 0; a < 3; ++a) off[a] = std::llround((v.geometry().origin_m[a] - g.origin_m[a]) / g.voxel_size_m[a]);
  const Shape& s = v.shape();
  for (int64_t k = 0; k < s.nz; ++k) {
    const int64_t z = k + off[0];
    if (z < 0 || z >= shape.nz) continue;
    for (int64_t j = 0; j < s.ny; ++j) {
      const int64_t y = j + off[1];
      if (y < 0 || y >= shape.ny) continue;
      for (int64_t i = 0; i < s.nx; ++i) {
        const int64_t x = i + off[2];
        if (x >= 0 && x < shape.nx) out.data()[(z * shape.ny + y) * shape.nx + x] = v.data()[(k * s.ny + j) * s.nx + i];
      }
    }
  }
  return out;
}

}  // namespace tg::compare
