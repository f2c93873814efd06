// Global grey-level thresholds on the full 16-bit histogram: Tsai's
// moment-preserving threshold (the reference study's choice), Otsu, manual.
//
// Convention (as Fiji's Auto_Threshold): the threshold t is a grey level and
// voxels with value > t are solid, voxels <= t are void.
//
// Moments (Tsai 1985, "Moment-preserving thresholding: a new approach",
// Computer Vision, Graphics, and Image Processing 29:377-393,
// doi:10.1016/0734-189X(85)90133-1). The image is replaced by a two-level
// image (levels z0 < z1, a fraction p0 at z0) that has the same first three
// moments m1, m2, m3 as the normalised histogram (m0 = 1):
//   cd = m0 m2 - m1^2,  c0 = (m1 m3 - m2^2) / cd,  c1 = (m1 m2 - m0 m3) / cd,
//   z0,1 = (-c1 -/+ sqrt(c1^2 - 4 c0)) / 2,        p0 = (z1 - m1) / (z1 - z0),
// and t is the first grey level whose cumulative normalised histogram exceeds
// p0. As in Fiji, the moments are taken on the histogram trimmed to its first
// and last non-empty bins (grey levels counted from the first non-empty bin;
// the result is shifted back), which also keeps i^3 ~ 2.8e14 from eating the
// double precision of m3.
//
// Otsu (1979, doi:10.1109/TSMC.1979.4310076): t maximises the between-class
// variance w0 w1 (mu0 - mu1)^2 over the same trimmed histogram; ties go to
// the lowest t.
//
// Degenerate histograms: an empty or constant volume throws InputError (there
// is nothing to separate); a volume with exactly two grey levels a < b gets
// t = a with a note in ThresholdResult::note (both methods would otherwise
// divide 0 by 0 or hinge on the last bit of a rounding).
//
// Cost: the histogram is one OpenMP pass over the volume (per-thread integer
// histograms of 65536 bins, summed in thread order); each method is O(65536).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/volume.hpp"

namespace tg {

// local: Tsai per block, interpolated (local_threshold.hpp); ThresholdResult
// then holds the global moments threshold, for the summary and as fallback.
// midpoint: halfway between the void and solid levels (phase_levels), the
// level where a blurred surface between the two phases sits for a symmetric
// PSF ("ISO-50" in dimensional CT); Tsai's moments sit above it on blurred
// scans (20 632 against 20 031 on the blind sweep's middle setting).
// automatic ("auto", an option): the midpoint where the void's noise
// allows it, Tsai's level where it does not (auto_threshold below).
enum class ThresholdMethod { moments, otsu, manual, local, midpoint, automatic };
const char* threshold_method_name(ThresholdMethod m);
// "moments" | "otsu" | "manual" | "local" | "midpoint" | "auto"; throws UsageError naming the valid set.
ThresholdMethod parse_threshold_method(const std::string& s);

// What the automatic rule measured and chose (auto_threshold).
struct AutoChoice {
  double void_level = 0, solid_level = 0;  // phase_levels' modes
  double void_sigma = 0, solid_sigma = 0;  // their noise sigmas (one-sided, phase_levels)
  double sigma = 0;                        // the larger of the two: the rule's noise
  double midpoint = 0;                     // (void_level + solid_level) / 2
  uint16_t moments = 0;                    // Tsai's level
  int64_t void_voxels = 0;                 // voxels at or below Tsai's level (bin 0 out)
  double k_sigmas = 0;                     // k: P(N(0,1) > k) = 1 / void_voxels
  double floor = 0;                        // void_level + k sigma
  std::string chosen;                      // "midpoint" | "moments" | "floor"
  std::string why;                         // one sentence for the summary
};

struct ThresholdResult {
  uint16_t value = 0;  // voxels > value are solid
  ThresholdMethod method = ThresholdMethod::moments;
  double p0 = 0;       // moments only: fraction of void voxels of the two-level image
  double z0 = 0, z1 = 0;  // moments only: the two preserved grey levels
  std::string note;    // non-empty for special cases (two grey levels only)
  // Otsu's separability eta at `value`: between-class / total grey variance.
  // 2/pi = 0.64 for a single Gaussian phase (noise only: an empty or
  // all-solid scan), 0.9+ for grains and void; segment() notes eta < 0.75.
  double separability = 0;
  AutoChoice automatic;  // ThresholdMethod::automatic only
};

// 65536-bin histogram of a 16-bit volume; with row spans (x0, x1 of one
// entry per y, as field_of_view.hpp's inside), only voxels x in
// [x0[y], x1[y]) of each row.
std::vector<int64_t> histogram_u16(const Volume<uint16_t>& v, const std::vector<int64_t>* x0 = nullptr,
                                   const std::vector<int64_t>* x1 = nullptr);

// Tsai moment-preserving threshold of a histogram (any size, typically 65536).
ThresholdResult moments_threshold(const std::vector<int64_t>& hist);
// Otsu threshold of the same histogram.
ThresholdResult otsu_threshold(const std::vector<int64_t>& hist);

// Separability eta of the split "<= t" / "> t" of a histogram (0 if degenerate).
double separability(const std::vector<int64_t>& hist, uint16_t t);

// Solid mask (1 where v > t, else 0), geometry kept.
Volume<uint8_t> binarise(const Volume<uint16_t>& v, uint16_t t);
// The same written over the scan's own storage (taken): no second volume.
Volume<uint8_t> binarise(Volume<uint16_t>&& v, uint16_t t);

// Graded mask, the grey evidence the later stages use where the geometry is
// ambiguous (segment.hpp, "Grey evidence"): 0 void (v <= t), 1 dim solid
// (t < v <= t_bright), 2 bright solid (v > t_bright). Same storage rules.
Volume<uint8_t> binarise_graded(const Volume<uint16_t>& v, uint16_t t, uint16_t t_bright);
Volume<uint8_t> binarise_graded(Volume<uint16_t>&& v, uint16_t t, uint16_t t_bright);

// Mean grey level of the voxels above t (the solid phase, partial-volume
// voxels included); t itself when none is above.
double mean_above(const std::vector<int64_t>& hist, uint16_t t);

// The solid phase's peak above t: its mode (the histogram above t in 256
// bins up to its 99.9th percentile, smoothed over 5 bins, the fullest bin's
// mean grey) and its noise sigma from the upper side of the peak only
// (partial-volume voxels lie below the mode, the noise on both sides):
// sigma = median(g - mode | g >= mode) / 0.6745, the half-normal's median.
// {t, 0} when nothing is above t.
struct SolidPeak {
  double mode = 0, sigma = 0;
};
SolidPeak solid_peak(const std::vector<int64_t>& hist, uint16_t t);

// The grey levels of pure void and pure solid (the inputs of a
// partial-volume estimate, measure/grey_volume.hpp): the histogram without
// its 0 bin (pre-masked voxels), split at its Tsai threshold, and each
// side's peak mode as solid_peak finds it (the void side from its 0.1th
// percentile up). The modes, not the means: partial-volume voxels pull a
// phase's mean towards the other phase, not its mode.
// Each peak's noise sigma comes from its outer side (the void's lower, the
// solid's upper: the sides without partial volume), as the median of the
// one-sided deviations / 0.6745 (0 when the side is empty). clipped_zeros:
// void voxels a noisy scan clipped at 0 and the histogram left out (they
// count on the void's lower side, beyond every other).
struct PhaseLevels {
  uint16_t threshold = 0;
  double void_level = 0, solid = 0;
  double void_sigma = 0, solid_sigma = 0;
};
PhaseLevels phase_levels(std::vector<int64_t> hist, int64_t clipped_zeros = 0);

// The automatic threshold: the midpoint of the phases where the void's noise
// allows it, else Tsai's level.
//
// Why the midpoint: for a symmetric PSF a blurred surface crosses half the
// contrast at its true position (ISO-50), so the midpoint neither shrinks
// nor grows the grains; Tsai's level lies above it on blurred scans (the
// partial-volume voxels skew the moments) and moves every surface inwards.
// Why not always: the lower the threshold, the more void voxels that noise
// lifts above it; next to a grain they grow it, in a gap a voxel wide they
// bridge two fragments. On the blind sweep (dev seeds 1-3) the midpoint
// gains at CNR 13 and 30 (F1 0.982 against 0.977) and loses halves at
// CNR 5 and 8 (40 / 51 % against 51 / 61 %).
//
// The rule: the threshold stays at least k noise sigmas above the void
// peak, with k such that a void voxel of pure Gaussian noise exceeds it with
// probability 1 / N, N the number of void voxels (those at or below Tsai's
// level): at most about one voxel of the whole void is lifted into the solid
// by noise alone, so noise makes no bridge anywhere in the scan (a
// false-alarm rate of one per scan, as in detection theory; k = 5.0 for
// N = 3e6, 5.6 for 5e7, 6.1 for 1e9: it grows slowly with the scan).
// sigma is the larger of the two phases' one-sided sigmas: the voxels of a
// gap hold both phases (partial volume), so their grey spreads with the
// noisier one, and a phase whose level varies across the scan (cupping
// darkens the solid towards the centre) shows a wider peak than its noise
// alone: the larger sigma is the safe one. (With the void's sigma alone the
// rule took the midpoint under cupping 0.3 and lost its halves: 73 %
// against Tsai's 83 %, dev seeds.)
//   floor = void_level + k sigma
//   t = midpoint                      if floor <= midpoint       ("midpoint")
//     = min(floor, Tsai)              else, never below midpoint ("floor" / "moments")
// so the rule takes the midpoint on quiet scans, Tsai's level on noisy ones
// (the floor above Tsai: Tsai's own level is what the method fell back on
// before, and a threshold higher still would cut the solid's own noise
// tail), and the floor between them. No constant of the rule comes from
// the sweep: k follows from N, the levels and sigma from the histogram
// (phase_levels). Blind sweep: midpoint = void + 6.4 sigma at CNR 13,
// 3.9 sigma at CNR 8, 2.5 at CNR 5, with k = 5.0 at 192^3.
// Two grey levels or no void: the midpoint (sigma 0, nothing to lift).
// Measured (bench/segmentation/RESULTS.md, rule fixed on dev seeds 1-3):
// the best of midpoint and Tsai at every sweep point within noise (middle
// F1 0.982, CNR 5-8 as Tsai, cupping 0.3 as Tsai), label |dV/V| 1.4 %
// against 2.2 %; but on the held-out seeds 201-202 (160^3, R 16) F1 0.969
// and one pore-induced over-segmentation against Tsai's 0.974 and none, so
// it is an option (--threshold auto), not the default.
ThresholdResult auto_threshold(const std::vector<int64_t>& hist);

// k with P(N(0,1) > k) = p (0 < p < 1; p >= 0.5 gives 0): the one-sided
// Gaussian tail's inverse, by bisection on erfc.
double gaussian_tail_sigmas(double p);

}  // namespace tg
