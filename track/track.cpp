#include "track/track.hpp"

#include <omp.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <numbers>
#include <stdexcept>
#include <unordered_map>

#include "core/clock.hpp"
#include "core/errors.hpp"
#include "core/io/hdf5.hpp"
#include "core/io/volume_io.hpp"
#include "core/memory.hpp"
#include "core/progress.hpp"
#include "measure/label_stats.hpp"
#include "track/rigid_fit.hpp"

namespace tg::track {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const char* const kEventNames[] = {"intact", "split", "fragmentation", "chipping", "chip", "new", "lost"};

bool is_break(Event e) { return e == Event::split || e == Event::fragmentation || e == Event::chipping; }

// Label value -> dense index (-1 when absent): a table up to 2^26 labels, else a hash map.
class LabelIndex {
 public:
  explicit LabelIndex(const std::vector<LineageRow>& rows) {
    uint32_t top = 0;
    for (const auto& r : rows) top = std::max(top, r.label);
    if (top <= (1u << 26)) {
      table_.assign(static_cast<size_t>(top) + 1, -1);
      for (size_t n = 0; n < rows.size(); ++n) table_[rows[n].label] = static_cast<int32_t>(n);
    } else {
      for (size_t n = 0; n < rows.size(); ++n) map_[rows[n].label] = static_cast<int32_t>(n);
    }
  }
  int32_t operator()(uint32_t label) const {
    if (!table_.empty() || map_.empty()) return label < table_.size() ? table_[label] : -1;
    auto it = map_.find(label);
    return it == map_.end() ? -1 : it->second;
  }

 private:
  std::vector<int32_t> table_;
  std::unordered_map<uint32_t, int32_t> map_;
};

// Particles of one stage: label, voxel count, centroid (voxel coordinates), border flag.
std::vector<LineageRow> particles_of(const Volume<uint32_t>& labels, int stage, int threads) {
  VolumeView<const uint32_t> v(labels.data(), labels.shape(), labels.shape().slice_voxels(), labels.shape().nx,
                               Geometry::isotropic_m(1.0));  // unit voxels: centroids come out in voxel coordinates
  measure::LabelStatsOptions so;
  so.detection_limit_m = 0;
  so.collect_surface = false;
  so.threads = threads;
  const auto st = measure::label_stats(v, so);
  std::vector<LineageRow> rows;
  rows.reserve(st.labels.size());
  for (const auto& s : st.labels) {
    LineageRow r;
    r.stage = stage;
    r.label = s.label;
    r.volume_vox = s.voxels;
    r.centroid_vox = s.centroid_m;
    r.touches_border = s.touches_border;
    r.box_lo = s.box_lo;
    r.box_hi = s.box_hi;
    rows.push_back(r);
  }
  // Voxels on the faces (step 7): the six face slices, once each.
  const Shape sh = labels.shape();
  const LabelIndex index(rows);
  auto add = [&](int64_t k, int64_t j, int64_t i) {
    const uint32_t l = labels.data()[sh.index(k, j, i)];
    const int32_t n = l ? index(l) : -1;
    if (n >= 0) ++rows[static_cast<size_t>(n)].face_vox;
  };
  for (int64_t j = 0; j < sh.ny; ++j)
    for (int64_t i = 0; i < sh.nx; ++i) add(0, j, i), add(sh.nz - 1, j, i);
  for (int64_t k = 0; k < sh.nz; ++k) {
    for (int64_t i = 0; i < sh.nx; ++i) add(k, 0, i), add(k, sh.ny - 1, i);
    for (int64_t j = 0; j < sh.ny; ++j) add(k, j, 0), add(k, j, sh.nx - 1);
  }
  return rows;
}

struct Overlap {
  int32_t a;   // index into A's rows
  uint32_t b;  // label in B
  int64_t n;
};

// ov(a, b): voxels of A particle a that land in B label b once moved by M x + shift[a]. The two
// stages may differ in shape (each scan cropped to its own specimen height): voxels that land
// outside B's volume count nowhere.
std::vector<Overlap> overlaps(const Volume<uint32_t>& A, const LabelIndex& ia, const Volume<uint32_t>& B,
                              const Eigen::Matrix3d& M, const std::vector<Eigen::Vector3d>& shift, int threads) {
  const Shape sh = A.shape(), sb = B.shape();
  const int nt = threads > 0 ? threads : omp_get_max_threads();
  std::vector<std::unordered_map<uint64_t, int64_t>> part(static_cast<size_t>(nt));
#pragma omp parallel num_threads(nt)
  {
    const int t = omp_get_thread_num(), n = omp_get_num_threads();
    auto& acc = part[static_cast<size_t>(t)];
    const int64_t z0 = sh.nz * t / n, z1 = sh.nz * (t + 1) / n;
    const double nzd = static_cast<double>(sb.nz), nyd = static_cast<double>(sb.ny), nxd = static_cast<double>(sb.nx);
    uint64_t run_key = ~uint64_t{0};
    int64_t run = 0;
    // Runs go through a small direct-mapped cache before the hash map: the same few (a, b)
    // pairs recur row after row, and a hash-map update per run was ~1/5 of this pass's time.
    constexpr size_t kCache = 256;
    std::array<uint64_t, kCache> cache_key;
    std::array<int64_t, kCache> cache_n{};
    cache_key.fill(~uint64_t{0});
    auto flush = [&] {
      if (!run) return;
      const size_t slot = static_cast<size_t>((run_key * 0x9E3779B97F4A7C15ull) >> 56);
      if (cache_key[slot] != run_key) {
        if (cache_n[slot]) acc[cache_key[slot]] += cache_n[slot];
        cache_key[slot] = run_key, cache_n[slot] = 0;
      }
      cache_n[slot] += run;
      run = 0;
    };
    uint32_t last = 0;
    int32_t ai = -1;
    Eigen::Vector3d s = Eigen::Vector3d::Zero();
    for (int64_t k = z0; k < z1; ++k)
      for (int64_t j = 0; j < sh.ny; ++j) {
        const uint32_t* row = A.data() + (k * sh.ny + j) * sh.nx;
        const Eigen::Vector3d base = M * Eigen::Vector3d(k + 0.5, j + 0.5, 0.5);
        for (int64_t i = 0; i < sh.nx; ++i) {
          const uint32_t a = row[i];
          if (!a) continue;
          if (a != last) {
            last = a;
            ai = ia(a);
            s = shift[static_cast<size_t>(ai)];
          }
          const double y0 = base[0] + M(0, 2) * static_cast<double>(i) + s[0];
          const double y1 = base[1] + M(1, 2) * static_cast<double>(i) + s[1];
          const double y2 = base[2] + M(2, 2) * static_cast<double>(i) + s[2];
          // Inside [0, n) in each axis, where truncation is the floor (no libm call per voxel).
          if (!(y0 >= 0 && y1 >= 0 && y2 >= 0 && y0 < nzd && y1 < nyd && y2 < nxd)) continue;
          const int64_t bk = static_cast<int64_t>(y0), bj = static_cast<int64_t>(y1), bi = static_cast<int64_t>(y2);
          const uint32_t b = B.data()[(bk * sb.ny + bj) * sb.nx + bi];
          if (!b) continue;
          const uint64_t key = (static_cast<uint64_t>(ai) << 32) | b;
          if (key != run_key) {
            flush();
            run_key = key;
          }
          ++run;
        }
      }
    flush();
    for (size_t q = 0; q < kCache; ++q)
      if (cache_n[q]) acc[cache_key[q]] += cache_n[q];
  }
  std::unordered_map<uint64_t, int64_t> all;
  for (const auto& p : part)
    for (const auto& [key, n] : p) all[key] += n;  // integer sums: order-free
  std::vector<Overlap> out;
  out.reserve(all.size());
  for (const auto& [key, n] : all) out.push_back({static_cast<int32_t>(key >> 32), static_cast<uint32_t>(key), n});
  std::sort(out.begin(), out.end(), [](const Overlap& x, const Overlap& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; });
  return out;
}

// Whether most of a B particle entered the field since A (its voxels the map sends outside A).
bool mostly_unseen(const LineageRow& b, int64_t unseen) { return 2 * unseen > b.volume_vox; }

// Parent (index into A, -1 none) and covered voxels of every B particle:
// the parent must cover min_overlap_fraction of the voxels of b that stage A could
// see (unseen: those that entered the field since, mapped_outside()), or, where b mostly
// entered the field since, be a particle cut by A's faces at least half of which lands in b.
// A particle the map sends wholly outside A was not in its field: new, even where a
// neighbour's refined shift (step 4) brushes it (measured: 13 of the 19 wrong parents of
// particles that mostly entered the field, on the truth labels of bench/track's R 8 window;
// no right one).
void assign_parents(const std::vector<Overlap>& ov, const LabelIndex& ib, const std::vector<LineageRow>& a_rows,
                    const std::vector<LineageRow>& b_rows, const std::vector<int64_t>& unseen,
                    const TrackOptions& opt, std::vector<int32_t>& parent, std::vector<int64_t>& covered) {
  parent.assign(b_rows.size(), -1);
  covered.assign(b_rows.size(), 0);
  for (const Overlap& o : ov) {  // ascending a: ties keep the lower index
    const int32_t bi = ib(o.b);
    if (bi < 0) continue;
    if (o.n > covered[bi]) covered[bi] = o.n, parent[bi] = o.a;
  }
  for (size_t q = 0; q < b_rows.size(); ++q) {
    if (parent[q] < 0) continue;
    const double seen = static_cast<double>(b_rows[q].volume_vox - unseen[q]);
    if (seen < 1) {
      parent[q] = -1;
      continue;
    }
    if (static_cast<double>(covered[q]) >= opt.min_overlap_fraction * seen) continue;
    // A grain entering the field, pushed further in than the map says (its own jitter): the part
    // of it the map says A saw is then larger than the sliver A did see, but that sliver, cut by
    // A's faces, lands mostly in it (measured on the truth labels of six bench/track windows: 13
    // of their 141 wrong parents right now, none made wrong; a 14-voxel sliver whose grain came
    // in as 21 104 voxels).
    const LineageRow& a = a_rows[static_cast<size_t>(parent[q])];
    const bool entering = a.touches_border && mostly_unseen(b_rows[q], unseen[q]) && 2 * covered[q] >= a.volume_vox;
    if (!entering) parent[q] = -1;
  }
}

// Step 8: where each particle of A with no child went. Its voxels (within its box) moved by the
// global map y = M x + t are counted outside B's volume, in B's labels, and in B's void; the
// largest of the three names it (`merged`: into the label that holds most of them).
std::vector<LostRow> where_lost(const Volume<uint32_t>& A, const std::vector<LineageRow>& rows,
                                const std::vector<int32_t>& lost, const Volume<uint32_t>& B, const Eigen::Matrix3d& M,
                                const Eigen::Vector3d& t, int stage, int threads) {
  const Shape sa = A.shape(), sb = B.shape();
  const double n[3] = {static_cast<double>(sb.nz), static_cast<double>(sb.ny), static_cast<double>(sb.nx)};
  std::vector<LostRow> out(lost.size());
#pragma omp parallel for schedule(dynamic) num_threads(threads > 0 ? threads : omp_get_max_threads())
  for (int64_t q = 0; q < static_cast<int64_t>(lost.size()); ++q) {
    const LineageRow& r = rows[static_cast<size_t>(lost[static_cast<size_t>(q)])];
    std::map<uint32_t, int64_t> in;  // label of B -> voxels (a lost particle is small or rare)
    int64_t outside = 0, all = 0;
    for (int64_t k = r.box_lo[0]; k < r.box_hi[0]; ++k)
      for (int64_t j = r.box_lo[1]; j < r.box_hi[1]; ++j)
        for (int64_t i = r.box_lo[2]; i < r.box_hi[2]; ++i) {
          if (A.data()[(k * sa.ny + j) * sa.nx + i] != r.label) continue;
          ++all;
          const Eigen::Vector3d y = M * Eigen::Vector3d(k + 0.5, j + 0.5, i + 0.5) + t;
          if (!(y[0] >= 0 && y[1] >= 0 && y[2] >= 0 && y[0] < n[0] && y[1] < n[1] && y[2] < n[2])) {
            ++outside;
            continue;
          }
          const uint32_t b = B.data()[(static_cast<int64_t>(y[0]) * sb.ny + static_cast<int64_t>(y[1])) * sb.nx +
                                      static_cast<int64_t>(y[2])];
          if (b) ++in[b];
        }
    LostRow& l = out[static_cast<size_t>(q)];
    l.stage = stage;
    l.label = r.label;
    int64_t most = 0;
    for (const auto& [b, c] : in) {  // ascending labels: ties keep the smaller
      l.in_labels_vox += c;
      if (c > most) most = c, l.into_label = b;
    }
    l.outside_vox = outside;
    l.void_vox = all - outside - l.in_labels_vox;
    if (l.outside_vox > 0 && l.outside_vox >= l.in_labels_vox && l.outside_vox >= l.void_vox)
      l.as = LostAs::left_field;
    else if (l.in_labels_vox > 0 && l.in_labels_vox >= l.void_vox)
      l.as = LostAs::merged;
    else
      l.as = LostAs::vanished;
    if (l.as != LostAs::merged) l.into_label = 0;
  }
  return out;
}

// Voxels of every particle of V that the affine map y = M x + t sends outside `target` (a
// volume's shape); with the inverse of the stage map and A's shape, the parts of B particles
// that entered the field since A (track.hpp step 3). Only the boxes whose corners do not all
// map inside are read: a particle clear of B's faces may still have been cut by A's (a sliver
// at A's face that moved in whole).
std::vector<int64_t> mapped_outside(const Volume<uint32_t>& V, const std::vector<LineageRow>& rows,
                                    const Eigen::Matrix3d& M, const Eigen::Vector3d& t, const Shape& target,
                                    int threads) {
  const Shape sh = V.shape();
  const double n[3] = {static_cast<double>(target.nz), static_cast<double>(target.ny), static_cast<double>(target.nx)};
  std::vector<int64_t> out(rows.size(), 0);
#pragma omp parallel for schedule(dynamic) num_threads(threads > 0 ? threads : omp_get_max_threads())
  for (int64_t q = 0; q < static_cast<int64_t>(rows.size()); ++q) {
    const LineageRow& r = rows[static_cast<size_t>(q)];
    bool inside = true;
    for (int corner = 0; corner < 8 && inside; ++corner) {
      const Eigen::Vector3d x = M * Eigen::Vector3d(static_cast<double>(corner & 1 ? r.box_hi[0] : r.box_lo[0]),
                                                    static_cast<double>(corner & 2 ? r.box_hi[1] : r.box_lo[1]),
                                                    static_cast<double>(corner & 4 ? r.box_hi[2] : r.box_lo[2])) + t;
      inside = x[0] >= 0 && x[1] >= 0 && x[2] >= 0 && x[0] < n[0] && x[1] < n[1] && x[2] < n[2];
    }
    if (inside) continue;
    int64_t c = 0;
    for (int64_t k = r.box_lo[0]; k < r.box_hi[0]; ++k)
      for (int64_t j = r.box_lo[1]; j < r.box_hi[1]; ++j)
        for (int64_t i = r.box_lo[2]; i < r.box_hi[2]; ++i) {
          if (V.data()[(k * sh.ny + j) * sh.nx + i] != r.label) continue;
          const Eigen::Vector3d x = M * Eigen::Vector3d(k + 0.5, j + 0.5, i + 0.5) + t;
          if (!(x[0] >= 0 && x[1] >= 0 && x[2] >= 0 && x[0] < n[0] && x[1] < n[1] && x[2] < n[2])) ++c;
        }
    out[static_cast<size_t>(q)] = c;
  }
  return out;
}

// For every eligible A particle, the B particle of ANOTHER parent that received most of its moved
// voxels, and how many (the larger of the overlap passes: the global map keeps a chip that drifted
// off its body's refined shift).
std::vector<NeighbourTransfer> transfers_to_neighbours(const std::vector<const std::vector<Overlap>*>& passes,
                                                       const LabelIndex& ib, const std::vector<int32_t>& parent,
                                                       const std::vector<char>& eligible) {
  std::vector<NeighbourTransfer> out(eligible.size());
  for (const auto* ov : passes)
    for (const Overlap& o : *ov) {
      const int32_t bi = ib(o.b);
      if (!eligible[static_cast<size_t>(o.a)] || bi < 0 || parent[bi] < 0 || parent[bi] == o.a) continue;
      NeighbourTransfer& x = out[static_cast<size_t>(o.a)];
      if (o.n > x.voxels) x.into = bi, x.voxels = o.n;
    }
  return out;
}

// Voxel faces between labels a and n of `v`, within a's bounding box grown by one voxel.
int64_t shared_faces(const Volume<uint32_t>& v, uint32_t a, uint32_t n, const std::array<int64_t, 3>& lo,
                     const std::array<int64_t, 3>& hi) {
  const Shape sh = v.shape();
  const int64_t dims[3] = {sh.nz, sh.ny, sh.nx}, step[3] = {sh.ny * sh.nx, sh.nx, 1};
  int64_t faces = 0;
  for (int64_t k = std::max<int64_t>(lo[0], 0); k < std::min(hi[0], sh.nz); ++k)
    for (int64_t j = std::max<int64_t>(lo[1], 0); j < std::min(hi[1], sh.ny); ++j)
      for (int64_t i = std::max<int64_t>(lo[2], 0); i < std::min(hi[2], sh.nx); ++i) {
        const int64_t at = (k * sh.ny + j) * sh.nx + i;
        if (v.data()[at] != a) continue;
        const int64_t idx[3] = {k, j, i};
        for (int ax = 0; ax < 3; ++ax) {
          if (idx[ax] > 0 && v.data()[at - step[ax]] == n) ++faces;
          if (idx[ax] + 1 < dims[ax] && v.data()[at + step[ax]] == n) ++faces;
        }
      }
  return faces;
}

}  // namespace

double new_contact_voxels(double volume_vox, double d_vox) {
  return 2 * std::numbers::pi * r_eq(volume_vox) * d_vox * d_vox;
}

const char* event_name(Event e) { return kEventNames[static_cast<int>(e)]; }

const char* lost_as_name(LostAs l) {
  static const char* const names[] = {"-", "left_field", "merged", "vanished"};
  return names[static_cast<int>(l)];
}

Event event_from_name(const std::string& name) {
  for (int e = 0; e < 7; ++e)
    if (name == kEventNames[e]) return static_cast<Event>(e);
  throw InputError("unknown event '" + name + "' (intact, split, fragmentation, chipping, chip, new, lost)");
}

namespace {
// A parent cut by the faces, one of whose smaller pieces the faces cut too (track.hpp step 5):
// the faces hide an unknown part of each, so their visible shares cannot tell a chip from a half.
bool cut_pieces(const LineageRow& pr, const std::vector<LineageRow>& rows, const std::vector<int32_t>& k) {
  if (!cut_by_faces(pr)) return false;
  for (size_t n = 1; n < k.size(); ++n)
    if (cut_by_faces(rows[static_cast<size_t>(k[n])])) return true;
  return false;
}

// The voxels of a break's piece that a neighbour's label absorbed (track.hpp step 5), 0 if none:
// a has two or more children, T (the most of its moved voxels in one B label of another parent n)
// is at least absorbed_piece_fraction of a, and both a's loss and n's gain are at least half T.
int64_t absorbed_piece(size_t a, const LineageRow& pr, int64_t after, const std::vector<int32_t>& k,
                       const std::vector<int32_t>& parent,
                       const std::vector<LineageRow>& prev, const std::vector<int64_t>& kids_volume,
                       const std::vector<NeighbourTransfer>& piece, const TrackOptions& o) {
  if (k.size() < 2 || a >= piece.size() || piece[a].into < 0) return 0;
  const NeighbourTransfer& x = piece[a];
  const int32_t n = parent[x.into];
  const auto t = static_cast<double>(x.voxels);
  const auto loss = static_cast<double>(pr.volume_vox - after);
  const auto gain = static_cast<double>(kids_volume[n] - prev[n].volume_vox);
  const bool found = t >= o.absorbed_piece_fraction * static_cast<double>(pr.volume_vox) &&
                     loss >= o.absorbed_confirm_fraction * t && gain >= o.absorbed_confirm_fraction * t;
  return found ? x.voxels : 0;
}

// The volume-loss rule's limit (track.hpp step 5): median + loss_outlier_sigmas x 1.4826 MAD of
// the relative loss 1 - V(child) / V(a) over the whole grains clear of the faces with one child,
// at least loss_floor_fraction; infinite (the rule off) with fewer than kMinLossSample of them or
// loss_outlier_sigmas = 0. A grain smaller than the sample's median r_eq (r_ref) has its loss
// weighed by (r_eq / r_ref)^loss_size_power, in the sample and in the test (LossLimit::scaled):
// the voxels a grain's label gains and loses from stage to stage lie on its surface, a share of
// its volume that grows as the grain gets smaller (measured: about as 1 / r_eq^2 on segmented
// wide gradings; track.hpp step 5).
struct LossLimit {
  double limit = std::numeric_limits<double>::infinity();
  double r_ref = 0;
  double power = 0;
  // A grain's relative loss, weighed for its size, to compare with `limit`.
  double scaled(double loss, double volume_vox) const {
    return r_ref > 0 ? loss * std::min(1.0, std::pow(r_eq(volume_vox) / r_ref, power)) : loss;
  }
};

LossLimit whole_grain_loss_limit(const std::vector<LineageRow>& prev, const std::vector<LineageRow>& rows,
                                 const std::vector<std::vector<int32_t>>& kids, const std::vector<char>& whole,
                                 const TrackOptions& o) {
  constexpr size_t kMinLossSample = 30;
  std::vector<double> loss, volume, radius;
  for (size_t a = 0; a < prev.size() && a < whole.size(); ++a) {
    if (!whole[a] || kids[a].size() != 1) continue;
    const LineageRow& c = rows[static_cast<size_t>(kids[a][0])];
    if (prev[a].touches_border || c.touches_border || prev[a].volume_vox <= 0) continue;
    const auto v = static_cast<double>(prev[a].volume_vox);
    loss.push_back(1 - static_cast<double>(c.volume_vox) / v);
    volume.push_back(v);
    radius.push_back(r_eq(v));
  }
  LossLimit L;
  if (!(o.loss_outlier_sigmas > 0) || loss.size() < kMinLossSample) return L;
  auto median = [](std::vector<double> v) {
    const size_t h = v.size() / 2;
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(h), v.end());
    const double hi = v[h];
    if (v.size() % 2) return hi;
    return 0.5 * (hi + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(h)));
  };
  L.r_ref = median(radius);
  L.power = o.loss_size_power;
  for (size_t i = 0; i < loss.size(); ++i) loss[i] = L.scaled(loss[i], volume[i]);
  const double m = median(loss);
  std::vector<double> dev(loss.size());
  for (size_t i = 0; i < loss.size(); ++i) dev[i] = std::abs(loss[i] - m);
  L.limit = std::max(o.loss_floor_fraction, m + o.loss_outlier_sigmas * 1.4826 * median(dev));
  return L;
}
}  // namespace

void link_stage(const std::vector<LineageRow>& prev, std::vector<LineageRow>& rows, const std::vector<int32_t>& parent,
                const TrackOptions& o, const LinkEvidence& ev) {
  const auto &transfer = ev.chip, &piece = ev.piece;
  const auto &gain = ev.gain, &foreign = ev.foreign;
  // Children's volume of every A particle (n's gain in the absorbed-chip rule).
  std::vector<int64_t> kids_volume(prev.size(), 0);
  for (size_t q = 0; q < rows.size(); ++q)
    if (parent[q] >= 0) kids_volume[parent[q]] += rows[q].volume_vox;
  // The children's volumes that came from their parent: a child whose label also holds a piece
  // of another parent's (foreign >= absorbed_piece_fraction of it) is counted without it.
  std::vector<double> own(rows.size());
  for (size_t q = 0; q < rows.size(); ++q) {
    const int64_t f = q < foreign.size() ? foreign[q] : 0;
    const auto v = static_cast<double>(rows[q].volume_vox);
    own[q] = static_cast<double>(f) >= o.absorbed_piece_fraction * v ? v - static_cast<double>(f) : v;
  }
  // Children of every A particle, largest (own volume) first.
  std::vector<std::vector<int32_t>> kids(prev.size());
  for (size_t q = 0; q < rows.size(); ++q)
    if (parent[q] >= 0) kids[parent[q]].push_back(static_cast<int32_t>(q));
  for (auto& k : kids) std::stable_sort(k.begin(), k.end(), [&](int32_t x, int32_t y) { return own[x] > own[y]; });
  for (auto& r : rows) {
    r.event = Event::new_particle;
    r.displacement_vox = {kNaN, kNaN, kNaN};
    r.quality = 0;
  }
  const LossLimit loss_limit = whole_grain_loss_limit(prev, rows, kids, ev.whole, o);
  for (size_t a = 0; a < prev.size(); ++a) {
    const auto& k = kids[a];
    if (k.empty()) continue;
    const LineageRow& pr = prev[a];
    int64_t after = 0;
    double own_sum = 0;
    for (int32_t q : k) after += rows[q].volume_vox, own_sum += own[q];
    const double f1 = own[k[0]] / own_sum;
    const double tol = std::max(o.min_volume_tolerance,
                                3 * o.surface_tolerance_vox / std::max(1.0, r_eq(static_cast<double>(pr.volume_vox))));
    Event first = Event::intact, rest = Event::intact;
    int64_t absorbed = 0;
    size_t glued = k.size();  // a child glued on at an earlier stage, coming apart: not linked
    std::vector<char> stray;  // children of a break that are no piece of it (not linked), if any
    // The glue of a's chain of 1:1 intact steps (track.hpp step 5): G voxels gained on V0, its
    // volume where the chain began, and the tolerance e V0 both glued-piece rules judge it with.
    const int64_t g = o.glued_pieces && a < gain.size() ? gain[a] : 0;
    const double v0 = static_cast<double>(pr.volume_vox - g), e = o.glued_volume_tolerance * v0;
    if (k.size() == 1) {
      const bool cut = pr.touches_border || rows[k[0]].touches_border;
      const double kept = static_cast<double>(after) / static_cast<double>(pr.volume_vox);
      if (!cut && kept < 1 - tol) {
        first = kept <= o.hidden_split_fraction ? Event::split : Event::chipping;
      } else if (!cut && kept <= 1 + tol && a < transfer.size() && transfer[a].into >= 0) {
        // A chip absorbed by a neighbour's label (track.hpp, step 5).
        const NeighbourTransfer& x = transfer[a];
        const int32_t n = parent[x.into];
        const double t = static_cast<double>(x.voxels);
        const double d = x.shift_vox > 0 ? x.shift_vox : o.surface_tolerance_vox;
        const double loss = static_cast<double>(pr.volume_vox - after);
        const double gain = static_cast<double>(kids_volume[n] - prev[n].volume_vox);
        if (t > d * static_cast<double>(x.contact_faces) + new_contact_voxels(static_cast<double>(pr.volume_vox), d) &&
            std::max(loss, gain) >= o.absorbed_confirm_fraction * t)
          first = Event::chipping, absorbed = x.voxels;
      }
      // A whole grain that lost more than the stage's whole grains do, its chips unseen (track.hpp step 5).
      if (first == Event::intact && !cut && a < ev.whole.size() && ev.whole[a] &&
          loss_limit.scaled(1 - kept, static_cast<double>(pr.volume_vox)) > loss_limit.limit)
        first = Event::chipping;
    } else if (const int64_t t = absorbed_piece(a, pr, after, k, parent, prev, kids_volume, piece, o); t > 0) {
      // A piece of a break in a neighbour's label (track.hpp step 5): one more child.
      const double f = std::max(own[k[0]], static_cast<double>(t)) / (own_sum + static_cast<double>(t));
      absorbed = t;
      if (f >= o.chip_body_fraction)
        first = Event::chipping, rest = Event::chip;
      else
        first = rest = Event::fragmentation;  // at least three pieces
    } else if (f1 >= o.chip_body_fraction) {
      first = Event::chipping, rest = Event::chip;
      // A piece glued on at an earlier stage coming apart (track.hpp step 5): the body
      // continues a alone and the pieces keep no parent (rows start as `new`).
      const auto body = static_cast<double>(rows[k[0]].volume_vox);
      if (static_cast<double>(g) > e && static_cast<double>(after) - body <= static_cast<double>(g) + e &&
          body >= v0 - e)
        first = Event::intact, rest = Event::new_particle;
      // Pieces that the parent covers less than half of, beside a body that kept its volume
      // within a share of the stage's limit (track.hpp step 5): not chips, but particles first
      // seen now.
      bool weak = std::isfinite(loss_limit.limit) && !ev.coverage.empty() && !pr.touches_border &&
                  loss_limit.scaled(1 - body / static_cast<double>(pr.volume_vox), static_cast<double>(pr.volume_vox)) <=
                      o.weak_piece_loss_share * loss_limit.limit;
      for (size_t n = 1; n < k.size() && weak; ++n) weak = ev.coverage[k[n]] < o.weak_piece_coverage;
      if (weak) first = Event::intact, rest = Event::new_particle;
      // A parent cut by the faces whose smaller pieces they cut too (track.hpp step 5): by count.
      if (first == Event::chipping && o.cut_pieces_by_count && cut_pieces(pr, rows, k))
        first = rest = k.size() == 2 ? Event::split : Event::fragmentation;
    } else {
      first = rest = k.size() == 2 ? Event::split : Event::fragmentation;
      // Of three or more children, those a's moved voxels cover less than half of are no piece
      // of its break (track.hpp step 5): a neighbour's crumb beside two halves is no third piece.
      if (k.size() >= 3 && !pr.touches_border && !ev.coverage.empty()) {
        stray.assign(k.size(), 0);
        size_t kept = k.size();
        for (size_t n = 1; n < k.size(); ++n)
          if (ev.coverage[k[n]] < o.weak_piece_coverage) stray[n] = 1, --kept;
        if (kept < 2) stray.clear();  // the break itself is in doubt: judged as it was
        else if (kept < k.size()) first = rest = kept == 2 ? Event::split : Event::fragmentation;
        else stray.clear();
      }
      // A piece glued on at an earlier stage coming apart beside the pieces of a's own break, or
      // beside a whole a (track.hpp step 5): the child whose volume is the gain keeps no parent,
      // and the rest are judged without it.
      if (static_cast<double>(g) > e && stray.empty()) {
        // One child only within e of G: where two are, the glue is no surer than a fragment of a.
        int matches = 0;
        for (size_t n = 0; n < k.size(); ++n)
          if (std::abs(own[k[n]] - static_cast<double>(g)) <= e) glued = n, ++matches;
        if (matches != 1) glued = k.size();
      }
      const size_t body = glued == 0 ? 1 : 0;  // the largest child but the glue
      if (glued < k.size() && k.size() == 2) {
        if (own[k[body]] >= v0 - e) first = Event::intact;
        else glued = k.size();  // the body lost more than the glue: judged as it was
      } else if (glued < k.size()) {
        const double f = own[k[body]] / (own_sum - own[k[glued]]);
        if (f >= o.chip_body_fraction) first = Event::chipping, rest = Event::chip;
        else first = rest = k.size() == 3 ? Event::split : Event::fragmentation;
      }
    }
    const size_t linked = rest == Event::new_particle ? 1 : k.size();
    const size_t lead = glued == 0 ? 1 : 0;  // the row that says `first`
    for (size_t n = 0; n < linked; ++n) {
      if (n == glued || (!stray.empty() && stray[n])) continue;  // keeps no parent (rows start as `new`)
      LineageRow& r = rows[k[n]];
      r.parent_label = pr.label;
      r.grain = pr.grain;
      r.event = n == lead ? first : rest;
      r.absorbed_vox = n == lead ? absorbed : 0;
      for (int ax = 0; ax < 3; ++ax) r.displacement_vox[ax] = r.centroid_vox[ax] - pr.centroid_vox[ax];
    }
  }
}

namespace {
bool has_voxels(const AnyVolume& v) {
  return std::visit([](const auto& x) { return x.size() > 0; }, v);
}
}  // namespace

Tracker::Tracker(TrackOptions o) : o_(std::move(o)) {}

Tracker::~Tracker() {
  std::error_code ec;
  if (!spilled_.empty()) std::filesystem::remove(spilled_, ec);
}

void Tracker::spill(const std::string& file) {
  if (prev_.empty() || !spilled_.empty()) return;
  H5Writer w(file);
  w.write_volume("/labels", prev_, 1);
  if (has_voxels(prev_grey_)) w.write_volume("/grey", prev_grey_, 1);
  w.commit();
  spilled_ = file;
  prev_ = Volume<uint32_t>{};
  prev_grey_ = AnyVolume{};
}

void Tracker::finish() {
  std::error_code ec;
  if (!spilled_.empty()) std::filesystem::remove(spilled_, ec);
  spilled_.clear();
  prev_ = Volume<uint32_t>{};
  prev_grey_ = AnyVolume{};
  finished_ = true;
}

Volume<uint32_t> Tracker::add_stage(Volume<uint32_t> labels, const std::string& name, AnyVolume grey) {
  const auto t0 = std::chrono::steady_clock::now();
  if (finished_) throw std::logic_error("Tracker::add_stage after finish()");
  if (!spilled_.empty()) {
    const H5Reader rd(spilled_);
    AnyVolume back = rd.read_volume("/labels");
    prev_ = std::move(std::get<Volume<uint32_t>>(back));
    if (rd.has("/grey")) prev_grey_ = rd.read_volume("/grey");
    std::error_code ec;
    std::filesystem::remove(spilled_, ec);
    spilled_.clear();
  }
  const int s = stages();
  if (has_voxels(grey) && !(shape_of(grey) == labels.shape()))
    throw InputError(name + ": its scan's shape differs from its labels'");
  if (s > 0) {
    const auto &g0 = prev_.geometry().voxel_size_m, &g1 = labels.geometry().voxel_size_m;
    for (int a = 0; a < 3; ++a)
      if (std::abs(g0[a] - g1[a]) > 1e-6 * std::max(std::abs(g0[a]), std::abs(g1[a])))
        throw InputError(name + ": voxel size differs from the first stage's (" + names_.front() + ")");
  }
  std::vector<LineageRow> rows = particles_of(labels, s, o_.threads);
  if (s == 0) {
    for (auto& r : rows) {
      r.grain = r.label;
      r.event = Event::intact;
      r.displacement_vox = {kNaN, kNaN, kNaN};
      r.quality = 1;
    }
    maps_.push_back(StageMap{});
  } else {
    std::vector<Point> pa, pb;
    for (const auto& r : prev_rows_) pa.push_back({r.centroid_vox, static_cast<double>(r.volume_vox)});
    for (const auto& r : rows) pb.push_back({r.centroid_vox, static_cast<double>(r.volume_vox)});
    const StageMap m =
        estimate_map(pa, pb, static_cast<double>(std::max(labels.shape().nz, prev_.shape().nz)), o_.map);
    if (!o_.allow_extension && m.axial_scale() > 1 + o_.extension_tolerance)
      throw InputError(names_.back() + " -> " + name + ": the specimen gets " +
                       std::to_string((m.axial_scale() - 1) * 100) +
                       " % longer between these stages (axial scale of the map " + std::to_string(m.axial_scale()) +
                       "): stages out of loading order?");
    maps_.push_back(m);

    const LabelIndex ia(prev_rows_), ib(rows);
    std::vector<Eigen::Vector3d> shift(prev_rows_.size(), m.t);
    std::vector<int32_t> parent, parent1;
    std::vector<int64_t> covered, covered1;
    std::vector<Overlap> ov1;
    const Eigen::Matrix3d Mi = m.M.inverse();
    const std::vector<int64_t> unseen = mapped_outside(labels, rows, Mi, -(Mi * m.t), prev_.shape(), o_.threads);
    auto ov = overlaps(prev_, ia, labels, m.M, shift, o_.threads);
    assign_parents(ov, ib, prev_rows_, rows, unseen, o_, parent, covered);
    if (o_.refine) {
      // Residual shift of each A particle: its children's volume-weighted centroid off its mapped centroid.
      std::vector<Eigen::Vector3d> sum(prev_rows_.size(), Eigen::Vector3d::Zero());
      std::vector<double> vol(prev_rows_.size(), 0);
      for (size_t q = 0; q < rows.size(); ++q) {
        if (parent[q] < 0) continue;
        const auto& c = rows[q].centroid_vox;
        sum[parent[q]] += static_cast<double>(rows[q].volume_vox) * Eigen::Vector3d(c[0], c[1], c[2]);
        vol[parent[q]] += static_cast<double>(rows[q].volume_vox);
      }
      for (size_t a = 0; a < prev_rows_.size(); ++a)
        if (vol[a] > 0) shift[a] = m.t + sum[a] / vol[a] - m.apply(prev_rows_[a].centroid_vox);
      parent1.swap(parent);
      covered1.swap(covered);
      ov1.swap(ov);
      ov = overlaps(prev_, ia, labels, m.M, shift, o_.threads);
      assign_parents(ov, ib, prev_rows_, rows, unseen, o_, parent, covered);
      // A child missed by its parent's shift (a thin chip on the side the body's centroid moved
      // away from) keeps its first-pass match: the better covered of the two passes wins.
      for (size_t q = 0; q < rows.size(); ++q)
        if (covered1[q] > covered[q] && parent1[q] >= 0) parent[q] = parent1[q], covered[q] = covered1[q];
    }
    // Particles no moved voxel covers (small pieces that drifted off their parent's voxels):
    // the A particle (of at least a quarter of the child's volume) whose moved body,
    // approximated as its equivalent sphere about its predicted centroid, the child's centroid
    // lies in or nearest to, within nearest_slack_vox. Match quality stays 0.
    for (size_t q = 0; q < rows.size(); ++q) {
      if (parent[q] >= 0 || mostly_unseen(rows[q], unseen[q])) continue;  // not a drifted piece: new material
      const auto& c = rows[q].centroid_vox;
      const Eigen::Vector3d y(c[0], c[1], c[2]);
      const double vb = static_cast<double>(rows[q].volume_vox);
      double best = o_.nearest_slack_vox * o_.nearest_slack_vox;
      for (size_t a = 0; a < prev_rows_.size(); ++a) {
        const double va = static_cast<double>(prev_rows_[a].volume_vox);
        if (va < 0.25 * vb) continue;
        const auto& ca = prev_rows_[a].centroid_vox;
        // Distance from the child's centroid to the parent's moved equivalent sphere.
        const double d = std::max(0.0, (m.M * Eigen::Vector3d(ca[0], ca[1], ca[2]) + shift[a] - y).norm() - r_eq(va));
        if (d * d < best) best = d * d, parent[q] = static_cast<int32_t>(a);
      }
    }
    {
      // A particle that mostly entered the field since A, still without parent, and a particle
      // cut by A's faces, not larger, still without child, whose moved centroid lies within the
      // first one's equivalent sphere + nearest_slack_vox: one grain, a sliver of it seen at A
      // (its moved voxels miss: jitter of the grain, a voxel or two, against a sliver of a few).
      // Quality 0. Measured on the truth labels of eight windows (bench/track): 12 of their 168
      // wrong parents right now, one made wrong; on segmented labels none worse.
      std::vector<char> has(prev_rows_.size(), 0);
      for (size_t q = 0; q < rows.size(); ++q)
        if (parent[q] >= 0) has[size_t(parent[q])] = 1;
      for (size_t q = 0; q < rows.size(); ++q) {
        if (parent[q] >= 0 || !mostly_unseen(rows[q], unseen[q])) continue;
        const auto& c = rows[q].centroid_vox;
        const Eigen::Vector3d y(c[0], c[1], c[2]);
        const double vb = static_cast<double>(rows[q].volume_vox), rb = r_eq(vb);
        double best = o_.nearest_slack_vox * o_.nearest_slack_vox;
        for (size_t a = 0; a < prev_rows_.size(); ++a) {
          const auto& pa = prev_rows_[a];
          if (has[a] || !pa.touches_border || static_cast<double>(pa.volume_vox) > vb) continue;
          const auto& ca = pa.centroid_vox;
          const double d = std::max(0.0, (m.M * Eigen::Vector3d(ca[0], ca[1], ca[2]) + shift[a] - y).norm() - rb);
          if (d * d < best) best = d * d, parent[q] = static_cast<int32_t>(a);
        }
      }
    }

    LinkEvidence ev;
    if (o_.absorbed_chips) ev.chip = transfers_to_neighbours({&ov, &ov1}, ib, parent, prev_whole_);
    // The boundary shift d of the rule (track.hpp step 5): the segmentation's surface
    // uncertainty and how far the stage's axial strain increment can press a contact of a
    // grain of radius r_eq (its two neighbours along the axis come closer by 2 strain r_eq),
    // in quadrature: the caps 2 pi r_eq d^2 that the two independent shifts move add.
    const double strain = std::max(0.0, 1.0 - m.axial_scale());
    // S_an, only where T could pass the threshold at all (a few dozen particles per stage).
    for (size_t a = 0; a < ev.chip.size(); ++a) {
      NeighbourTransfer& x = ev.chip[a];
      const auto& pa = prev_rows_[a];
      if (x.into < 0 || parent[x.into] < 0) continue;
      const int32_t n = parent[x.into];
      x.shift_vox = std::hypot(o_.surface_tolerance_vox, strain * r_eq(static_cast<double>(pa.volume_vox)));
      const double floor_vox = new_contact_voxels(static_cast<double>(pa.volume_vox), x.shift_vox);
      if (static_cast<double>(x.voxels) <= floor_vox) continue;
      const std::array<int64_t, 3> lo{pa.box_lo[0] - 1, pa.box_lo[1] - 1, pa.box_lo[2] - 1},
          hi{pa.box_hi[0] + 1, pa.box_hi[1] + 1, pa.box_hi[2] + 1};
      x.contact_faces = shared_faces(prev_, pa.label, prev_rows_[n].label, lo, hi);
    }
    if (o_.absorbed_pieces) {
      ev.piece = transfers_to_neighbours({&ov, &ov1}, ib, parent, std::vector<char>(prev_rows_.size(), 1));
      ev.foreign.assign(rows.size(), 0);
      for (const Overlap& x : ov) {
        const int32_t bi = ib(x.b);
        if (bi >= 0 && parent[bi] >= 0 && parent[bi] != x.a) ev.foreign[bi] += x.n;
      }
    }
    ev.gain = std::move(prev_gain_);  // replaced by this stage's gains below
    ev.whole = prev_whole_;
    // Of the voxels the earlier stage could see (as min_overlap_fraction is judged).
    ev.coverage.resize(rows.size());
    for (size_t q = 0; q < rows.size(); ++q)
      ev.coverage[q] = static_cast<double>(covered[q]) /
                       static_cast<double>(std::max<int64_t>(1, rows[q].volume_vox - unseen[q]));
    link_stage(prev_rows_, rows, parent, o_, ev);
    {  // Step 8: where the A particles with no child went.
      std::vector<char> has_child(prev_rows_.size(), 0);
      for (const auto& r : rows)
        if (r.parent_label) has_child[static_cast<size_t>(ia(r.parent_label))] = 1;
      std::vector<int32_t> none;
      for (size_t a = 0; a < prev_rows_.size(); ++a)
        if (!has_child[a]) none.push_back(static_cast<int32_t>(a));
      const auto l = where_lost(prev_, prev_rows_, none, labels, m.M, m.t, s, o_.threads);
      lost_.insert(lost_.end(), l.begin(), l.end());
    }
    // Displacements in the frame of the files' origins: a stage cropped differently, with the
    // crop recorded in origin_m, has not moved by the crop's offset.
    const auto& g = labels.geometry();
    for (auto& r : rows)
      for (int ax = 0; ax < 3; ++ax) r.displacement_vox[ax] += (g.origin_m[ax] - prev_origin_m_[ax]) / g.voxel_size_m[ax];
    for (size_t q = 0; q < rows.size(); ++q)
      rows[q].quality = parent[q] < 0 || rows[q].parent_label == 0
                            ? 0.0
                            : static_cast<double>(covered[q]) / static_cast<double>(rows[q].volume_vox);
    // Rotations from the grey levels (rigid_fit.hpp), from where the parent's motion puts the child.
    if (has_voxels(grey) && has_voxels(prev_grey_)) {
#pragma omp parallel for schedule(dynamic) num_threads(o_.threads > 0 ? o_.threads : omp_get_max_threads())
      for (int64_t q = 0; q < static_cast<int64_t>(rows.size()); ++q) {
        LineageRow& r = rows[static_cast<size_t>(q)];
        if (!r.parent_label) continue;
        const auto a = static_cast<size_t>(ia(r.parent_label));
        const Eigen::Vector3d cb(r.centroid_vox[0], r.centroid_vox[1], r.centroid_vox[2]);
        const RigidFit f = fit_rigid(prev_grey_, grey, labels, r.label, r.box_lo, r.box_hi, Mi * (cb - shift[a]) - cb,
                                     {}, &prev_, r.parent_label);
        if (!f.ok) continue;
        for (int ax = 0; ax < 3; ++ax) r.rotation_deg[ax] = f.rotation_deg[ax];
        r.rotation_se_deg = f.rotation_se_deg;
      }
    }
  }
  std::vector<char> whole(rows.size(), s == 0);
  std::vector<int64_t> gain(rows.size(), 0);
  // The volume where each particle's chain of 1:1 intact steps began (its own where it starts one).
  std::vector<int64_t> base(rows.size());
  for (size_t q = 0; q < rows.size(); ++q) base[q] = rows[q].volume_vox;
  if (s > 0) {
    const LabelIndex ip(prev_rows_);
    std::vector<int> linked(prev_rows_.size(), 0);
    for (const auto& r : rows)
      if (r.parent_label) ++linked[static_cast<size_t>(ip(r.parent_label))];
    for (size_t q = 0; q < rows.size(); ++q) {
      const int32_t a = rows[q].parent_label ? ip(rows[q].parent_label) : -1;
      whole[q] = a >= 0 && prev_whole_[static_cast<size_t>(a)] && rows[q].event == Event::intact;
      // Not where a face cut the parent: a grain entering the field of view grows by what
      // comes in (one clear of the faces before cannot; what it gains there was glued on).
      // The gain is counted from the chain's first volume: a piece glued on at any step of it
      // may come apart later (the glue holds while the two are pressed together).
      if (a >= 0 && linked[static_cast<size_t>(a)] == 1 && rows[q].event == Event::intact &&
          !prev_rows_[static_cast<size_t>(a)].touches_border) {
        base[q] = prev_base_[static_cast<size_t>(a)];
        gain[q] = rows[q].volume_vox - base[q];
      }
    }
  }
  lineage_.insert(lineage_.end(), rows.begin(), rows.end());
  prev_rows_ = std::move(rows);
  prev_whole_ = std::move(whole);
  prev_gain_ = std::move(gain);
  prev_base_ = std::move(base);
  prev_origin_m_ = labels.geometry().origin_m;
  prev_grey_ = std::move(grey);
  Volume<uint32_t> spent = std::move(prev_);
  prev_ = std::move(labels);
  names_.push_back(name);
  seconds_.push_back(seconds_since(t0));
  return spent;
}

TrackResult Tracker::result() const {
  TrackResult r;
  r.stage_names = names_;
  r.maps = maps_;
  r.lineage = lineage_;
  r.seconds = seconds_;
  r.lost = lost_;
  r.events = derive_events(r.lineage, stages(), lost_);
  r.summary = summarise(r.lineage, r.events, stages());
  for (int s = 0; s < stages() && s < static_cast<int>(r.summary.size()); ++s) {
    r.summary[s].axial_scale = s == 0 ? 1.0 : maps_[s].axial_scale();
    r.summary[s].map_matches = s == 0 ? 0 : maps_[s].matches;
    r.summary[s].map_method = s == 0 ? "-" : maps_[s].method;
  }
  return r;
}

namespace {

// Rows of each stage, in lineage order.
std::vector<std::vector<const LineageRow*>> by_stage(const std::vector<LineageRow>& lineage, int stages) {
  std::vector<std::vector<const LineageRow*>> out(static_cast<size_t>(stages));
  for (const auto& r : lineage)
    if (r.stage >= 0 && r.stage < stages) out[r.stage].push_back(&r);
  return out;
}

// Height fifth (1..5) of z within [lo, hi].
int band_of(double z, double lo, double hi) {
  if (!(hi > lo)) return 1;
  return std::clamp(static_cast<int>(std::floor(5 * (z - lo) / (hi - lo))) + 1, 1, 5);
}

std::pair<double, double> z_range(const std::vector<const LineageRow*>& rows) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto* r : rows) lo = std::min(lo, r->centroid_vox[0]), hi = std::max(hi, r->centroid_vox[0]);
  return {lo, hi};
}

}  // namespace

std::vector<EventRow> derive_events(const std::vector<LineageRow>& lineage, int stages,
                                    const std::vector<LostRow>& lost) {
  const auto st = by_stage(lineage, stages);
  std::map<std::pair<int, uint32_t>, const LostRow*> fate;
  for (const auto& l : lost) fate[{l.stage, l.label}] = &l;
  std::vector<EventRow> out;
  for (int s = 1; s < stages; ++s) {
    std::map<uint32_t, std::vector<const LineageRow*>> kids;
    for (const auto* r : st[s])
      if (r->parent_label) kids[r->parent_label].push_back(r);
    const auto [lo, hi] = z_range(st[s - 1]);
    for (const auto* p : st[s - 1]) {
      EventRow e;
      e.stage = s;
      e.parent_label = p->label;
      e.grain = p->grain;
      e.volume_before_vox = p->volume_vox;
      e.parent_z_vox = p->centroid_vox[0];
      e.band = band_of(p->centroid_vox[0], lo, hi);
      auto it = kids.find(p->label);
      if (it == kids.end()) {
        e.type = Event::lost;
        if (auto f = fate.find({s, p->label}); f != fate.end()) e.lost_as = f->second->as, e.into_label = f->second->into_label;
      } else {
        e.type = Event::intact;
        for (const auto* c : it->second) {
          e.children.push_back(c->label);
          e.volume_after_vox += c->volume_vox;
          if (is_break(c->event)) e.type = c->event;
          e.absorbed_vox += c->absorbed_vox;
        }
        if (e.type == Event::intact) continue;  // a plain continuation is not an event
      }
      out.push_back(std::move(e));
    }
    for (const auto* r : st[s])
      if (!r->parent_label) {
        EventRow e;
        e.stage = s;
        e.type = Event::new_particle;
        e.children = {r->label};
        e.volume_after_vox = r->volume_vox;
        e.parent_z_vox = r->centroid_vox[0];
        e.band = band_of(r->centroid_vox[0], lo, hi);
        out.push_back(std::move(e));
      }
  }
  return out;
}

bool cut_by_faces(const LineageRow& r) {
  if (r.face_vox <= 0 || r.volume_vox <= 0) return false;
  const double r_eq = std::cbrt(3.0 * static_cast<double>(r.volume_vox) / (4.0 * M_PI));
  return static_cast<double>(r.face_vox) >= kCutFootprintShare * M_PI * r_eq * r_eq;
}

std::vector<SummaryRow> summarise(const std::vector<LineageRow>& lineage, const std::vector<EventRow>& events,
                                  int stages) {
  const auto st = by_stage(lineage, stages);
  std::vector<SummaryRow> out(static_cast<size_t>(stages));
  if (stages == 0) return out;
  // Stage-0 grains and their height fifth; those the faces cut (step 7).
  std::map<uint32_t, int> grain_band;
  std::map<uint32_t, bool> cut;
  {
    const auto [lo, hi] = z_range(st[0]);
    for (const auto* r : st[0]) {
      grain_band[r->label] = band_of(r->centroid_vox[0], lo, hi);
      if (cut_by_faces(*r)) cut[r->label] = true;
    }
    if (static_cast<int64_t>(grain_band.size() - cut.size()) < kMinUncutGrains) cut.clear();
  }
  std::map<uint32_t, bool> pristine;  // label at the current stage -> still an intact grain
  std::map<uint32_t, bool> broken;    // grain -> broke at or before the current stage
  for (int s = 0; s < stages; ++s) {
    SummaryRow& row = out[s];
    row.stage = s;
    row.particles = static_cast<int64_t>(st[s].size());
    std::map<uint32_t, bool> now;
    for (const auto* r : st[s]) {
      const bool p = s == 0 ? grain_band.count(r->label) > 0
                            : r->event == Event::intact && r->parent_label && pristine.count(r->parent_label) &&
                                  pristine.at(r->parent_label);
      now[r->label] = p;
      if (r->event == Event::chip) ++row.chips;
      if (r->event == Event::new_particle && s > 0) ++row.new_particles;
    }
    pristine = std::move(now);
    for (const auto& e : events) {
      if (e.stage != s) continue;
      if (e.type == Event::split) ++row.split;
      if (e.type == Event::fragmentation) ++row.fragmentation;
      if (e.type == Event::chipping) ++row.chipping;
      if (e.type == Event::chipping && e.absorbed_vox > 0) ++row.chips_absorbed;
      if (e.type == Event::lost) {
        ++row.lost;
        row.lost_left_field += e.lost_as == LostAs::left_field;
        row.lost_merged += e.lost_as == LostAs::merged;
        row.lost_vanished += e.lost_as == LostAs::vanished;
      }
      if (is_break(e.type)) {
        ++row.breaks_band[e.band - 1];
        if (e.grain && grain_band.count(e.grain)) broken[e.grain] = true;
      }
    }
    std::map<uint32_t, bool> intact_grains;
    for (const auto* r : st[s])
      if (pristine[r->label] && r->grain && !broken.count(r->grain)) intact_grains[r->grain] = true;
    row.grains_intact = static_cast<int64_t>(intact_grains.size());
    row.grains_broken = static_cast<int64_t>(broken.size());
    row.grains_lost = static_cast<int64_t>(grain_band.size()) - row.grains_intact - row.grains_broken;
    row.grains_cut = static_cast<int64_t>(cut.size());
    auto pct = [](int64_t b, int64_t i) { return b + i ? 100.0 * static_cast<double>(b) / static_cast<double>(b + i) : 0.0; };
    row.pct_intact_broken_all = pct(row.grains_broken, row.grains_intact);
    int64_t nb_uncut = 0, ni_uncut = 0;
    for (const auto& [g, b] : broken) nb_uncut += !cut.count(g);
    for (const auto& [g, b] : intact_grains) ni_uncut += !cut.count(g);
    row.pct_intact_broken = pct(nb_uncut, ni_uncut);
    std::array<int64_t, 5> nb{}, ni{};
    for (const auto& [g, b] : broken)
      if (!cut.count(g)) ++nb[grain_band[g] - 1];
    for (const auto& [g, b] : intact_grains)
      if (!cut.count(g)) ++ni[grain_band[g] - 1];
    for (int q = 0; q < 5; ++q)
      row.pct_broken_band[q] = nb[q] + ni[q] ? 100.0 * static_cast<double>(nb[q]) / static_cast<double>(nb[q] + ni[q]) : 0.0;
  }
  return out;
}

TrackResult track_files(const std::vector<std::string>& paths, const TrackOptions& o,
                        const std::vector<std::string>& scans) {
  if (paths.empty()) throw UsageError("track: no stages given");
  if (!scans.empty() && scans.size() != paths.size())
    throw UsageError("track: " + std::to_string(scans.size()) + " scans for " + std::to_string(paths.size()) +
                     " stages (give one scan per stage, or none)");
  Tracker tr(o);
  Progress bar("track", static_cast<double>(paths.size()), "stages");
  if (!o.progress) bar.finish();
  std::vector<double> sec;
  std::vector<int64_t> peak;
  AnyVolume spare;  // the stage before last's labels: the next stage is read into them
  bool own_peak = true;
  int64_t voxels = 0;
  for (size_t s = 0; s < paths.size(); ++s) {
    own_peak = reset_peak_rss() && own_peak;
    const auto t0 = std::chrono::steady_clock::now();
    std::string spec = paths[s];
    const auto [file, ds] = split_dataset_spec(spec);
    if (format_of(spec, false) == FileFormat::hdf5 && ds.empty() && H5Reader(file).has("/labels")) spec = file + ":/labels";
    ReadOptions ro;
    ro.progress = false;
    ro.reuse = &spare;
    Volume<uint32_t> labels = read_label_volume(spec, ro);
    voxels = std::max(voxels, labels.size());  // stages cropped differently: the largest
    AnyVolume grey;
    if (!scans.empty()) {
      ReadOptions rg;
      rg.progress = false;
      grey = read_volume(scans[s], rg);
      if (!(shape_of(grey) == labels.shape()))
        throw InputError(scans[s] + ": its shape differs from the labels of " + paths[s]);
    }
    spare = tr.add_stage(std::move(labels), paths[s], std::move(grey));
    sec.push_back(seconds_since(t0));
    peak.push_back(peak_rss_bytes());
    if (o.progress) bar.update(static_cast<double>(s + 1));
  }
  if (o.progress) bar.finish();
  TrackResult r = tr.result();
  r.stage_seconds = std::move(sec);
  r.peak_rss_bytes = std::move(peak);
  r.own_peak = own_peak;
  r.voxels = voxels;
  return r;
}

Table lineage_table(const TrackResult& r) {
  RowTable t({"stage", "label", "parent_label", "grain", "event", "volume_vox", "cz_vox", "cy_vox", "cx_vox", "dz_vox",
              "dy_vox", "dx_vox", "quality", "border", "absorbed_vox", "face_vox", "rz_deg", "ry_deg", "rx_deg",
              "rotation_se_deg"});
  for (const LineageRow& x : r.lineage)
    t.row({x.stage, static_cast<int64_t>(x.label), static_cast<int64_t>(x.parent_label), static_cast<int64_t>(x.grain),
           event_name(x.event), x.volume_vox, x.centroid_vox[0], x.centroid_vox[1], x.centroid_vox[2],
           x.displacement_vox[0], x.displacement_vox[1], x.displacement_vox[2], x.quality,
           static_cast<int>(x.touches_border), x.absorbed_vox, x.face_vox, x.rotation_deg[0], x.rotation_deg[1],
           x.rotation_deg[2], x.rotation_se_deg});
  return t.table();
}

Table events_table(const TrackResult& r) {
  RowTable t({"stage", "parent_label", "grain", "type", "children", "child_labels", "volume_before_vox",
              "volume_after_vox", "absorbed_vox", "cz_vox", "band", "lost_as", "into_label"});
  for (const EventRow& e : r.events) {
    std::string kids;
    for (size_t c = 0; c < e.children.size(); ++c) {
      if (c) kids += ';';
      kids += std::to_string(e.children[c]);
    }
    t.row({e.stage, static_cast<int64_t>(e.parent_label), static_cast<int64_t>(e.grain), event_name(e.type),
           e.children.size(), kids.empty() ? "-" : kids, e.volume_before_vox, e.volume_after_vox, e.absorbed_vox,
           e.parent_z_vox, e.band, lost_as_name(e.lost_as), static_cast<int64_t>(e.into_label)});
  }
  return t.table();
}

Table summary_table(const TrackResult& r) {
  Table t;
  const size_t n = r.summary.size();
  auto col = [&](const std::string& name, auto get) {
    std::vector<double> v(n);
    for (size_t i = 0; i < n; ++i) v[i] = static_cast<double>(get(r.summary[i]));
    t.add(name, std::move(v));
  };
  col("stage", [](const SummaryRow& s) { return s.stage; });
  col("particles", [](const SummaryRow& s) { return s.particles; });
  col("grains_intact", [](const SummaryRow& s) { return s.grains_intact; });
  col("grains_broken", [](const SummaryRow& s) { return s.grains_broken; });
  col("grains_lost", [](const SummaryRow& s) { return s.grains_lost; });
  col("pct_intact_broken", [](const SummaryRow& s) { return s.pct_intact_broken; });
  col("pct_intact_broken_all", [](const SummaryRow& s) { return s.pct_intact_broken_all; });
  col("grains_cut", [](const SummaryRow& s) { return s.grains_cut; });
  col("split", [](const SummaryRow& s) { return s.split; });
  col("fragmentation", [](const SummaryRow& s) { return s.fragmentation; });
  col("chipping", [](const SummaryRow& s) { return s.chipping; });
  col("chips", [](const SummaryRow& s) { return s.chips; });
  col("chips_absorbed", [](const SummaryRow& s) { return s.chips_absorbed; });
  col("lost", [](const SummaryRow& s) { return s.lost; });
  col("lost_left_field", [](const SummaryRow& s) { return s.lost_left_field; });
  col("lost_merged", [](const SummaryRow& s) { return s.lost_merged; });
  col("lost_vanished", [](const SummaryRow& s) { return s.lost_vanished; });
  col("new", [](const SummaryRow& s) { return s.new_particles; });
  for (int b = 0; b < 5; ++b)
    col("breaks_band" + std::to_string(b + 1), [b](const SummaryRow& s) { return s.breaks_band[b]; });
  for (int b = 0; b < 5; ++b)
    col("pct_broken_band" + std::to_string(b + 1), [b](const SummaryRow& s) { return s.pct_broken_band[b]; });
  col("axial_scale", [](const SummaryRow& s) { return s.axial_scale; });
  col("map_matches", [](const SummaryRow& s) { return s.map_matches; });
  std::vector<std::string> method(n);
  for (size_t i = 0; i < n; ++i) method[i] = r.summary[i].map_method;
  t.add_text("map_method", method);
  return t;
}

void write_outputs(const TrackResult& r, const std::string& dir) {
  std::filesystem::create_directories(dir);
  const std::filesystem::path d(dir);
  write_csv(lineage_table(r), d / "lineage.csv");
  write_csv(events_table(r), d / "events.csv");
  write_csv(summary_table(r), d / "summary.csv");
}

std::vector<LineageRow> read_lineage(const Table& t) {
  const auto &stage = t.num("stage"), &label = t.num("label"), &parent = t.num("parent_label"), &grain = t.num("grain");
  const auto& ev = t.text("event");
  std::vector<LineageRow> out(static_cast<size_t>(t.rows()));
  for (int64_t i = 0; i < t.rows(); ++i) {
    LineageRow& r = out[i];
    r.stage = static_cast<int>(stage[i]);
    r.label = static_cast<uint32_t>(label[i]);
    r.parent_label = static_cast<uint32_t>(parent[i]);
    r.grain = static_cast<uint32_t>(grain[i]);
    r.event = event_from_name(ev[i]);
    if (t.has("volume_vox")) r.volume_vox = static_cast<int64_t>(t.num("volume_vox")[i]);
    if (t.has("cz_vox")) r.centroid_vox = {t.num("cz_vox")[i], t.num("cy_vox")[i], t.num("cx_vox")[i]};
    if (t.has("absorbed_vox")) r.absorbed_vox = static_cast<int64_t>(t.num("absorbed_vox")[i]);
    if (t.has("border")) r.touches_border = t.num("border")[i] != 0;
    if (t.has("face_vox")) r.face_vox = static_cast<int64_t>(t.num("face_vox")[i]);
    if (t.has("rz_deg")) r.rotation_deg = {t.num("rz_deg")[i], t.num("ry_deg")[i], t.num("rx_deg")[i]};
  }
  return out;
}

}  // namespace tg::track
