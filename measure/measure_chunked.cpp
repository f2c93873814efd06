#include "measure/measure_chunked.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>

#include "core/errors.hpp"
#include "core/memory.hpp"
#include "measure/grey_volume.hpp"
#include "measure/label_stats.hpp"

namespace tg::measure {

MeasureChunkPlan plan_measure_chunks(const Shape& s, bool grey, int64_t limit) {
  MeasureChunkPlan p;
  const double per_voxel = kMeasureBytesPerVoxel + (grey ? 2.0 : 0.0);
  p.estimate_bytes = int64_t(per_voxel * double(s.voxels())) + kMeasureFixedBytes;
  if (limit <= 0 || p.estimate_bytes <= limit) {
    p.core = s.nz;
    p.slabs = 1;
    p.slab_bytes = p.estimate_bytes;
    return p;
  }
  p.in_memory = false;
  // A slab: its labels and grey (4 + 2 B/voxel, margins included) beside the
  // boundary lists of the whole volume, which grow to their full size.
  const double slab_voxel = 4.0 + (grey ? 2.0 : 0.0);
  const double lists = kMeasureListBytesPerVoxel * double(s.voxels());
  const double room = double(limit - kMeasureFixedBytes) - lists;
  const double slice = slab_voxel * double(s.slice_voxels());
  const int64_t slices = room > 0 ? int64_t(room / slice) : 0;  // core + 2 margin slices
  if (slices < 3)
    throw UsageError("--memory-limit " + human_bytes(double(limit)) + " is too small to measure " + s.str() +
                     " slab by slab: the boundary voxels of its particles need about " + human_bytes(lists) +
                     " and a slab of one slice " + human_bytes(3 * slice) + "; give at least " +
                     human_bytes(lists + 3 * slice + double(kMeasureFixedBytes)));
  p.core = std::min(slices - 2, s.nz);
  p.slabs = (s.nz + p.core - 1) / p.core;
  p.slab_bytes = int64_t(double(p.core + 2) * slice + lists) + kMeasureFixedBytes;
  return p;
}

namespace {

// Ascending distinct non-zero labels of a volume.
std::vector<uint32_t> chunk_distinct_labels(const Volume<uint32_t>& v) {
  std::vector<uint32_t> out;
  uint32_t last = 0;
  const uint32_t* d = v.data();
  for (int64_t i = 0; i < v.size(); ++i)
    if (d[i] != last) {
      last = d[i];
      if (last) out.push_back(last);
    }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace

std::vector<Particle> measure_particles_chunked(const Shape& shape, const Geometry& geometry,
                                                const LabelSlabSource& read_labels, const GreySlabSource& read_grey,
                                                int64_t core, const ParticleOptions& opt,
                                                const std::function<void(int64_t, int64_t)>& progress) {
  if (opt.surface)
    throw UsageError("surface areas need the whole label volume: measure without --memory-limit, or without --surface");
  if (core < 1) throw UsageError("measure slab by slab: core slices must be >= 1, got " + std::to_string(core));
  if (!geometry.has_voxel_size()) throw UsageError("label_stats: the label volume has no voxel size (give --voxel-um)");
  LabelStatsOptions so = opt.stats;
  so.collect_surface = true;
  so.threads = opt.threads;
  GreyVolumeOptions go = opt.grey_levels;
  go.threads = opt.threads;

  // The whole volume's sums, by label in order of first appearance.
  std::unordered_map<uint32_t, size_t> where;
  std::vector<uint32_t> labels;
  std::vector<LabelMoments> moments;
  std::vector<std::vector<SurfaceVoxel>> surface;
  std::unordered_map<uint32_t, int64_t> grey_sum;
  auto slot = [&](uint32_t l) {
    auto [it, fresh] = where.emplace(l, labels.size());
    if (fresh) {
      labels.push_back(l);
      moments.emplace_back();
      surface.emplace_back();
    }
    return it->second;
  };

  for (int64_t c0 = 0; c0 < shape.nz; c0 += core) {
    const int64_t c1 = std::min(shape.nz, c0 + core);
    const int64_t w0 = std::max<int64_t>(0, c0 - 1), w1 = std::min(shape.nz, c1 + 1);
    const Volume<uint32_t> L = read_labels(w0, w1 - w0);
    const Shape ws{w1 - w0, shape.ny, shape.nx};
    if (!(L.shape() == ws))
      throw InputError("label slab of slices " + std::to_string(w0) + ".." + std::to_string(w1 - 1) + " is " +
                       L.shape().str() + ", expected " + ws.str());
    LabelSums sums = label_sums(L.view(), c0 - w0, c1 - w0, w0, so);
    for (size_t n = 0; n < sums.labels.size(); ++n) {
      const size_t x = slot(sums.labels[n]);
      moments[x].merge(sums.moments[n]);
      auto& list = surface[x];
      list.insert(list.end(), sums.surface.begin() + sums.surface_offset[n],
                  sums.surface.begin() + sums.surface_offset[n + 1]);
    }
    if (read_grey) {
      const Volume<uint16_t> G = read_grey(w0, w1 - w0);
      if (!(G.shape() == ws))
        throw InputError("grey slab of slices " + std::to_string(w0) + ".." + std::to_string(w1 - 1) + " is " +
                         G.shape().str() + ", expected " + ws.str());
      // Every label of the window: an unlabelled core voxel gives its share
      // to the labels around it, which may lie in the margin only.
      const std::vector<uint32_t> ids = chunk_distinct_labels(L);
      const std::vector<int64_t> s = grey_volume_sums(L.view(), G.view(), ids, go, c0 - w0, c1 - w0);
      for (size_t n = 0; n < ids.size(); ++n)
        if (s[n]) grey_sum[ids[n]] += s[n];
    }
    if (progress) progress(c1, shape.nz);
  }

  // Ascending labels, as label_stats lists them.
  std::vector<size_t> order(labels.size());
  for (size_t n = 0; n < order.size(); ++n) order[n] = n;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return labels[a] < labels[b]; });
  LabelSums all;
  all.labels.reserve(order.size());
  all.moments.reserve(order.size());
  all.surface_offset.assign(order.size() + 1, 0);
  for (size_t n = 0; n < order.size(); ++n)
    all.surface_offset[n + 1] = all.surface_offset[n] + int64_t(surface[order[n]].size());
  all.surface.reserve(size_t(all.surface_offset.back()));
  std::vector<double> grey_vox;
  for (const size_t x : order) {
    all.labels.push_back(labels[x]);
    all.moments.push_back(moments[x]);
    all.surface.insert(all.surface.end(), surface[x].begin(), surface[x].end());
    std::vector<SurfaceVoxel>().swap(surface[x]);
    if (read_grey) {
      const auto it = grey_sum.find(labels[x]);
      grey_vox.push_back(it == grey_sum.end() ? 0.0 : double(it->second) / grey_volume_units);
    }
  }
  const LabelStatsResult ls = label_stats_from_sums(std::move(all), geometry, so);
  return particles_from_stats(ls, grey_vox, geometry, opt);
}

}  // namespace tg::measure
