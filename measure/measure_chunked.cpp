#include "measure/measure_chunked.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <memory>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include "core/errors.hpp"
#include "core/memory.hpp"
#include "measure/contacts.hpp"
#include "measure/grey_volume.hpp"
#include "measure/label_stats.hpp"

namespace tg::measure {
namespace {

// A boundary voxel in 8 B instead of SurfaceVoxel's 16: the lists are the
// slab path's largest memory.
struct PackedSurfaceVoxel {
  uint16_t k = 0, j = 0, i = 0;
  uint8_t exposed = 0;
};
static_assert(sizeof(PackedSurfaceVoxel) == 8);
constexpr int64_t kPackedSide = 65535;
constexpr double kPerLabelBytes = 160;  // moments, list header, map entries

double slab_voxel_bytes(bool grey) { return 4.0 + (grey ? 2.0 : 0.0); }

// Core slices that fit beside `lists` bytes (boundary lists, tables), with
// `margins` slices of margin in all.
int64_t core_room(const Shape& s, double voxel_bytes, int64_t limit, double lists, int64_t margins) {
  // 10 % of the room left for what is not counted (the HDF5 reader's
  // compressed chunks, allocator slack).
  const double room = 0.9 * (double(limit - kMeasureFixedBytes) - lists);
  const double slice = voxel_bytes * double(s.slice_voxels());
  return room > 0 ? int64_t(room / slice) - margins : -margins;
}
// Pass 1's margins: the contact search's z lines look 4 slices below the core.
int64_t pass1_margins(bool contacts) { return contacts ? kCrossingMarginBelow + 1 : 2; }

// Ascending distinct non-zero labels of a volume (a set, not a list of
// every run: a slab has tens of millions of runs).
std::vector<uint32_t> chunk_distinct_labels(const Volume<uint32_t>& v) {
  std::unordered_set<uint32_t> seen;
  uint32_t last = 0;
  const uint32_t* d = v.data();
  for (int64_t i = 0; i < v.size(); ++i)
    if (d[i] != last) {
      last = d[i];
      if (last) seen.insert(last);
    }
  std::vector<uint32_t> out(seen.begin(), seen.end());
  std::sort(out.begin(), out.end());
  return out;
}

// label_sums lists a slab's boundary voxels twice on the way (per thread,
// then by label: ~40 B each) before they are packed: the core is summed in
// parts of this many slices, so that the transient lists stay small.
constexpr int64_t kSumSlices = 16;

}  // namespace

MeasureChunkPlan plan_measure_chunks(const Shape& s, GreyHeld held, int64_t limit) {
  MeasureChunkPlan p;
  const bool grey = held != GreyHeld::none;
  const double grey_bytes = held == GreyHeld::whole   ? 2.0 * double(s.voxels())
                            : held == GreyHeld::slabs ? 2.0 * double(grey_window_slices(s) * s.slice_voxels())
                                                      : 0.0;
  p.estimate_bytes = int64_t(kMeasureBytesPerVoxel * double(s.voxels()) + grey_bytes) + kMeasureFixedBytes;
  if (limit <= 0 || p.estimate_bytes <= limit) {
    p.core = s.nz;
    return p;
  }
  p.in_memory = false;
  if (std::max({s.nz, s.ny, s.nx}) > kPackedSide)
    throw UsageError("measuring " + s.str() + " slab by slab (--memory-limit): sides of up to " +
                     std::to_string(kPackedSide) + " voxels only");
  p.list_bytes = int64_t(kMeasureListBytesPerVoxel * double(s.voxels()));
  p.core = std::min(core_room(s, slab_voxel_bytes(grey), limit, double(p.list_bytes), pass1_margins(true)), s.nz);
  if (p.core < 1) {
    const double need = double(p.list_bytes) +
                        double(1 + pass1_margins(true)) * slab_voxel_bytes(grey) * double(s.slice_voxels()) +
                        double(kMeasureFixedBytes);
    throw UsageError("--memory-limit " + human_bytes(double(limit)) + " is too small to measure " + s.str() +
                     " slab by slab: the boundary voxels of its particles need about " +
                     human_bytes(double(p.list_bytes)) + " beside a slab; give at least " + human_bytes(need));
  }
  return p;
}

ChunkedMeasure measure_particles_chunked(const Shape& shape, const Geometry& geometry,
                                         const LabelSlabSource& read_labels, const GreySlabSource& read_grey,
                                         const ChunkedMeasureOptions& chunks, const ParticleOptions& opt,
                                         const std::function<void(int64_t, int64_t)>& progress) {
  if (opt.surface)
    throw UsageError("surface areas need the whole label volume: measure without --memory-limit, or without --surface");
  if (chunks.core < 0 || (chunks.core == 0 && chunks.memory_limit_bytes <= 0))
    throw UsageError("measure slab by slab: give core slices >= 1 or a memory limit");
  if (!geometry.has_voxel_size()) throw UsageError("label_stats: the label volume has no voxel size (give --voxel-um)");
  if (std::max({shape.nz, shape.ny, shape.nx}) > kPackedSide)
    throw UsageError("measuring " + shape.str() + " slab by slab: sides of up to " + std::to_string(kPackedSide) +
                     " voxels only");
  LabelStatsOptions so = opt.stats;
  so.collect_surface = true;
  so.threads = opt.threads;
  GreyVolumeOptions go = opt.grey_levels;
  go.threads = opt.threads;
  const bool with_grey = bool(read_grey);
  std::unique_ptr<ContactSearch> search;
  if (opt.contacts) {
    ContactOptions co = opt.contact;
    co.threads = opt.threads;
    search = std::make_unique<ContactSearch>(shape, geometry, co);
  }
  // Bytes of the pass-1 candidates per pair (contacts.cpp's sums) and of the
  // contacts (pass 2).
  constexpr double kPairBytes = 600;
  const int64_t margins = pass1_margins(opt.contacts);

  // The whole volume's sums, by label in order of first appearance.
  std::unordered_map<uint32_t, size_t> where;
  std::vector<uint32_t> labels;
  std::vector<LabelMoments> moments;
  std::vector<std::vector<PackedSurfaceVoxel>> surface;
  std::unordered_map<uint32_t, size_t> grey_slot;  // label -> its row of grey_sum
  GreyVolumeSums grey_sum;
  int64_t points = 0;
  auto slot = [&](uint32_t l) {
    auto [it, fresh] = where.emplace(l, labels.size());
    if (fresh) {
      labels.push_back(l);
      moments.emplace_back();
      surface.emplace_back();
    }
    return it->second;
  };

  ChunkedMeasure out;
  for (int64_t c0 = 0; c0 < shape.nz;) {
    int64_t core = chunks.core;
    if (core == 0) {
      // The lists at the end, projected from the slices read so far (the
      // plan's rate before the first slab), and the tables beside them.
      const double rate = c0 ? double(points) * double(sizeof(PackedSurfaceVoxel)) / double(c0 * shape.slice_voxels())
                             : kMeasureListBytesPerVoxel;
      const double transient = rate / double(sizeof(PackedSurfaceVoxel)) * 40.0 * double(kSumSlices) *
                               double(shape.slice_voxels());
      const double lists = rate * double(shape.voxels()) + kPerLabelBytes * double(labels.size()) +
                           (search ? kPairBytes * 4.0 * double(labels.size()) : 0.0) + transient;
      core = core_room(shape, slab_voxel_bytes(with_grey), chunks.memory_limit_bytes, lists, margins);
      if (core < 1)
        throw UsageError("--memory-limit " + human_bytes(double(chunks.memory_limit_bytes)) + " ran out at slice " +
                         std::to_string(c0) + ": the boundary voxels of the particles will need about " +
                         human_bytes(lists) + " beside a slab; give at least " +
                         human_bytes(lists + double(1 + margins) * slab_voxel_bytes(with_grey) *
                                                 double(shape.slice_voxels()) +
                                     double(kMeasureFixedBytes)));
    }
    const int64_t c1 = std::min(shape.nz, c0 + core);
    const int64_t w0 = std::max<int64_t>(0, c0 - (search ? kCrossingMarginBelow : 1)), w1 = std::min(shape.nz, c1 + 1);
    const Shape ws{w1 - w0, shape.ny, shape.nx};
    Volume<uint32_t> L = read_labels(w0, w1 - w0);
    if (!(L.shape() == ws))
      throw InputError("label slab of slices " + std::to_string(w0) + ".." + std::to_string(w1 - 1) + " is " +
                       L.shape().str() + ", expected " + ws.str());
    for (int64_t p0 = c0; p0 < c1; p0 += kSumSlices) {
      const int64_t p1 = std::min(c1, p0 + kSumSlices);
      LabelSums sums = label_sums(L.view(), p0 - w0, p1 - w0, w0, so);
      for (size_t n = 0; n < sums.labels.size(); ++n) {
        const size_t x = slot(sums.labels[n]);
        moments[x].merge(sums.moments[n]);
        auto& list = surface[x];
        // Exactly as large as needed: a vector left to double would hold up
        // to twice the lists, the largest memory of the run.
        list.reserve(list.size() + size_t(sums.surface_offset[n + 1] - sums.surface_offset[n]));
        for (int64_t q = sums.surface_offset[n]; q < sums.surface_offset[n + 1]; ++q) {
          const SurfaceVoxel& v = sums.surface[size_t(q)];
          list.push_back({uint16_t(v.k), uint16_t(v.j), uint16_t(v.i), v.exposed});
        }
        points += sums.surface_offset[n + 1] - sums.surface_offset[n];
      }
    }
    if (search) search->add_crossings(L.view(), c0 - w0, c1 - w0, w0);
    if (with_grey) {
      const Volume<uint16_t>& G = read_grey(w0, w1 - w0);
      if (!(G.shape() == ws))
        throw InputError("grey slab of slices " + std::to_string(w0) + ".." + std::to_string(w1 - 1) + " is " +
                         G.shape().str() + ", expected " + ws.str());
      // Every label of the window: an unlabelled core voxel gives its share
      // to the labels around it, which may lie in the margin only.
      const std::vector<uint32_t> ids = chunk_distinct_labels(L);
      const GreyVolumeSums s = grey_volume_sums(L.view(), G.view(), ids, go, c0 - w0, c1 - w0);
      for (size_t n = 0; n < ids.size(); ++n) {
        if (!s.inner[n] && !s.band[n]) continue;
        auto it = grey_slot.find(ids[n]);
        if (it == grey_slot.end()) it = grey_slot.emplace(ids[n], grey_sum.append()).first;
        grey_sum.add(it->second, s, n);
      }
    }
    ++out.slabs;
    c0 = c1;
    if (progress) progress(c1, shape.nz);
  }
  out.boundary_voxels = points;

  // The contacts' second pass: the normals, from slabs with the ball's
  // margin (labels only), beside the lists.
  std::vector<int> coordination_of;  // by label, in `labels` order
  if (search) {
    const int64_t m = search->ball_margin();
    for (int64_t c0 = 0; c0 < shape.nz;) {
      int64_t core = chunks.core;
      if (core == 0) {
        const double held = double(points) * double(sizeof(PackedSurfaceVoxel)) +
                            (kPerLabelBytes + kPairBytes * 4.0) * double(labels.size());
        core = core_room(shape, 4.0, chunks.memory_limit_bytes, held, 2 * m);
        if (core < 1)
          throw UsageError("--memory-limit " + human_bytes(double(chunks.memory_limit_bytes)) +
                           " leaves no room for the contact normals' slabs (" + std::to_string(2 * m + 1) +
                           " slices beside " + human_bytes(held) + " of boundary voxels and contacts)");
      }
      const int64_t c1 = std::min(shape.nz, c0 + core);
      const int64_t w0 = std::max<int64_t>(0, c0 - m), w1 = std::min(shape.nz, c1 + m);
      const Volume<uint32_t> L = read_labels(w0, w1 - w0);
      if (!(L.shape() == Shape{w1 - w0, shape.ny, shape.nx}))
        throw InputError("label slab of slices " + std::to_string(w0) + ".." + std::to_string(w1 - 1) + " is " +
                         L.shape().str());
      search->add_normals(L.view(), c0 - w0, c1 - w0, w0);
      ++out.normal_slabs;
      c0 = c1;
    }
    const ContactResult res = search->result();
    search.reset();
    out.contacts = int64_t(res.contacts.size());
    coordination_of = coordination(res.contacts, labels);
  }

  // Ascending labels, as label_stats lists them. The particles are
  // independent (particles_from_stats), so they are made in batches whose
  // lists are unpacked at a time (16 B a voxel), the packed ones freed as
  // they go: the end costs one batch, not a second copy of every list.
  std::vector<size_t> order(labels.size());
  for (size_t n = 0; n < order.size(); ++n) order[n] = n;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return labels[a] < labels[b]; });
  constexpr int64_t kBatchPoints = int64_t(1) << 24;  // 256 MB unpacked
  // Volumes from the grey sums of every slab (each label's scale needs all of them).
  const std::vector<double> grey_all = with_grey ? grey_volumes_from_sums(grey_sum, go) : std::vector<double>{};
  for (size_t first = 0; first < order.size();) {
    size_t last = first;
    int64_t batch_points = 0;
    while (last < order.size() && (last == first || batch_points + int64_t(surface[order[last]].size()) <= kBatchPoints))
      batch_points += int64_t(surface[order[last++]].size());
    LabelSums part;
    part.surface_offset.assign(last - first + 1, 0);
    part.surface.reserve(size_t(batch_points));
    std::vector<double> grey_vox;
    for (size_t n = first; n < last; ++n) {
      const size_t x = order[n];
      part.labels.push_back(labels[x]);
      part.moments.push_back(moments[x]);
      for (const PackedSurfaceVoxel& v : surface[x]) part.surface.push_back({v.k, v.j, v.i, v.exposed});
      part.surface_offset[n - first + 1] = int64_t(part.surface.size());
      std::vector<PackedSurfaceVoxel>().swap(surface[x]);
      if (with_grey) {
        const auto it = grey_slot.find(labels[x]);
        grey_vox.push_back(it == grey_slot.end() ? 0.0 : grey_all[it->second]);
      }
    }
    const LabelStatsResult ls = label_stats_from_sums(std::move(part), geometry, so);
    std::vector<Particle> ps = particles_from_stats(ls, grey_vox, geometry, opt);
    if (!coordination_of.empty())
      for (size_t n = first; n < last; ++n) ps[n - first].coordination = coordination_of[order[n]];
    out.particles.insert(out.particles.end(), std::make_move_iterator(ps.begin()), std::make_move_iterator(ps.end()));
    first = last;
  }
  return out;
}

}  // namespace tg::measure
