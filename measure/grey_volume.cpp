#include "measure/grey_volume.hpp"

#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "core/errors.hpp"

namespace tg::measure {
namespace grey_volume_detail {

// Fixed point of the sums: 2^-24 voxel per unit. A contribution is at most
// 2 voxels (f clamped to [-1, 2]), so a label of up to 2^38 voxels (far
// beyond a 1220^3 scan) cannot overflow an int64.
constexpr double kUnit = grey_volume_units;

inline int64_t fixed(double voxels) { return static_cast<int64_t>(std::llround(voxels * kUnit)); }

}  // namespace grey_volume_detail

std::vector<double> grey_volumes(const VolumeView<const uint32_t>& labels, const VolumeView<const uint16_t>& grey,
                                 const std::vector<uint32_t>& ids, const GreyVolumeOptions& opt) {
  return grey_volumes_from_sums(grey_volume_sums(labels, grey, ids, opt, 0, labels.shape().nz), opt);
}

void GreyVolumeSums::resize(size_t n) {
  inner.assign(n, 0), band.assign(n, 0), solid_grey.assign(n, 0), solid_count.assign(n, 0);
}

size_t GreyVolumeSums::append() {
  inner.push_back(0), band.push_back(0), solid_grey.push_back(0), solid_count.push_back(0);
  return inner.size() - 1;
}

void GreyVolumeSums::add(size_t to, const GreyVolumeSums& o, size_t from) {
  inner[to] += o.inner[from], band[to] += o.band[from];
  solid_grey[to] += o.solid_grey[from], solid_count[to] += o.solid_count[from];
}

std::vector<double> grey_volumes_from_sums(const GreyVolumeSums& s, const GreyVolumeOptions& opt) {
  const size_t n = s.inner.size();
  // The scale of each label's band (header, "local solid level"): the
  // scan's contrast over the contrast of this label's core.
  const double all = opt.solid_grey - opt.void_grey;
  std::vector<double> out(n);
  for (size_t x = 0; x < n; ++x) {
    double scale = 1;
    if (opt.local_solid && all > 0 && s.solid_count[x] * kCoreRowStride >= opt.min_solid_voxels) {
      const double own = double(s.solid_grey[x]) / double(s.solid_count[x]) - opt.void_grey;
      scale = std::clamp(all / std::max(own, 1e-9), kMinBandScale, kMaxBandScale);
    }
    out[x] = (double(s.inner[x]) + double(s.band[x]) * scale) / grey_volume_detail::kUnit;
  }
  return out;
}

int64_t grey_window_slices(const Shape& s) {
  const int64_t slice_bytes = std::max<int64_t>(1, s.slice_voxels()) * int64_t(sizeof(uint16_t));
  return std::clamp<int64_t>((int64_t(256) << 20) / slice_bytes, 3, std::max<int64_t>(3, s.nz));
}

std::vector<double> grey_volumes(const VolumeView<const uint32_t>& labels, const GreySlabSource& grey,
                                 const std::vector<uint32_t>& ids, const GreyVolumeOptions& opt,
                                 int64_t window_slices) {
  if (window_slices < 3) throw UsageError("grey volume: a window needs >= 3 slices (a core and one on each side)");
  const Shape s = labels.shape();
  GreyVolumeSums sum;
  sum.resize(ids.size());
  // Windows of equal size (one buffer serves them all): [c0 - 1, c0 - 1 + W)
  // holds the core [c0, c0 + W - 2); the first starts at the face, the last
  // ends there.
  for (int64_t c0 = 0; c0 < s.nz;) {
    const int64_t w0 = std::max<int64_t>(0, c0 - 1), w1 = std::min(s.nz, w0 + window_slices);
    const int64_t c1 = w1 == s.nz ? s.nz : w1 - 1;
    const Volume<uint16_t>& g = grey(w0, w1 - w0);
    const Shape ws{w1 - w0, s.ny, s.nx};
    if (!(g.shape() == ws))
      throw InputError("grey slab of slices " + std::to_string(w0) + ".." + std::to_string(w1 - 1) + " is " +
                       g.shape().str() + ", expected " + ws.str());
    const GreyVolumeSums part = grey_volume_sums(labels.slices(w0, w1 - w0), g.view(), ids, opt, c0 - w0, c1 - w0);
    for (size_t n = 0; n < ids.size(); ++n) sum.add(n, part, n);
    c0 = c1;
  }
  return grey_volumes_from_sums(sum, opt);
}

GreyVolumeSums grey_volume_sums(const VolumeView<const uint32_t>& labels, const VolumeView<const uint16_t>& grey,
                                const std::vector<uint32_t>& ids, const GreyVolumeOptions& opt, int64_t c0, int64_t c1) {
  using grey_volume_detail::fixed;
  const Shape s = labels.shape();
  if (c0 < 0 || c1 > s.nz || c0 > c1)
    throw UsageError("grey volume: core slices [" + std::to_string(c0) + ", " + std::to_string(c1) +
                     ") outside the window " + s.str());
  if (!(grey.shape() == s))
    throw UsageError("grey volume " + grey.shape().str() + " and labels " + s.str() + " differ in shape");
  if (!(opt.solid_grey > opt.void_grey))
    throw UsageError("grey volume: the solid level (" + std::to_string(opt.solid_grey) +
                     ") must be above the void level (" + std::to_string(opt.void_grey) + ")");
  if (!std::is_sorted(ids.begin(), ids.end()) || std::adjacent_find(ids.begin(), ids.end()) != ids.end())
    throw UsageError("grey volume: the label list must be ascending without repeats");
  const int nt = opt.threads > 0 ? opt.threads : omp_get_max_threads();
  const size_t nl = ids.size();
  // Label -> index in ids: a table up to 2^24 (64 MB), else binary search.
  std::vector<int32_t> table;
  if (!ids.empty() && ids.back() <= (1u << 24)) {
    table.assign(size_t(ids.back()) + 1, -1);
    for (size_t n = 0; n < nl; ++n) table[ids[n]] = int32_t(n);
  }
  auto index_of = [&](uint32_t l) -> int32_t {
    if (!table.empty()) return l < table.size() ? table[l] : -1;
    const auto it = std::lower_bound(ids.begin(), ids.end(), l);
    return it != ids.end() && *it == l ? int32_t(it - ids.begin()) : -1;
  };

  // f(g) for every grey level: (g - void) / (solid - void), clamped to
  // [-1, 2]; grey 0 is pre-masked void (header).
  std::vector<double> frac(65536);
  std::vector<int64_t> frac_fixed(65536);  // fixed(frac): a boundary voxel's share, without llround per voxel
  const double span = opt.solid_grey - opt.void_grey;
  for (size_t g = 0; g < frac.size(); ++g) {
    frac[g] = g == 0 ? 0.0 : std::clamp((double(g) - opt.void_grey) / span, -1.0, 2.0);
    frac_fixed[g] = fixed(frac[g]);
  }
  const int64_t one = fixed(1.0);
  // Core voxels (below) at least half way from the void to the solid count
  // toward their label's own solid level (a filled pore's dark voxels do not).
  const double mid = 0.5 * (opt.void_grey + opt.solid_grey);
  const uint16_t solid_from = uint16_t(std::clamp(std::ceil(mid), 1.0, 65535.0));

  std::vector<GreyVolumeSums> part(static_cast<size_t>(nt));
#pragma omp parallel num_threads(nt)
  {
    const int t = omp_get_thread_num();
    const int n_threads = omp_get_num_threads();
    GreyVolumeSums& mine = part[static_cast<size_t>(t)];
    mine.resize(nl);
    std::vector<int64_t>& acc = mine.band;
    const int64_t z0 = c0 + (c1 - c0) * t / n_threads, z1 = c0 + (c1 - c0) * (t + 1) / n_threads;
    std::array<uint32_t, 26> nb_label{};
    std::array<int, 26> nb_count{};
    // near[i]: the OR of the labels in the 3x3 rows around (k, j) at column
    // i (non-zero iff one is labelled); near3 the same over i - 1 .. i + 1.
    // Most unlabelled voxels lie far from any label: they are skipped on
    // near3 alone instead of a 26-neighbour scan (the whole pass took half
    // of `measure`'s time on a 1220^3 scan before).
    std::vector<uint32_t> near(static_cast<size_t>(s.nx)), near3(static_cast<size_t>(s.nx));
    // inner[i]: 1 where the voxel is labelled and its six face neighbours
    // carry its label (it counts one voxel). Found in a branch-free pass the
    // compiler vectorises; the voxel loop below then tests one byte instead
    // of six labels. (This function was ~30 % of `measure` on a 1220^3 scan;
    // this pass, the one-pass neighbour OR and the single-label shortcut
    // below took 21 % off it at 512^3, with the same integer sums.)
    std::vector<uint8_t> inner(static_cast<size_t>(s.nx));
    // core[i]: 1 where all 26 neighbours carry the voxel's label (>= 2 voxels
    // from its surface along every axis) and are at least half way to solid
    // (off a filled pore's wall), on the sampled rows: the voxels whose grey
    // tells the label's solid level (a voxel one inside the surface is dimmed
    // by the blur, the more so the smaller the grain).
    std::vector<uint8_t> core(static_cast<size_t>(s.nx));
    const std::vector<uint32_t> zero_row(static_cast<size_t>(s.nx), 0u);
    for (int64_t k = z0; k < z1; ++k)
      for (int64_t j = 0; j < s.ny; ++j) {
        const uint32_t* row = labels.row(k, j).data();
        const uint16_t* grow = grey.row(k, j).data();
        // The 3x3 neighbour rows (nullptr outside the volume); rows[4] is row.
        std::array<const uint32_t*, 9> rows{};
        for (int64_t dk = -1; dk <= 1; ++dk)
          for (int64_t dj = -1; dj <= 1; ++dj) {
            const int64_t kk = k + dk, jj = j + dj;
            rows[size_t(3 * (dk + 1) + dj + 1)] =
                kk >= 0 && kk < s.nz && jj >= 0 && jj < s.ny ? labels.row(kk, jj).data() : nullptr;
          }
        // One pass over the nine rows (a row of zeros outside the volume),
        // then near3 without a branch inside the row: both vectorise (nine
        // read-modify-write passes were a quarter of this function).
        std::array<const uint32_t*, 9> src{};
        for (size_t q = 0; q < 9; ++q) src[q] = rows[q] ? rows[q] : zero_row.data();
        uint32_t* nr = near.data();
        for (int64_t i = 0; i < s.nx; ++i)
          nr[i] = src[0][i] | src[1][i] | src[2][i] | src[3][i] | src[4][i] | src[5][i] | src[6][i] | src[7][i] |
                  src[8][i];
        uint32_t* n3 = near3.data();
        for (int64_t i = 1; i + 1 < s.nx; ++i) n3[i] = nr[i - 1] | nr[i] | nr[i + 1];
        n3[0] = nr[0] | (s.nx > 1 ? nr[1] : 0u);
        if (s.nx > 1) n3[s.nx - 1] = nr[s.nx - 2] | nr[s.nx - 1];
        const uint32_t *below = rows[1], *above = rows[7], *before = rows[3], *after = rows[5];
        const bool edge_row = !below || !above || !before || !after;
        uint8_t* in = inner.data();
        std::fill(inner.begin(), inner.end(), uint8_t{0});  // the row's first and last voxels touch a face
        uint8_t* co = core.data();
        std::fill(core.begin(), core.end(), uint8_t{0});
        // The core is looked for on every kCoreRowStride-th row of a slice
        // only (by j, so that a slab's rows are the whole volume's): the
        // level needs hundreds of voxels, not all, and the test's 54
        // comparisons a voxel cost 12 % of `measure --grey` on every row.
        if (!edge_row)
          for (int64_t i = 1; i < s.nx - 1; ++i) {
            const uint32_t l = row[i];
            in[i] = uint8_t((l != 0) & (below[i] == l) & (above[i] == l) & (before[i] == l) & (after[i] == l) &
                            (row[i - 1] == l) & (row[i + 1] == l));
          }
        if (!edge_row && j % kCoreRowStride == 0) {
          std::copy(inner.begin(), inner.end(), core.begin());
          // Row by row, so that each pass vectorises: the 3 x 3 rows' labels,
          // then their grey at least half way to solid too (not the wall of a
          // filled pore, whose partial volume would dim a porous grain's level).
          for (const uint32_t* r : src)
            for (int64_t i = 1; i < s.nx - 1; ++i)
              co[i] &= uint8_t((r[i - 1] == row[i]) & (r[i] == row[i]) & (r[i + 1] == row[i]));
          for (int64_t dk = -1; dk <= 1; ++dk)
            for (int64_t dj = -1; dj <= 1; ++dj) {
              const uint16_t* r = grey.row(k + dk, j + dj).data();
              for (int64_t i = 1; i < s.nx - 1; ++i)
                co[i] &= uint8_t((r[i - 1] >= solid_from) & (r[i] >= solid_from) & (r[i + 1] >= solid_from));
            }
        }
        uint32_t last = 0;  // the label of the last labelled voxel, and its index
        int32_t last_x = -1;
        for (int64_t i = 0; i < s.nx; ++i) {
          const uint32_t l = row[i];
          if (l) {
            if (l != last) last = l, last_x = index_of(l);
            if (last_x < 0) continue;
            const size_t x = size_t(last_x);
            const uint16_t g = grow[i];
            if (in[i]) {
              mine.inner[x] += one;
              if (co[i] && g >= solid_from) mine.solid_grey[x] += g, ++mine.solid_count[x];
            } else {
              acc[x] += frac_fixed[g];
            }
            continue;
          }
          if (!near3[size_t(i)]) continue;  // no labelled neighbour
          // Unlabelled: share f among the labels of the 26 neighbours, by count.
          const double f = frac[grow[i]];
          if (i > 0 && i + 1 < s.nx) {
            // Most such voxels touch one label only: found without branches
            // (the largest neighbour label, and whether every labelled
            // neighbour carries it); the general count below is the rest.
            uint32_t top = 0;
            int n = 0;
            for (const uint32_t* r : src)
              for (int64_t ii = i - 1; ii <= i + 1; ++ii) top = std::max(top, r[ii]), n += r[ii] != 0;
            bool single = true;
            for (const uint32_t* r : src)
              for (int64_t ii = i - 1; ii <= i + 1; ++ii) single &= (r[ii] == 0) | (r[ii] == top);
            if (single) {
              const int32_t x = index_of(top);
              if (x >= 0) acc[size_t(x)] += fixed(f * n / n);  // the general case's expression, count = n
              continue;
            }
          }
          int distinct = 0, n = 0;
          for (const uint32_t* nrow : rows) {
            if (!nrow) continue;
            for (int64_t ii = std::max<int64_t>(i - 1, 0); ii <= std::min(i + 1, s.nx - 1); ++ii) {
              const uint32_t m = nrow[ii];
              if (!m) continue;  // the voxel itself is 0 too
              ++n;
              int d = 0;
              while (d < distinct && nb_label[size_t(d)] != m) ++d;
              if (d == distinct) nb_label[size_t(distinct++)] = m, nb_count[size_t(d)] = 0;
              ++nb_count[size_t(d)];
            }
          }
          for (int d = 0; d < distinct; ++d) {
            const int32_t x = index_of(nb_label[size_t(d)]);
            if (x >= 0) acc[size_t(x)] += fixed(f * nb_count[size_t(d)] / n);
          }
        }
      }
  }

  GreyVolumeSums sum;
  sum.resize(nl);
  for (const auto& p : part)  // integer sums: any order gives the same result
    for (size_t n = 0; n < nl; ++n) sum.add(n, p, n);
  return sum;
}

}  // namespace tg::measure
