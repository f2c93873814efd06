#include "segmentation/segment.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fmt/core.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>
#include <omp.h>

#include "core/errors.hpp"
#include "core/memory.hpp"
#include "segmentation/connected_components.hpp"
#include "segmentation/distance_transform.hpp"
#include "segmentation/markers.hpp"
#include "segmentation/neighbourhood.hpp"

namespace tg {

double grain_radius_in_voxels(double radius_m, const Geometry& g) {
  if (!g.has_voxel_size()) throw UsageError("segment: a grain radius in metres needs the voxel size");
  return radius_m / std::min({g.voxel_size_m[0], g.voxel_size_m[1], g.voxel_size_m[2]});
}
namespace {

class StageClock {
 public:
  explicit StageClock(SegmentResult& r) : r_(r), t0_(std::chrono::steady_clock::now()) {}
  void lap(const std::string& name) {
    const auto t = std::chrono::steady_clock::now();
    r_.stage_seconds.emplace_back(name, std::chrono::duration<double>(t - t0_).count());
    t0_ = t;
  }

 private:
  SegmentResult& r_;
  std::chrono::steady_clock::time_point t0_;
};

void validate(const SegmentOptions& o) {
  if (!(o.grain_radius_vox > 0) || !std::isfinite(o.grain_radius_vox))
    throw UsageError("segment: the expected grain radius must be a positive number of voxels");
  if (o.threshold == ThresholdMethod::manual && (o.manual_threshold < 0 || o.manual_threshold > 65535))
    throw UsageError("segment: a manual threshold must be a grey level in 0..65535");
  if (o.min_size_vox < 1) throw UsageError("segment: the minimum label size must be >= 1 voxel");
  if (!(o.split_smoothing_vox >= 0) || !std::isfinite(o.split_smoothing_vox))
    throw UsageError("segment: the split repair's smoothing must be >= 0 voxels (0: chosen from the noise)");
  if (!(o.split_depth_sigmas > 0) || !std::isfinite(o.split_depth_sigmas) || !(o.split_depth_sigmas_correlated > 0) ||
      !std::isfinite(o.split_depth_sigmas_correlated))
    throw UsageError("segment: the split repair's depth must be a positive number of noise sigmas");
  if (o.saturation_level < 1 || o.saturation_level > 65535)
    throw UsageError("segment: the saturation level must be a grey level in 1..65535");
  if (o.local_window_vox < 0 || o.local_window_vox == 1)
    throw UsageError("segment: the local threshold's window must be >= 2 voxels (0: the default, 4 R)");
  seg::check_connectivity(o.connectivity);
}

// The threshold and the bright level from the histogram inside the field
// of view (the local threshold's blocks need the volume: run_from_grey);
// the split repair's depth from the smoothed sample slices' histogram.
void threshold_from_histogram(GreyDecisions& d, std::vector<int64_t>& hist,
                              const std::vector<std::vector<int64_t>>& smoothed,
                              const std::vector<std::vector<int64_t>>& pairs, const SegmentOptions& o) {
  d.levels = screen_levels(hist, o.saturation_level);
  bool any = false;
  for (const int64_t c : hist) any = any || c > 0;
  if (!any)
    throw InputError(std::string("segment: every voxel") + (d.fov.active ? " inside the field of view" : "") +
                     " is 0 (" + d.levels.action() + "): nothing to threshold");
  if (o.threshold == ThresholdMethod::manual) {
    d.t.method = ThresholdMethod::manual;
    d.t.value = static_cast<uint16_t>(o.manual_threshold);
  } else if (o.threshold == ThresholdMethod::midpoint) {
    const PhaseLevels pl = phase_levels(hist);
    d.t = moments_threshold(hist);  // its p0, z0, z1 stay in the summary
    d.t.method = ThresholdMethod::midpoint;
    d.t.value = static_cast<uint16_t>(std::clamp(std::lround(0.5 * (pl.void_level + pl.solid)), 0L, 65535L));
  } else if (o.threshold == ThresholdMethod::automatic) {
    d.t = auto_threshold(hist);
  } else {
    d.t = o.threshold == ThresholdMethod::otsu ? otsu_threshold(hist) : moments_threshold(hist);
  }
  d.t.separability = separability(hist, d.t.value);
  // The void's level and raw noise: the noise-speck test, the face slivers
  // and the split repair's test for correlated noise read them.
  const PhaseLevels phases = phase_levels(hist, d.levels.zeros_clipped ? d.levels.zero_count : 0);
  if (o.threshold != ThresholdMethod::local && o.grey_evidence) {
    // Halfway to the solid's mean grey, and at least bright_sigmas noise
    // sigmas below the solid's peak (a noisy scan lowers it, down to t:
    // then nothing is dim, and the grey evidence is off).
    const SolidPeak peak = solid_peak(hist, d.t.value);
    const double halfway = double(d.t.value) + o.bright_fraction * (mean_above(hist, d.t.value) - double(d.t.value));
    const double b = std::min(halfway, peak.mode - o.bright_sigmas * peak.sigma);
    d.bright = uint16_t(std::clamp(std::lround(b), long(d.t.value), 65535L));
    d.noise_sigma = peak.sigma;
    d.graded = d.bright > d.t.value;  // no dim band: the plain mask's chain (no second pore pass)
  }
  const std::vector<double> sigmas = split_smoothing_candidates(o);
  if (o.split && o.threshold != ThresholdMethod::local && smoothed.size() == sigmas.size()) {
    // The smoothed solid's noise from the upper side of its peak (as the
    // raw one: partial volume only widens the lower side); the floor keeps
    // a noiseless scan from splitting at every smoothing ripple. The least
    // smoothing whose depth a gap's dip can still pass (segment.hpp
    // kSplitSmoothingLadder).
    // Where the grains differ in brightness, the smoothed solid's peak is as
    // wide as the spread of their levels (smoothing leaves that whole and
    // takes the noise away): a depth of 6 such sigmas is deeper than any gap
    // (blind_scene.py --grain-contrast 0.7,1: 17 400 grey levels, no label
    // split, a third of the split halves lost). The split repair compares a
    // label's cores with the sheet between them, inside one grain, so it
    // needs what varies inside a grain: noise, and texture where the grains
    // have it (the void's noise alone split textured grains into dozens:
    // --grain-texture 0.1, F1 0.39). That sigma comes from pairs of pixels
    // inside one body (split_labels.hpp within_grain_sigma), clear of the
    // partial volume (segment.hpp kWithinGrainClearShare). Both sigmas
    // bound what varies inside a grain from above (the peak holds the
    // spread between grains, the pairs what partial volume is left above
    // the cut), so the smaller is taken.
    // (It used to take over only where the peak was over 1.5 times as wide:
    // at R 8, grain contrast 0.85-1, seeds at 1.48-1.49 kept the peak's
    // depth and 36 of 80 halves, the peer 55; bench/segmentation/RESULTS.md
    // "Grains of different brightness: each pair's own level".)
    const SolidPeak raw = solid_peak(hist, d.t.value);
    const double height = std::max(0.0, raw.mode - double(d.t.value));
    d.solid_level = raw.mode;
    for (size_t k = 0; k < sigmas.size(); ++k) {
      if (smoothed[k].size() != hist.size()) break;
      SolidPeak sm = solid_peak(smoothed[k], d.t.value);
      d.smoothed_solid_sigma = sm.sigma;
      WithinGrain within;
      if (k < pairs.size()) {
        const double clear = double(d.t.value) + kWithinGrainClearShare * height;
        within = within_grain_sigma(pairs[k], uint16_t(std::clamp(std::lround(clear), 0L, 65535L)), kWithinGrainMinPairs);
        if (within.sigma == 0) within = within_grain_sigma(pairs[k], d.t.value, kWithinGrainMinPairs);
      }
      d.within_grain_sigma = within.sigma;
      d.within_grain_pairs = within.pairs;
      d.noise_within_grains = within.sigma > 0 && within.sigma < sm.sigma;
      if (d.noise_within_grains) sm.sigma = within.sigma;
      d.split_smoothing = sigmas[k];
      d.smoothed_sigma = sm.sigma;
      // Correlated noise (segment.hpp kCorrelatedNoiseRatio): the void's
      // smoothed sigma against white noise's.
      const double white = phases.void_sigma * white_noise_gain(sigmas[k]);
      d.noise_correlation = white > 0 ? phase_levels(smoothed[k]).void_sigma / white : 0.0;
      d.depth_sigmas = d.noise_correlation > kCorrelatedNoiseRatio
                           ? std::min(o.split_depth_sigmas, o.split_depth_sigmas_correlated)
                           : o.split_depth_sigmas;
      d.split_depth = std::max(d.depth_sigmas * sm.sigma, o.split_min_depth_contrast * height);
      if (d.depth_sigmas * sm.sigma <= kSplitDepthShare * height) break;
    }
  }
  if (o.split && o.threshold != ThresholdMethod::local && smoothed.size() == sigmas.size() && !smoothed.empty() &&
      smoothed.back().size() == hist.size()) {
    // Grain levels (grain_levels.hpp) read the smoothest sample histogram.
    d.levels_void = phases.void_level;
    // The brightest grains' level: the 99th percentile of the smoothed
    // solid (the mode is wherever most grains happen to lie).
    const std::vector<int64_t>& h = smoothed.back();
    int64_t above = 0;
    for (size_t g = size_t(d.t.value) + 1; g < h.size(); ++g) above += h[g];
    int64_t seen = 0;
    for (size_t g = size_t(d.t.value) + 1; g < h.size() && above > 0; ++g)
      if ((seen += h[g]) >= int64_t(std::ceil(kGrainLevelsSolidShare * double(above)))) {
        d.levels_solid = double(g);
        break;
      }
    d.levels_void_sigma = phase_levels(smoothed.back()).void_sigma;
    // A darker population is looked for below the smoothed solid's mode (a
    // broad solid peak, textured grains, puts its 99th percentile far above
    // the mode, and the peak's own flank would read as a population).
    const double mode = solid_peak(h, d.t.value).mode;
    d.levels_dim = dim_population(h, {d.levels_void, std::min(mode, d.levels_solid), d.levels_void_sigma});
  }
  if ((o.noise_specks || o.face_slivers) && o.threshold != ThresholdMethod::local) {
    // The void's noise above t (noise_specks.hpp): the void peak's mode and
    // the sigma of its lower side, the voxels a noisy scan clipped at 0
    // counted in (the solid's sigma is no stand-in: where the threshold lies
    // low, the void's tail fills the histogram above it). The void's grey
    // also sets the face slivers' half levels (face_slivers.hpp).
    d.void_level = phases.void_level;
    if (o.noise_specks) {
      d.speck_test.threshold = double(d.t.value);
      d.speck_test.void_level = phases.void_level;
      d.speck_test.sigma = phases.void_sigma;
      d.speck_test.z_crit = o.speck_z;
    }
  }
  if (d.split_depth > 0 || d.speck_test.sigma > 0 || d.void_level > 0) d.split_code = GreyCode::from_histogram(hist);
}

GreyDecisions choose_threshold(const Volume<uint16_t>& grey, const SegmentOptions& o) {
  GreyDecisions d;
  d.fov = find_field_of_view(grey, o.fov);
  auto hist = histogram_in_fov(grey, d.fov);
  std::vector<std::vector<int64_t>> smoothed, pairs;
  if (o.split && o.threshold != ThresholdMethod::local)
    for (const double s : split_smoothing_candidates(o))
      smoothed_sample_histogram(grey, 0, grey.shape().nz, d.fov, s, smoothed.emplace_back(), &pairs.emplace_back());
  threshold_from_histogram(d, hist, smoothed, pairs, o);
  if (o.threshold == ThresholdMethod::local) {
    d.t.method = ThresholdMethod::local;
    const int64_t w = o.local_window_vox > 0 ? o.local_window_vox : default_local_window(o.grain_radius_vox);
    d.local = local_moments_thresholds(grey, d.fov, hist, w, d.t.value);
  }
  return d;
}

// What a slab of a chunked run needs beyond the plain chain (segment.hpp
// SlabWindow) and what it reports back.
struct SlabRun {
  SlabWindow window;
  SlabOutcome* out = nullptr;
  int64_t min_size_vox = 8;  // the caller's size floor (the slab's own chain runs with 1)
};

// The merge's share test in the grey code's units (merge_labels.hpp
// MergeOptions::grey): the threshold, and the grading's bright level (graded
// bright at or below it: brightened by the pore filling).
struct MergeGrey {
  uint8_t floor = 0, filled = 0;
};

// grey_code (or nullptr) and split_depth > 0: the split repair runs on the
// labels; depth and floor in the code's units. grey_code and specks: the
// noise-speck test (in the code's units) runs first.
SegmentResult segment_graded(Volume<uint8_t> mask, const SegmentOptions& opt, bool graded, SlabRun* slab = nullptr,
                             const Volume<uint8_t>* grey_code = nullptr, double split_depth = 0,
                             double split_floor = 0, const SpeckTest* specks = nullptr, double solid_level = 0,
                             const FaceSliverOptions* slivers = nullptr, const MergeGrey* merge_grey = nullptr);

// grey -> mask with the decisions d, then the chain. The core's solid count
// (slab) or the field of view's goes to *nsolid_out.
SegmentResult chain_from_grey(const Volume<uint16_t>& grey, Volume<uint16_t>* owned, const GreyDecisions& d,
                              const SegmentOptions& opt, SlabRun* slab, int64_t* nsolid_out, StageClock& clock) {
  const ThresholdResult& t = d.t;
  const Shape shape = grey.shape();
  // The split repair reads the grey after the watershed: a one-byte code of
  // it (split_labels.hpp GreyCode) stays, 1 B/voxel more at peak. An owned
  // scan becomes the mask in its own storage.
  const bool split = d.split_depth > 0 && t.method != ThresholdMethod::local;
  const bool specks = d.speck_test.sigma > 0 && t.method != ThresholdMethod::local;
  const bool slivers = opt.face_slivers && d.void_level > 0 && t.method != ThresholdMethod::local;
  Volume<uint8_t> code;
  if (split || specks || slivers) code = quantise_grey(grey, d.split_code);
  Volume<uint8_t> mask;
  if (t.method == ThresholdMethod::local) {
    mask = owned ? binarise_local(std::move(*owned), d.local, d.fov) : binarise_local(grey, d.local, d.fov);
  } else {
    if (d.graded)
      mask = owned ? binarise_graded(std::move(*owned), t.value, d.bright) : binarise_graded(grey, t.value, d.bright);
    else
      mask = owned ? binarise(std::move(*owned), t.value) : binarise(grey, t.value);
    clear_outside(mask, d.fov);
  }
  // Solid fraction of the field of view (segment_mask's is of the whole
  // volume); of a slab, the core's solid voxels.
  int64_t nsolid = 0;
  if (d.fov.active || slab) {
    const int64_t sl = shape.slice_voxels();
    const int64_t lo = slab ? slab->window.core_begin * sl : 0, hi = slab ? slab->window.core_end * sl : mask.size();
    const uint8_t* m = mask.data();
#pragma omp parallel for schedule(static) reduction(+ : nsolid)
    for (int64_t i = lo; i < hi; ++i) nsolid += m[i] != 0;
  }
  *nsolid_out = nsolid;
  clock.lap("threshold");
  const GreyCode& c = d.split_code;
  SpeckTest st = d.speck_test;  // in the code's units
  st.threshold = (st.threshold - c.lo) / c.step, st.void_level = (st.void_level - c.lo) / c.step, st.sigma /= c.step;
  SegmentOptions o = opt;
  o.split_smoothing_vox = d.split_smoothing;  // chosen from the noise (decide_grey) unless given
  auto code_of = [&](double g) { return uint8_t(std::clamp(std::lround((g - c.lo) / c.step), 0L, 255L)); };
  const MergeGrey mg{code_of(double(t.value)), code_of(double(d.bright))};
  FaceSliverOptions fs;  // in the code's units; a slab's cut faces are not the scan's
  fs.threshold = (double(t.value) - c.lo) / c.step, fs.void_level = (d.void_level - c.lo) / c.step;
  if (slab) fs.faces[0] = slab->window.scan_bottom, fs.faces[1] = slab->window.scan_top;
  fs.min_size_vox = slab ? slab->min_size_vox : opt.min_size_vox;
  return segment_graded(std::move(mask), o, d.graded, slab, split || specks || slivers ? &code : nullptr,
                        split ? d.split_depth / c.step : 0.0, (double(t.value) - c.lo) / c.step, specks ? &st : nullptr,
                        (d.solid_level - c.lo) / c.step, slivers ? &fs : nullptr, &mg);
}



SegmentResult run_from_grey(const Volume<uint16_t>& grey, Volume<uint16_t>* owned, const SegmentOptions& opt) {
  validate(opt);
  SegmentResult r0;
  StageClock clock(r0);
  GreyDecisions d = choose_threshold(grey, opt);
  const Shape whole = grey.shape();
  // Grains of different brightness: the scan levelled grain by grain, and
  // every grey decision taken again on it (the grains now share one level).
  const GrainLevelsOptions glo;
  GrainLevelsResult gl;
  gl.spread_ratio = grain_spread_ratio(d);
  gl.dim = d.levels_dim;
  Volume<uint16_t> levelled;
  const Volume<uint16_t>* src = &grey;
  if (grain_levels_wanted(d, opt)) {
    const GrainLevelsResult first = gl;
    levelled = normalise_grain_levels(grey, grain_levels_input(d), glo, &gl);
    gl.spread_ratio = first.spread_ratio;
    gl.dim = first.dim;
    if (owned) *owned = Volume<uint16_t>();  // the raw scan is read no more
    src = owned = &levelled;
    clock.lap("grain_levels");
    d = choose_threshold(levelled, opt);
  }
  int64_t nsolid = 0;
  SegmentResult r = chain_from_grey(*src, owned, d, opt, nullptr, &nsolid, clock);
  r.grain_levels = gl;
  if (d.fov.active) {
    const int64_t inside = d.fov.inside_voxels(whole);
    r.solid_fraction = inside ? double(nsolid) / double(inside) : 0.0;
  }
  record_decisions(r, std::move(d), opt, whole);
  r.stage_seconds.insert(r.stage_seconds.begin(), r0.stage_seconds.begin(), r0.stage_seconds.end());
  return r;
}

}  // namespace

double grain_spread_ratio(const GreyDecisions& d) {
  return d.within_grain_sigma > 0 ? d.smoothed_solid_sigma / d.within_grain_sigma : 0.0;
}

bool grain_levels_wanted(const GreyDecisions& d, const SegmentOptions& opt) {
  return opt.grain_levels && (grain_spread_ratio(d) >= GrainLevelsOptions{}.min_spread_ratio || d.levels_dim.found) &&
         d.levels_void_sigma > 0 && d.levels_solid > d.levels_void;
}

GrainLevelsInput grain_levels_input(const GreyDecisions& d) {
  return {d.levels_void, d.levels_solid, d.levels_void_sigma};
}

void record_decisions(SegmentResult& r, GreyDecisions d, const SegmentOptions& opt, const Shape& whole) {
  const ThresholdResult& t = d.t;
  if (!r.grain_levels.used) {
    r.grain_levels.spread_ratio = grain_spread_ratio(d);
    r.grain_levels.dim = d.levels_dim;
    r.grain_levels.levels = grain_levels_input(d);
  } else {
    r.notes.push_back(fmt::format(
        "grain levels ran ({}): grains darker than the rest were raised to the solid's grey before the threshold; "
        "anything else of intermediate grey inside the field of view (a container's wall) is raised with them: mask "
        "it, or give --no-grain-levels",
        r.grain_levels.dim.found ? fmt::format("a darker population at grey {:.0f}", r.grain_levels.dim.level)
                                 : fmt::format("the solid peak {:.1f} x the grey's spread inside a grain",
                                               r.grain_levels.spread_ratio)));
  }
  r.threshold = t;
  r.bright_value = d.bright;
  r.solid_noise_sigma = d.noise_sigma;
  r.smoothed_noise_sigma = d.smoothed_sigma;
  r.smoothed_solid_sigma = d.smoothed_solid_sigma;
  r.within_grain_sigma = d.within_grain_sigma;
  r.within_grain_pairs = d.within_grain_pairs;
  r.split_noise_within_grains = d.noise_within_grains;
  r.split_noise_correlation = d.noise_correlation;
  r.split_depth_sigmas_used = d.depth_sigmas;
  r.split_smoothing_vox = d.split_smoothing;
  r.split_depth = r.split_used ? d.split_depth : 0.0;
  r.split_code = d.split_code;
  r.speck_test = d.speck_test;
  r.void_level = d.void_level;
  if (opt.split && !r.split_used)
    r.notes.push_back(t.method == ThresholdMethod::local
                          ? "split repair off: it needs one global threshold (not --threshold local)"
                          : "split repair off: no smoothed solid peak to set its depth");
  if (r.split_used && d.noise_within_grains)
    r.notes.push_back(fmt::format(
        "the smoothed solid's grey peak is {:.1f} times as wide as the grey varies inside a grain (grains of "
        "different brightness, a texture inside them, or brightness drifting over the scan): the split repair's depth "
        "is from the latter",
        d.smoothed_solid_sigma / d.within_grain_sigma));
  if (opt.grey_evidence && t.method != ThresholdMethod::local && !d.graded)
    r.notes.push_back("grey evidence off: the solid's grey spread (sigma " + std::to_string(long(d.noise_sigma)) +
                      " grey levels: noise, and grains of different brightness) leaves no dim band between the "
                      "threshold and " + std::to_string(int(opt.bright_sigmas)) + " sigmas below the solid's peak");
  if (opt.grey_evidence && t.method == ThresholdMethod::local)
    r.notes.push_back("grey evidence off: it needs one global threshold (not --threshold local)");
  std::vector<std::string> notes;
  if (!t.note.empty()) notes.push_back(t.note);
  if (!d.fov.note.empty()) notes.push_back(d.fov.note);
  if (d.fov.active)
    notes.push_back(fmt::format("field of view ({}): centre (y {:.1f}, x {:.1f}), radius {:.1f} voxels; {:.3g} % of the "
                                "voxels outside, not thresholded nor labelled",
                                d.fov.source, d.fov.centre_y, d.fov.centre_x, d.fov.radius,
                                100.0 * double(d.fov.outside_voxels) / double(std::max<int64_t>(1, whole.voxels()))));
  notes.insert(notes.end(), d.levels.notes.begin(), d.levels.notes.end());
  if (!d.local.note.empty()) notes.push_back(d.local.note);
  r.notes.insert(r.notes.begin(), notes.begin(), notes.end());
  if (t.separability < 0.75)
    r.notes.push_back("the grey histogram is hardly bimodal (separability " + std::to_string(t.separability) +
                      " < 0.75; one noisy phase gives 0.64): the scan may hold void only or solid only, and the "
                      "labels may be noise");
  r.fov = std::move(d.fov);
  r.levels = std::move(d.levels);
  r.local = std::move(d.local);
}

std::vector<double> split_smoothing_candidates(const SegmentOptions& opt) {
  if (opt.split_smoothing_vox > 0) return {opt.split_smoothing_vox};
  return std::vector<double>(std::begin(kSplitSmoothingLadder), std::end(kSplitSmoothingLadder));
}

GreyDecisions decide_grey(FieldOfView fov, std::vector<int64_t> hist,
                          const std::vector<std::vector<int64_t>>& smoothed_hist, const SegmentOptions& opt,
                          const std::vector<std::vector<int64_t>>& pair_hists) {
  validate(opt);
  if (opt.threshold == ThresholdMethod::local)
    throw UsageError("segment: --threshold local needs the whole volume at once (its blocks' thresholds); it does not "
                     "run slab by slab under --memory-limit");
  GreyDecisions d;
  d.fov = std::move(fov);
  threshold_from_histogram(d, hist, smoothed_hist, pair_hists, opt);
  return d;
}

SlabOutcome segment_slab(Volume<uint16_t>&& grey, const GreyDecisions& d, const SegmentOptions& opt_in,
                         const SlabWindow& w) {
  validate(opt_in);
  if (!(w.core_begin >= 0 && w.core_begin < w.core_end && w.core_end <= grey.shape().nz))
    throw UsageError("segment: a slab's core must be a non-empty range of its slices");
  if (!(w.buckets_per_unit > 0)) throw UsageError("segment: a slab needs the scan's watershed levels per unit");
  SegmentOptions opt = opt_in;
  opt.min_size_vox = 1;  // the size filter needs whole particles: the caller applies it
  SlabOutcome out;
  SlabRun run{w, &out, opt_in.min_size_vox};
  SegmentResult r0;
  StageClock clock(r0);
  Volume<uint16_t> g = std::move(grey);
  out.result = chain_from_grey(g, &g, d, opt, &run, &out.core_solid, clock);
  out.result.stage_seconds.insert(out.result.stage_seconds.begin(), r0.stage_seconds.begin(), r0.stage_seconds.end());
  return out;
}

SegmentOptions SegmentOptions::resolved() const {
  SegmentOptions o = *this;
  validate(o);
  if (o.pore_max_volume_vox < 0) o.pore_max_volume_vox = PoreFilterOptions::from_grain_radius(grain_radius_vox).max_volume_vox;
  if (std::isnan(o.h)) throw UsageError("segment: the marker depth h must be a number");
  if (o.h < 0) o.h = std::max(0.5, 0.035 * o.grain_radius_vox);
  if (std::isnan(o.thin_piece_radius_vox) || o.thin_piece_radius_vox < 0 || !std::isfinite(o.thin_piece_radius_vox))
    throw UsageError("segment: the thin-piece radius must be >= 0 voxels (0: from the grain radius)");
  if (o.thin_piece_radius_vox == 0) o.thin_piece_radius_vox = std::max(3.0, 0.15 * o.grain_radius_vox);
  if (!(o.bright_fraction >= 0 && o.bright_fraction <= 1))
    throw UsageError("segment: the bright fraction must be in [0, 1]");
  if (!(o.bright_sigmas >= 0) || !std::isfinite(o.bright_sigmas))
    throw UsageError("segment: bright sigmas must be >= 0");
  if (o.pore_shell_vox < 0 || o.pore_shell_vox > 16)
    throw UsageError("segment: the pore shell must be 0..16 voxels");
  return o;
}

// Each entry point gives back the blocks its stages freed (core/memory.hpp):
// the caller's next steps should not find them resident.
SegmentResult segment(const Volume<uint16_t>& grey, const SegmentOptions& opt) {
  SegmentResult r = run_from_grey(grey, nullptr, opt);
  release_idle_blocks();
  return r;
}

SegmentResult segment(Volume<uint16_t>&& grey, const SegmentOptions& opt) {
  SegmentResult r;
  {
    Volume<uint16_t> g = std::move(grey);
    r = run_from_grey(g, &g, opt);
  }
  release_idle_blocks();
  return r;
}

SegmentResult segment_mask(Volume<uint8_t> solid, const SegmentOptions& opt) {
  SegmentResult r = segment_graded(std::move(solid), opt, false);
  release_idle_blocks();
  return r;
}

namespace {

// The chain from a mask: 0/nonzero (graded = false), or graded 0 void,
// 1 dim, 2 bright (the header's grey evidence).
SegmentResult segment_graded(Volume<uint8_t> solid, const SegmentOptions& opt_in, bool graded, SlabRun* slab,
                             const Volume<uint8_t>* grey_code, double split_depth, double split_floor,
                             const SpeckTest* specks, double solid_level, const FaceSliverOptions* slivers,
                             const MergeGrey* merge_grey) {
  const SegmentOptions opt = opt_in.resolved();
  SegmentResult r;
  StageClock clock(r);
  const Shape s = solid.shape();
  const int64_t n = solid.size();
  uint8_t* sm = solid.data();
  auto count_solid = [&] {
    int64_t c = 0;
#pragma omp parallel for schedule(static) reduction(+ : c)
    for (int64_t i = 0; i < n; ++i) c += sm[i] != 0;
    return c;
  };
  int64_t nsolid = count_solid();
  r.solid_fraction = n ? double(nsolid) / double(n) : 0.0;
  r.h = opt.h;
  r.graded = graded;
  const uint8_t bright = graded ? 2 : 1;

  r.pore_criteria = {opt.pore_max_volume_vox, opt.pore_min_sphericity};
  // The scan's faces close the pores they cut; a slab's inner faces do not.
  r.pore_criteria.closed_faces = {!slab || slab->window.scan_bottom, !slab || slab->window.scan_top, true, true, true, true};
  // Graded: the void pores filled as 3 for a moment (their shells below).
  if (opt.fill_pores) r.pores = fill_pores(solid, r.pore_criteria, 1, graded ? 3 : bright);
  nsolid += r.pores.filled_voxels;
  if (graded && opt.fill_pores) {
    // The filled pores' own dim shells first (pore_filter.hpp
    // brighten_pore_shells): a shell reaching the grain's dim rim is no
    // enclosed pocket for the pass below.
    r.pore_shell_voxels = brighten_pore_shells(solid, 3, 1, 2, opt.pore_shell_vox);
    // Dim pockets enclosed by bright solid (26-connected: see
    // PoreFilterOptions): a filled pore's partial-volume shell, noise
    // specks. Any shape (an enclosed pocket cannot part two
    // pieces that the bright solid around it joins), twice the pore volume
    // (the pore with its shell).
    PoreFilterOptions pockets{2 * opt.pore_max_volume_vox, 0.0, 26};
    pockets.closed_faces = r.pore_criteria.closed_faces;
    r.dim_pockets = fill_pores(solid, pockets, 2, 2);
    if (r.dim_pockets.filled) nsolid = count_solid();  // an enclosed pocket may hold void voxels too
  }
  clock.lap("pores");

  Volume<uint32_t> lab;  // the markers, then the labels
  if (nsolid == 0 || nsolid == n) {
    // Nothing to separate: no solid, or no void at all (the distance map
    // would be infinite). One label for an all-solid volume.
    r.notes.push_back(nsolid == 0 ? "no solid voxel: no particles" : "no void voxel: the whole volume is one particle");
    lab = Volume<uint32_t>::filled(s, nsolid == 0 ? 0u : 1u, solid.geometry());
    r.markers = nsolid ? 1 : 0;
    auto rl = relabel_consecutive(lab, opt.min_size_vox);
    r.count = rl.count;
    r.dropped = rl.dropped;
    r.labels = std::move(lab);
    if (slab) slab->out->sizes = std::move(rl.sizes);
    clock.lap("watershed");
    r.peak_rss_bytes = peak_rss_bytes();
    return r;
  }

  // Memory: the mask goes once the distance map exists (the map is 0
  // exactly on the void), the map shrinks to 16 bits before the markers
  // come, and the flood levels go over its storage (6 B/voxel at peak).
  // (Growing the mask's storage into the markers' instead cost more than
  // fresh pages: realloc copied it, 0.22 s at 512^3.)
  // Distance map in units of the finest voxel edge.
  EdtOptions eo;
  const auto& vs = solid.geometry().voxel_size_m;
  if (solid.geometry().has_voxel_size()) {
    const double w = std::min({vs[0], vs[1], vs[2]});
    eo.spacing = {vs[0] / w, vs[1] / w, vs[2] / w};
  }
  eo.solid_from = bright;
  Volume<float> dist;
  distance_transform(solid, dist, eo);
  if (graded) {
    // Dim solid: the lowest solid height (below any bright voxel, >= 1), so
    // it is solid for the markers and the flood, and flooded last.
    constexpr float kDim = 1e-3f;
    float* d = dist.data();
    int64_t ndim = 0;
#pragma omp parallel for schedule(static) reduction(+ : ndim)
    for (int64_t i = 0; i < n; ++i) {
      const bool dim = sm[i] == 1;
      ndim += dim;
      d[i] = dim ? kDim : d[i];
    }
    r.dim_fraction = nsolid ? double(ndim) / double(nsolid) : 0.0;
  }
  clock.lap("edt");

  solid = Volume<uint8_t>();
  if (slab) {
    // The core's deepest voxel: exact there (the margin holds its nearest
    // void), so the caller learns the whole scan's deepest from the cores.
    const int64_t sl = s.slice_voxels();
    const float* d = dist.data();
    float dmax = 0;
#pragma omp parallel for schedule(static) reduction(max : dmax)
    for (int64_t i = slab->window.core_begin * sl; i < slab->window.core_end * sl; ++i) dmax = std::max(dmax, d[i]);
    slab->out->core_dmax = dmax;
  }
  // The markers and the levels only compare distances: a 16-bit fixed-point
  // map (1/256 voxel) over the float map's storage holds the peak at
  // 2 + 4 B/voxel while the markers are found. A slab takes the whole
  // scan's units and quantisation (its own deepest voxel, perhaps in the
  // margin, would change their rounding).
  FixedDistance fixed = to_fixed_point(std::move(dist), slab ? slab->window.fixed_units : 0.0);
  r.markers = find_markers(fixed, lab, {opt.h, opt.connectivity});
  clock.lap("markers");
  Volume<uint8_t> levels = slab ? quantise_levels_at(std::move(fixed), slab->window.buckets_per_unit)
                                : quantise_levels(std::move(fixed), opt.buckets_per_unit, r.buckets_per_unit);
  if (slab) r.buckets_per_unit = slab->window.buckets_per_unit;
  if (r.buckets_per_unit < opt.buckets_per_unit)
    r.notes.push_back("watershed levels coarsened to " + std::to_string(r.buckets_per_unit) +
                      " per voxel (255 levels at most; the largest distance is " +
                      std::to_string(254.0 / r.buckets_per_unit) + " voxels)");
  watershed_levels(levels, lab, {opt.watershed_lines, opt.connectivity, r.buckets_per_unit});
  clock.lap("watershed");

  // The merge's roots are applied by the renumbering below (one pass less).
  // levels > 0: the solid; level 1 is the dim solid when q >= 1 (bright
  // voxels, d >= 1, get 1 + floor(q d) >= 2).
  if (graded && r.buckets_per_unit < 1)
    r.notes.push_back("grey evidence not used by the merge: grains over 254 voxels deep leave no level for dim voxels");
  const uint8_t merge_bright = graded && r.buckets_per_unit >= 1 ? 2 : 1;
  MergeOptions mo;
  mo.ratio = opt.merge_ratio;
  mo.bright_level = merge_bright;
  mo.apply = false;
  if (grey_code && merge_grey && opt.grey_evidence) {
    mo.grey = grey_code;
    mo.grey_floor = merge_grey->floor, mo.grey_filled = merge_grey->filled;
    mo.grey_fraction = opt.bright_fraction;
    r.merge_own_levels = true;
  }
  if (opt.merge) r.merge = merge_oversegmented(lab, levels, mo);
  clock.lap("merge");
  levels = Volume<uint8_t>();
  // With the face slivers the size floor spares the labels at the scan's
  // faces until they have grown (a sliver's voxels above the threshold are
  // often fewer than the floor): then the last renumbering applies it.
  const bool slivers_on = grey_code && slivers;
  const bool floor_deferred = slivers_on && opt.min_size_vox > 1;
  const std::vector<uint32_t>* roots = r.merge.root.empty() ? nullptr : &r.merge.root;
  const std::vector<uint8_t> spared = floor_deferred ? labels_in_shell(lab, *slivers, roots) : std::vector<uint8_t>{};
  auto rl = relabel_consecutive(lab, opt.min_size_vox, roots, floor_deferred ? &spared : nullptr);
  r.merge.root = {};
  r.count = rl.count;
  r.dropped = rl.dropped;
  clock.lap("relabel");
  if (grey_code && specks) {
    // Noise specks (noise_specks.hpp) before the split repair, which then
    // need not look at them, and before the face slivers grow (the test
    // reads a sliver's voxels above the threshold only).
    r.specks = find_noise_specks(lab, r.count, *grey_code, *specks);
    if (r.specks.dropped > 0) {
      rl = relabel_consecutive(lab, floor_deferred ? 1 : opt.min_size_vox, &r.specks.keep);
      r.count = rl.count;
    }
    r.specks.keep = {};
    clock.lap("specks");
  }
  if (slivers_on) {
    // Face slivers (face_slivers.hpp): thin labels at the scan's faces take
    // their partial-volume voxels.
    r.face_slivers_used = true;
    grow_face_slivers(lab, r.count, *grey_code, *slivers, &r.face_slivers);
    clock.lap("face_slivers");
  }
  if (grey_code && split_depth > 0) {
    // Split repair (split_labels.hpp), then raster order again (a chunked
    // run numbers particles by their first voxel).
    r.split_used = true;
    SplitOptions so;
    so.smoothing_sigma_vox = opt.split_smoothing_vox;
    so.depth = split_depth;
    so.floor = split_floor;
    so.min_piece_fraction = opt.split_min_piece_fraction;
    uint32_t count = r.count;
    r.split = split_by_grey(lab, &count, *grey_code, so);
    clock.lap("split");
    if (opt.thin_pieces) {
      // Thin pieces (split_labels.hpp split_thin_pieces): chips pressed on
      // a grain, which neither the distance map nor the grey part.
      r.thin_pieces_used = true;
      ThinPieceOptions to;
      to.radius_vox = opt.thin_piece_radius_vox;
      to.min_piece_fraction = opt.split_min_piece_fraction;
      to.spacing = eo.spacing;
      r.thin_piece_radius_vox = to.radius_vox;
      r.thin_pieces = split_thin_pieces(lab, &count, to);
      clock.lap("thin_pieces");
      // Thin walls cut by the watershed into a chain (merge_labels.hpp
      // merge_thin_walls): bright means past halfway from the threshold
      // to the solid, as the dim band's first bound.
      WallMergeOptions wo;
      wo.floor = split_floor;
      wo.bright = split_floor + 0.5 * (solid_level - split_floor);
      wo.min_area = int64_t(std::lround(to.radius_vox * to.radius_vox));
      // Walls only where grains are deeper than r (segment.hpp).
      r.thin_walls_used = opt.merges_thin_walls();
      if (r.thin_walls_used)
        r.thin_walls = merge_thin_walls(lab, *grey_code, r.thin_pieces.thin, r.thin_pieces.thin_boxes, wo);
      r.thin_pieces.thin = {};
      r.thin_pieces.thin_boxes = {};
      clock.lap("thin_walls");
    }
    if (opt.face_caps) {
      // Face caps (split_labels.hpp split_face_caps): the scan's faces only
      // (a slab's cut faces are not).
      r.face_caps_used = true;
      FaceCapOptions fo;
      if (slab) fo.faces[0] = slab->window.scan_bottom, fo.faces[1] = slab->window.scan_top;
      fo.spacing = eo.spacing;
      fo.solid = solid_level;
      fo.floor = split_floor;
      r.face_caps = split_face_caps(lab, &count, *grey_code, fo);
      clock.lap("face_caps");
    }
  }
  // (Grown or joined slivers may start earlier in raster order, or leave a
  // number unused.)
  if (r.split.pieces_added + r.thin_pieces.pieces_added + r.thin_walls.merges + r.face_caps.pieces_added +
          r.face_slivers.slivers_joined + r.face_slivers.voxels_added > 0 ||
      floor_deferred) {
    rl = relabel_consecutive(lab, opt.min_size_vox);
    r.count = rl.count;
    r.dropped += rl.dropped;
    clock.lap("renumber");
  }
  r.labels = std::move(lab);
  if (slab) slab->out->sizes = std::move(rl.sizes);
  r.peak_rss_bytes = peak_rss_bytes();
  return r;
}

}  // namespace

std::string summary_json(const SegmentResult& r, const SegmentOptions& opt_in) {
  const SegmentOptions o = opt_in.resolved();
  using nlohmann::json;
  json j;
  j["shape_zyx"] = {r.labels.shape().nz, r.labels.shape().ny, r.labels.shape().nx};
  j["voxel_size_m_zyx"] = r.labels.geometry().voxel_size_m;
  j["grain_radius_vox"] = o.grain_radius_vox;
  j["threshold"] = {{"method", threshold_method_name(r.threshold.method)},
                    {"value", r.threshold.value},
                    {"rule", "voxels with grey value > value are solid"},
                    {"p0", r.threshold.p0},
                    {"separability", r.threshold.separability},
                    {"z0", r.threshold.z0},
                    {"z1", r.threshold.z1}};
  if (r.threshold.method == ThresholdMethod::automatic) {
    const AutoChoice& a = r.threshold.automatic;
    j["threshold"]["auto"] = {{"chosen", a.chosen},
                              {"why", a.why},
                              {"void_level", a.void_level},
                              {"solid_level", a.solid_level},
                              {"void_sigma", a.void_sigma},
                              {"solid_sigma", a.solid_sigma},
                              {"sigma", a.sigma},
                              {"midpoint", a.midpoint},
                              {"moments", a.moments},
                              {"void_voxels", a.void_voxels},
                              {"k_sigmas", a.k_sigmas},
                              {"floor", a.floor},
                              {"rule", "midpoint if floor = void_level + k sigma <= midpoint (sigma: the larger phase sigma; k: "
                                       "P(noise > k sigma) = 1 / void_voxels), else min(floor, moments), never below "
                                       "the midpoint"}};
  }
  if (r.threshold.method == ThresholdMethod::local)
    j["threshold"]["local"] = {{"window_vox", r.local.window},
                               {"blocks_zyx", {r.local.nbz, r.local.nby, r.local.nbx}},
                               {"blocks_bimodal", r.local.trusted},
                               {"blocks_from_neighbours", r.local.filled},
                               {"min", r.local.min},
                               {"max", r.local.max},
                               {"global_value_is", "the global moments threshold, the fallback"}};
  j["solid_fraction"] = r.solid_fraction;
  j["field_of_view"] = {{"source", r.fov.source},
                        {"active", r.fov.active},
                        {"centre_yx", {r.fov.centre_y, r.fov.centre_x}},
                        {"radius_vox", r.fov.radius},
                        {"outside_value", r.fov.outside_value},
                        {"fit_rms_vox", r.fov.fit_rms},
                        {"voxels_outside", r.fov.outside_voxels},
                        {"premasked_zero_voxels", r.levels.zeros_premasked ? r.levels.zero_count : int64_t(0)},
                        {"detection", o.fov.detect}};
  j["saturation"] = {{"level", r.levels.top_level},
                     {"fraction", r.levels.top_fraction()},
                     {"zero_fraction", r.levels.zero_fraction()},
                     {"zeros", r.levels.zeros_premasked ? "pre-masked" : r.levels.zeros_clipped ? "clipped" : "data"},
                     {"action", r.levels.action()}};
  j["pores"] = {{"enabled", o.fill_pores},
                {"criteria", r.pore_criteria.describe()},
                {"max_volume_vox", r.pore_criteria.max_volume_vox},
                {"min_sphericity", r.pore_criteria.min_sphericity},
                {"void_components", r.pores.void_components},
                {"enclosed", r.pores.enclosed},
                {"filled", r.pores.filled},
                {"filled_voxels", r.pores.filled_voxels},
                {"filled_at_faces", r.pores.filled_at_faces}};
  j["grey_evidence"] = {{"enabled", r.graded},
                        {"bright_fraction", o.bright_fraction},
                        {"bright_sigmas", o.bright_sigmas},
                        {"solid_noise_sigma", r.solid_noise_sigma},
                        {"bright_value", r.bright_value},
                        {"rule", "solid voxels with grey value <= bright_value are dim"},
                        {"dim_fraction_of_solid", r.dim_fraction},
                        {"dim_pockets_filled", r.dim_pockets.filled},
                        {"pore_shell_vox", o.pore_shell_vox},
                        {"pore_shell_voxels_brightened", r.pore_shell_voxels},
                        {"dim_pocket_voxels_filled", r.dim_pockets.filled_voxels}};
  j["markers"] = {{"h", r.h}, {"connectivity", o.connectivity}, {"count", r.markers}};
  j["watershed"] = {{"lines", o.watershed_lines},
                    {"buckets_per_unit", o.buckets_per_unit},
                    {"buckets_per_unit_used", r.buckets_per_unit}};
  j["merge"] = {{"enabled", o.merge},
                {"ratio", o.merge_ratio},
                {"touching_pairs", r.merge.touching_pairs},
                {"passing_pairs", r.merge.candidates},
                {"merges", r.merge.merges},
                {"bright_value", r.bright_value},
                {"bright_rule", r.merge_own_levels
                                    ? "the interface's bright share counts the voxels whose grey lies past "
                                      "--bright-fraction of the way from the threshold to the pair's own level (the "
                                      "mean grey of the two labels' voxels above the threshold), or that the pore "
                                      "filling made bright; its area counts every voxel the grey evidence grades "
                                      "bright (above bright_value)"
                                    : "an interface voxel counts bright where the grey evidence grades it bright "
                                      "(every solid voxel without grey evidence)"}};
  j["split"] = {{"enabled", r.split_used},
                {"smoothing_sigma_vox", r.split_smoothing_vox},
                {"smoothing_rule", o.split_smoothing_vox > 0
                                       ? std::string("given")
                                       : fmt::format("the least of {} voxel whose depth_sigmas x smoothed noise sigma "
                                                     "is <= {} x (solid peak - threshold), else the last",
                                                     fmt::join(kSplitSmoothingLadder, ", "), kSplitDepthShare)},
                {"smoothed_noise_sigma", r.smoothed_noise_sigma},
                {"smoothed_solid_sigma", r.smoothed_solid_sigma},
                {"within_grain_sigma", r.within_grain_sigma},
                {"within_grain_pairs", r.within_grain_pairs},
                {"noise_from", r.split_noise_within_grains
                                   ? std::string("within grains: narrower than the solid's peak (grains of "
                                                 "different brightness or texture widen the peak)")
                                   : std::string("solid peak")},
                {"depth_sigmas", o.split_depth_sigmas},
                {"depth_sigmas_correlated", o.split_depth_sigmas_correlated},
                {"depth_sigmas_used", r.split_depth_sigmas_used},
                {"noise_correlation", r.split_noise_correlation},
                {"min_depth_contrast", o.split_min_depth_contrast},
                {"depth", r.split_depth},
                {"grey_code", {{"lo", r.split_code.lo}, {"step", r.split_code.step},
                               {"rule", "the repair reads grey lo + c step, c = round((grey - lo) / step) in 0..255"}}},
                {"min_piece_fraction", o.split_min_piece_fraction},
                {"rule", "a label is split where its smoothed grey holds pieces of >= max(min_piece_fraction x its "
                         "voxels, 27) voxels whose peaks stand >= depth grey levels above the sheet between them"},
                {"labels_tested", r.split.tested},
                {"labels_split", r.split.split},
                {"pieces_added", r.split.pieces_added},
                {"labels_too_large_to_test", r.split.skipped_large}};
  j["thin_pieces"] = {{"enabled", r.thin_pieces_used},
                      {"radius_vox", r.thin_piece_radius_vox},
                      {"rule", [] {
                         const ThinPieceOptions d;  // the values segment() runs with (radius aside)
                         return fmt::format(
                             "a label's voxels left by its opening with a ball of radius_vox (those within radius_vox "
                             "of a voxel deeper than radius_vox) form a thin piece, given a label of its own, where a "
                             "6-connected component holds >= max({}, min_piece_fraction x the label) voxels, <= {} of "
                             "the label, touches no scan face unless it holds >= (3 radius_vox)^3 voxels, and < {} "
                             "of its voxels touch the opening "
                             "(split_labels.hpp split_thin_pieces)",
                             d.min_piece_vox, d.max_share, d.max_contact);
                       }()},
                      {"labels_tested", r.thin_pieces.tested},
                      {"labels_tested_in_full", r.thin_pieces.screened_in},
                      {"labels_split", r.thin_pieces.split},
                      {"pieces_added", r.thin_pieces.pieces_added},
                      {"walls", {{"enabled", r.thin_walls_used},
                                 {"rule", [] {
                                    const WallMergeOptions d;
                                    return fmt::format(
                                        "two labels thin throughout (no voxel deeper than radius_vox: the pieces above, "
                                        "and labels so thin) merge where they meet across >= radius_vox^2 voxels of "
                                        "interface at least halfway from the threshold to the solid's grey, >= {} of "
                                        "it (a wall the watershed cut; merge_labels.hpp merge_thin_walls); runs where the grain radius "
                                        "is >= 2 (radius_vox + 1) voxels (smaller grains are thin throughout themselves)",
                                        d.min_bright_share);
                                  }()},
                                 {"thin_labels", r.thin_walls.thin_labels},
                                 {"pairs_touching", r.thin_walls.touching_pairs},
                                 {"merges", r.thin_walls.merges}}}};
  j["face_caps"] = {{"enabled", r.face_caps_used},
                    {"rule", [] {
                       const FaceCapOptions d;  // the values segment() runs with
                       return fmt::format(
                           "a label touching a scan face whose footprint there holds two or more distance maxima "
                           "(dynamic >= {} voxel, >= {} voxels deep) is parted among them, the parts' cores seeding a "
                           "watershed of the label's own distance map; a piece of >= {} voxels leaves it when the raw "
                           "grey on the sheet between it and the largest piece lies >= {} of (solid peak - threshold) "
                           "below the solid peak; a footprint with one maximum whose label, behind a layer that thins "
                           "out or darkens by as much, is bright solid again (a cap pressed on a grain behind it) is "
                           "cut so too, the sheet >= {} below (split_labels.hpp split_face_caps)",
                           d.h, d.min_peak, d.min_piece_vox, d.min_dip, d.min_dip_in_front);
                     }()},
                    {"candidates", r.face_caps.candidates},
                    {"labels_split", r.face_caps.split},
                    {"pieces_added", r.face_caps.pieces_added}};
  j["face_slivers"] = {{"enabled", r.face_slivers_used},
                       {"rule", [] {
                          const FaceSliverOptions d;  // the values segment() runs with
                          return fmt::format(
                              "a label lying wholly within {} voxels of a scan face (crumbs of one under {} x the size "
                              "floor joined across a line first; a crumb under the floor beside a deeper label left to "
                              "the floor) grows {} times into the unlabelled voxels there above "
                              "void + {} (its brightest voxel - void), where that is below the threshold, whose "
                              "labelled neighbours are its alone; the size floor applies after (face_slivers.hpp)",
                              d.depth, d.crumbs, d.rounds, d.half);
                        }()},
                       {"void_level", r.void_level},
                       {"slivers_joined", r.face_slivers.slivers_joined},
                       {"labels_grown", r.face_slivers.labels_grown},
                       {"voxels_added", r.face_slivers.voxels_added}};
  {
    const GrainLevelsOptions glo;
    const GrainLevelsResult& g = r.grain_levels;
    j["grain_levels"] = {
        {"enabled", o.grain_levels},
        {"used", g.used},
        {"spread_ratio", g.spread_ratio},
        {"min_spread_ratio", glo.min_spread_ratio},
        {"dim_population", {{"found", g.dim.found}, {"level", g.dim.level}, {"prominence", g.dim.prominence},
                            {"min_prominence", kDimPopulationProminence}}},
        {"void_level", g.levels.void_level},
        {"solid_level", g.levels.solid_level},
        {"smoothed_noise_sigma", g.levels.smoothed_sigma},
        {"voxels_raised", g.voxels_raised},
        {"voxels_from_smoothed", g.voxels_from_smoothed},
        {"rule", fmt::format("where the smoothed solid peak is >= {:g} times as wide as the grey varies inside a grain "
                             "(grains of different brightness), or the smoothed grey's histogram holds a peak between "
                             "the void and the solid at least {:g} times its floors on either side (a population of "
                             "darker grains), each voxel's grey is raised by gain = (solid - void) "
                             "/ (M - void), M the largest grey smoothed over {:g} voxel within {} voxels, gain <= {:.3g}, "
                             "read from the smoothed grey as the gain nears {:.3g}; left alone where M is the solid's "
                             "level or within {:g} smoothed noise sigmas of the void; the threshold and every grey "
                             "decision are then taken on the levelled scan (grain_levels.hpp)",
                             glo.min_spread_ratio, kDimPopulationProminence, glo.smoothing_sigma_vox, glo.reach_vox,
                             glo.max_gain,
                             glo.smooth_from_gain, glo.min_excess_sigmas)}};
  }
  j["noise_specks"] = {{"enabled", r.specks.used},
                       {"rule", "a label is void noise, and cleared, when z = (m - mu0) / (s0 / sqrt(n)) < z_crit "
                                "(m its mean grey's excess over the threshold in noise sigmas, n its voxels, mu0 and s0 "
                                "the excess of void noise above the threshold: a truncated normal) and the grey "
                                "smoothed over 1 voxel reaches the threshold at none of its voxels (no core)"},
                       {"void_level", r.speck_test.void_level},
                       {"noise_sigma", r.speck_test.sigma},
                       {"z_crit", o.speck_z},
                       {"mu0", r.specks.mu0},
                       {"s0", r.specks.s0},
                       {"labels_tested", r.specks.tested},
                       {"labels_dropped", r.specks.dropped},
                       {"voxels_dropped", r.specks.dropped_voxels}};
  j["labels"] = {{"count", r.count}, {"min_size_vox", o.min_size_vox}, {"dropped", r.dropped}};
  json st = json::object();
  double total = 0;
  for (const auto& [name, sec] : r.stage_seconds) {
    st[name] = sec;
    total += sec;
  }
  j["seconds"] = st;
  j["seconds_total"] = total;
  j["peak_rss_bytes"] = r.peak_rss_bytes;
  j["shape"] = {r.labels.shape().nz, r.labels.shape().ny, r.labels.shape().nx};  // (z, y, x) voxels
  const int64_t nvox = r.labels.size();
  j["peak_rss_bytes_per_voxel"] = nvox ? double(r.peak_rss_bytes) / double(nvox) : 0.0;
  j["notes"] = r.notes;
  return j.dump(2);
}

}  // namespace tg
