#include "segmentation/segment_chunked.hpp"

#include "segmentation/distance_transform.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <unordered_map>

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include "core/errors.hpp"
#include "core/memory.hpp"
#include "segmentation/threshold.hpp"

namespace tg {
namespace {

constexpr int64_t kChunkAlign = 16;  // slab starts: the watershed's 8-slice blocks, in even/odd pairs

int64_t round_up_align(int64_t v) { return (v + kChunkAlign - 1) / kChunkAlign * kChunkAlign; }

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

bool chunk_progress_on() { return std::getenv("TOMOGRAIN_QUIET") == nullptr; }

// A particle owned by an earlier slab, by the position of its first voxel.
struct OwnedParticle {
  uint32_t number = 0;  // 0: dropped by the size filter
  int64_t size = 0;
};

std::string margin_advice(const ChunkPlan& p) {
  return fmt::format("the slab margin of {} slices is too small for these grains; give a larger --slab-margin-vox "
                     "(default 5 R + 4, R from --grain-radius-vox)",
                     p.margin);
}

}  // namespace

double segment_bytes_per_voxel(const SegmentOptions& o) {
  return kSegmentBytesPerVoxel +
         ((o.split || o.noise_specks) && o.threshold != ThresholdMethod::local ? kSplitGreyBytesPerVoxel : 0.0);
}

ChunkPlan plan_chunks(const Shape& s, double grain_radius_vox, const ChunkedOptions& c) {
  ChunkPlan p;
  p.estimate_bytes = int64_t(c.bytes_per_voxel * double(s.voxels())) + kSegmentFixedBytes;
  if (c.memory_limit_bytes <= 0 || p.estimate_bytes <= c.memory_limit_bytes) return p;
  p.in_memory = false;
  if (!(grain_radius_vox > 0)) throw UsageError("segment: slabs need a positive grain radius");
  p.margin = round_up_align(c.margin_vox >= 0 ? c.margin_vox : int64_t(std::ceil(5.0 * grain_radius_vox)) + 4);
  const double slice_bytes = c.bytes_per_voxel * double(s.slice_voxels());
  const int64_t fit = int64_t(double(c.memory_limit_bytes - kSegmentFixedBytes) / slice_bytes);  // slices
  p.core = (fit - 2 * p.margin) / kChunkAlign * kChunkAlign;
  if (p.core < kChunkAlign) {
    const double need = double(kSegmentFixedBytes) + slice_bytes * double(kChunkAlign + 2 * p.margin);
    throw UsageError(fmt::format(
        "segment: --memory-limit {} is too small for one slab: 16 core slices and 2 x {} margin slices of {} x {} "
        "voxels need about {} ({} B/voxel); give at least that, or a smaller --slab-margin-vox",
        human_bytes(double(c.memory_limit_bytes)), p.margin, s.ny, s.nx, human_bytes(need), c.bytes_per_voxel));
  }
  p.slabs = (s.nz + p.core - 1) / p.core;
  const int64_t thickest = std::min(s.nz, p.core + 2 * p.margin);
  p.slab_bytes = int64_t(slice_bytes * double(thickest)) + kSegmentFixedBytes;
  return p;
}

ChunkedResult segment_chunked(const Shape& shape, const Geometry& geometry, const GreySlabReader& read,
                              const LabelSlabWriter& write, const SegmentOptions& opt_in, const ChunkPlan& plan) {
  const SegmentOptions opt = opt_in.resolved();
  if (opt.threshold == ThresholdMethod::local)  // before reading anything (decide_grey says the same)
    throw UsageError("segment: --threshold local needs the whole volume at once (its blocks' thresholds); it does not "
                     "run slab by slab under --memory-limit");
  if (plan.core < kChunkAlign || plan.core % kChunkAlign || plan.margin % kChunkAlign || plan.margin < 0)
    throw UsageError("segment: slabs need a core and a margin in multiples of 16 slices");
  ChunkedResult cr;
  cr.shape = shape;
  cr.geometry = geometry;
  cr.plan = plan;
  cr.plan.slabs = (shape.nz + plan.core - 1) / plan.core;
  const int64_t sl = shape.slice_voxels();
  const bool talk = chunk_progress_on();

  // ---- Pass 1: field of view, histogram, decisions.
  auto t1 = std::chrono::steady_clock::now();
  const int64_t step = std::min(shape.nz, plan.core + 2 * plan.margin);
  FieldOfView fov = given_field_of_view(opt.fov, shape);
  const bool detect = !fov.active && opt.fov.detect && !(opt.fov.radius_vox > 0);
  FovScan scan(shape.ny, shape.nx);
  std::vector<int64_t> hist(65536, 0);
  const std::vector<double> sigmas = split_smoothing_candidates(opt);
  std::vector<std::vector<int64_t>> smoothed(opt.split ? sigmas.size() : 0), pairs(smoothed.size());
  // The slabs start at multiples of 16 slices (step is one), so the
  // smoothed sample slices find their neighbours in the slab
  // (split_labels.hpp smoothed_sample_histogram): the same histograms as
  // the one-piece run.
  auto add_hist = [&](const Volume<uint16_t>& g, int64_t z0) {
    const auto h = histogram_in_fov(g, fov);
    for (size_t b = 0; b < hist.size(); ++b) hist[b] += h[b];
    for (size_t k = 0; k < smoothed.size(); ++k)
      smoothed_sample_histogram(g, z0, shape.nz, fov, sigmas[k], smoothed[k], &pairs[k]);
  };
  for (int64_t z0 = 0; z0 < shape.nz; z0 += step) {
    const Volume<uint16_t> g = read(z0, std::min(step, shape.nz - z0));
    if (detect) scan.add(g);
    add_hist(g, z0);
  }
  if (detect) {
    fov = scan.finish(shape);
    if (fov.active) {  // the histograms again, inside the field of view now known
      cr.pass1_reads = 2;
      std::fill(hist.begin(), hist.end(), 0);
      for (auto& h : smoothed) std::fill(h.begin(), h.end(), 0);
      for (auto& h : pairs) std::fill(h.begin(), h.end(), 0);
      for (int64_t z0 = 0; z0 < shape.nz; z0 += step) add_hist(read(z0, std::min(step, shape.nz - z0)), z0);
    }
  }
  GreyDecisions d = decide_grey(fov, hist, smoothed, opt, pairs);
  // Grains of different brightness (grain_levels.hpp), as segment() does:
  // every slab levelled from grain_levels_reach() slices beyond it (so its
  // values are the whole scan's), the histograms and the decisions taken
  // again on the levelled scan, and pass 2 reads levelled slabs.
  GreySlabReader source = read;
  GrainLevelsResult gl;
  gl.spread_ratio = grain_spread_ratio(d);
  gl.dim = d.levels_dim;
  if (grain_levels_wanted(d, opt)) {
    const GrainLevelsOptions glo;
    const GrainLevelsInput in = grain_levels_input(d);
    const int64_t halo = grain_levels_reach(glo);
    auto levelled = [&read, &shape, in, glo, halo](int64_t z0, int64_t nz, GrainLevelsResult* res) {
      const int64_t a = std::max<int64_t>(0, z0 - halo), b = std::min(shape.nz, z0 + nz + halo);
      const Volume<uint16_t> lev = normalise_grain_levels(read(a, b - a), in, glo, res, z0 - a, z0 - a + nz);
      return to_volume(lev.view().slices(z0 - a, nz));
    };
    source = [levelled](int64_t z0, int64_t nz) { return levelled(z0, nz, nullptr); };
    std::fill(hist.begin(), hist.end(), 0);
    for (auto& h : smoothed) std::fill(h.begin(), h.end(), 0);
    for (auto& h : pairs) std::fill(h.begin(), h.end(), 0);
    for (int64_t z0 = 0; z0 < shape.nz; z0 += step) {
      GrainLevelsResult part;
      add_hist(levelled(z0, std::min(step, shape.nz - z0), &part), z0);
      gl.voxels_raised += part.voxels_raised;
      gl.voxels_from_smoothed += part.voxels_from_smoothed;
    }
    gl.used = true;
    gl.levels = in;
    cr.pass1_reads += 1;
    d = decide_grey(fov, std::move(hist), smoothed, opt, pairs);
  }
  cr.pass1_seconds = seconds_since(t1);
  if (talk)
    std::fprintf(stderr, "chunked: pass 1 (field of view, histogram, threshold %d) %.1f s; %lld slabs of %lld core + 2 x %lld margin slices\n",
                 int(d.t.value), cr.pass1_seconds, (long long)cr.plan.slabs, (long long)plan.core,
                 (long long)plan.margin);

  // ---- Pass 2: the slabs. Restarted with coarser levels if a core is
  // deeper than the quantisation allows (segment() coarsens it from the
  // whole volume's deepest voxel, known only at the end).
  auto t2 = std::chrono::steady_clock::now();
  float dmax_seen = 0;
  double q = opt.buckets_per_unit;
  double units = fixed_point_units(0.0f);  // the fixed-point map's (distance_transform.hpp), likewise
  auto q_for = [&](float dmax) { return levels_per_unit(dmax, opt.buckets_per_unit); };
  uint32_t running = 0;
  int64_t dropped = 0, core_solid = 0;
  bool split_used = false, specks_used = false;
  std::unordered_map<int64_t, OwnedParticle> owned;  // by the first voxel's linear index in the scan
  std::vector<std::pair<std::string, double>> stage_sum;
  for (int64_t s = 0; s < cr.plan.slabs; ++s) {
    if (s == 0) {
      running = 0, dropped = 0, core_solid = 0;
      owned.clear();
      stage_sum.clear();
      cr.slab_seconds.clear();
    }
    const auto ts = std::chrono::steady_clock::now();
    const int64_t c0 = s * plan.core, c1 = std::min(shape.nz, c0 + plan.core);
    const int64_t z0 = std::max<int64_t>(0, c0 - plan.margin), z1 = std::min(shape.nz, c1 + plan.margin);
    const int64_t cb = c0 - z0, ce = c1 - z0;
    SlabOutcome out = segment_slab(source(z0, z1 - z0), d, opt, {cb, ce, q, units, z0 == 0, z1 == shape.nz});
    const float deepest = std::max(dmax_seen, out.core_dmax);
    if (q_for(deepest) != q || fixed_point_units(deepest) != units) {
      dmax_seen = deepest;
      q = q_for(dmax_seen);
      units = fixed_point_units(dmax_seen);
      ++cr.restarts;
      if (talk)
        std::fprintf(stderr, "chunked: slab %lld is %.1f voxels deep: watershed levels coarsened to %.3g per voxel, "
                             "pass 2 starts again\n", (long long)s + 1, double(dmax_seen), q);
      s = -1;
      continue;
    }
    dmax_seen = std::max(dmax_seen, out.core_dmax);
    core_solid += out.core_solid;
    split_used = split_used || out.result.split_used;
    specks_used = specks_used || out.result.specks.used;
    for (const auto& [name, sec] : out.result.stage_seconds) {
      auto it = std::find_if(stage_sum.begin(), stage_sum.end(), [&](const auto& p) { return p.first == name; });
      if (it == stage_sum.end()) stage_sum.emplace_back(name, sec);
      else it->second += sec;
    }

    // Each slab label's first voxel (labels are numbered in raster order of
    // their first voxels, so they appear in order), the slab faces it
    // touches, and whether it has voxels in the core.
    Volume<uint32_t>& L = out.result.labels;
    const uint32_t count = out.result.count;
    const uint32_t* lp = L.data();
    std::vector<int64_t> first(size_t(count) + 1, -1);
    {
      uint32_t next = 1;
      for (int64_t i = 0; i < L.size() && next <= count; ++i)
        if (lp[i] == next) first[next++] = i;
      if (next != count + 1) throw std::logic_error("segment_chunked: slab labels are not in raster order");
    }
    enum : uint8_t { kBottom = 1, kTop = 2, kCore = 4 };
    std::vector<uint8_t> flags(size_t(count) + 1, 0);
    auto mark = [&](int64_t k0, int64_t k1, uint8_t f) {
      for (int64_t i = k0 * sl; i < k1 * sl; ++i) flags[lp[i]] |= f;
    };
    if (z0 > 0) mark(0, 1, kBottom);
    if (z1 < shape.nz) mark(L.shape().nz - 1, L.shape().nz, kTop);
    mark(cb, ce, kCore);
    std::vector<uint32_t> number(size_t(count) + 1, 0);
    for (uint32_t l = 1; l <= count; ++l) {
      const int64_t fz = first[l] / sl;
      const int64_t key = (z0 + fz) * sl + first[l] % sl;  // the first voxel in the scan
      const int64_t size = out.sizes[l];
      const auto where = [&] {
        return fmt::format("particle at voxel (z {}, y {}, x {})", z0 + fz, (first[l] % sl) / shape.nx,
                           first[l] % shape.nx);
      };
      if (fz >= cb && fz < ce) {  // owned
        if (flags[l] & kTop)
          throw UsageError(fmt::format("segment: slab {} (slices {}..{}): the {} reaches the slab's top face: {}", s + 1,
                                       z0, z1 - 1, where(), margin_advice(plan)));
        const uint32_t num = size >= opt.min_size_vox ? ++running : 0u;
        dropped += num == 0;
        number[l] = num;
        owned[key] = {num, size};
      } else if (fz < cb && (flags[l] & kCore)) {  // owned below, reaching into this core
        const auto it = owned.find(key);
        if ((flags[l] & kBottom) || it == owned.end() || it->second.size != size)
          throw UsageError(fmt::format("segment: slab {} (slices {}..{}): the {} is not the particle that {} saw "
                                       "there ({}): {}",
                                       s + 1, z0, z1 - 1, where(), "an earlier slab",
                                       (flags[l] & kBottom) ? "it is cut by the slab's bottom face"
                                       : it == owned.end()  ? "no particle starts there"
                                                            : fmt::format("{} voxels, not {}", it->second.size, size),
                                       margin_advice(plan)));
        number[l] = it->second.number;
      }
    }
    uint32_t* lw = L.data();
#pragma omp parallel for schedule(static)
    for (int64_t i = cb * sl; i < ce * sl; ++i) lw[i] = number[lw[i]];
    write(c0, L, cb, ce - cb);
    const double sec = seconds_since(ts);
    cr.slab_seconds.emplace_back(fmt::format("{}..{}", c0, c1 - 1), sec);
    if (talk)
      std::fprintf(stderr, "chunked: slab %lld/%lld, core slices %lld..%lld (read %lld..%lld): %.1f s, %u particles so far\n",
                   (long long)s + 1, (long long)cr.plan.slabs, (long long)c0, (long long)c1 - 1, (long long)z0,
                   (long long)z1 - 1, sec, running);
  }
  cr.pass2_seconds = seconds_since(t2);

  SegmentResult& r = cr.result;
  const int64_t inside = d.fov.active ? d.fov.inside_voxels(shape) : shape.voxels();
  r.solid_fraction = inside ? double(core_solid) / double(inside) : 0.0;
  r.graded = d.graded;
  r.h = opt.h;
  r.pore_criteria = {opt.pore_max_volume_vox, opt.pore_min_sphericity};
  r.buckets_per_unit = q;
  if (q < opt.buckets_per_unit)
    r.notes.push_back("watershed levels coarsened to " + std::to_string(q) +
                      " per voxel (255 levels at most; the largest distance is " + std::to_string(254.0 / q) +
                      " voxels)");
  r.count = running;
  r.dropped = dropped;
  r.split_used = split_used;
  r.face_caps_used = split_used && opt.face_caps;
  r.thin_pieces_used = split_used && opt.thin_pieces;
  r.thin_piece_radius_vox = opt.thin_piece_radius_vox;
  r.face_slivers_used = opt.face_slivers && d.void_level > 0 && d.t.method != ThresholdMethod::local;
  r.specks.used = specks_used;
  r.stage_seconds = std::move(stage_sum);
  r.stage_seconds.insert(r.stage_seconds.begin(), {"pass1", cr.pass1_seconds});
  r.grain_levels = gl;
  record_decisions(r, std::move(d), opt, shape);
  r.peak_rss_bytes = peak_rss_bytes();
  release_idle_blocks();  // the slabs' blocks (core/memory.hpp)
  return cr;
}

std::string summary_json(const ChunkedResult& cr, const SegmentOptions& opt) {
  using nlohmann::json;
  json j = json::parse(summary_json(cr.result, opt));
  const Shape& s = cr.shape;
  j["shape_zyx"] = {s.nz, s.ny, s.nx};
  j["shape"] = {s.nz, s.ny, s.nx};
  j["voxel_size_m_zyx"] = cr.geometry.voxel_size_m;
  j["peak_rss_bytes_per_voxel"] = s.voxels() ? double(cr.result.peak_rss_bytes) / double(s.voxels()) : 0.0;
  // Whole-volume counts that the slabs do not add up (a pore or a merge in
  // a margin is seen by two slabs).
  for (const char* k : {"void_components", "enclosed", "filled", "filled_voxels"}) j["pores"][k] = nullptr;
  for (const char* k : {"dim_fraction_of_solid", "dim_pockets_filled", "dim_pocket_voxels_filled"})
    j["grey_evidence"][k] = nullptr;
  j["markers"]["count"] = nullptr;
  for (const char* k : {"touching_pairs", "passing_pairs", "merges"}) j["merge"][k] = nullptr;
  for (const char* k : {"labels_tested", "labels_split", "pieces_added", "labels_too_large_to_test"}) j["split"][k] = nullptr;
  for (const char* k : {"candidates", "labels_split", "pieces_added"}) j["face_caps"][k] = nullptr;
  for (const char* k : {"labels_tested", "labels_tested_in_full", "labels_split", "pieces_added"}) j["thin_pieces"][k] = nullptr;
  for (const char* k : {"thin_labels", "pairs_touching", "merges"}) j["thin_pieces"]["walls"][k] = nullptr;
  for (const char* k : {"slivers_joined", "labels_grown", "voxels_added"}) j["face_slivers"][k] = nullptr;
  for (const char* k : {"mu0", "s0", "labels_tested", "labels_dropped", "voxels_dropped"}) j["noise_specks"][k] = nullptr;
  json slabs = json::array();
  for (const auto& [range, sec] : cr.slab_seconds) slabs.push_back({{"core_slices", range}, {"seconds", sec}});
  j["chunked"] = {{"slabs", cr.plan.slabs},
                  {"core_slices", cr.plan.core},
                  {"margin_slices", cr.plan.margin},
                  {"estimated_in_memory_bytes", cr.plan.estimate_bytes},
                  {"estimated_slab_bytes", cr.plan.slab_bytes},
                  {"pass1_seconds", cr.pass1_seconds},
                  {"pass1_reads", cr.pass1_reads},
                  {"pass2_seconds", cr.pass2_seconds},
                  {"pass2_restarts", cr.restarts},
                  {"peak_rss_bytes", cr.result.peak_rss_bytes},
                  {"peak_rss_bytes_per_voxel", j["peak_rss_bytes_per_voxel"]},
                  {"per_slab", slabs},
                  {"null_counts", "pores, dim pockets, markers, merges, splits and noise specks are counted per slab, margins twice: left out"}};
  return j.dump(2);
}

}  // namespace tg
