// Stage-to-stage tracking of grains and fragments through the label volumes
// of an oedometer test (issue #20; the reference study's section 2.2 "used
// several image processing algorithms to identify and track intact particles
// and fragments ... and about the types of breakage events").
//
// Method, for each pair of consecutive stages A -> B:
//  1. Per-label statistics of both stages (measure/label_stats.hpp): voxel
//     count, centroid, bounding box, border contact.
//  2. The global map y = M x + t between the stages (track/registration.hpp:
//     RANSAC affine on candidate centroid matches, least-squares polish;
//     identity plus axial compression when too few grains).
//  3. Overlap of the moved labels: every voxel of A is moved by the map
//     (plus the particle's own residual shift, step 4) and the label of B it
//     lands in is counted: ov(a, b) = voxels of a landing in b. A B particle's
//     parent is the A particle that covers most of it, provided it covers at
//     least `min_overlap_fraction` of b's voxels (else b is `new`); its match
//     quality is that covered fraction. Of b's voxels, those that the
//     global map sends back outside the volume are not counted: where the
//     specimen moves through the faces (a scan of a window of a taller
//     specimen, the moving platen outside it) a grain cut by a face at A
//     has entered further by B, and its child is several times what A saw.
//     (Measured on bench/track/blind_series.py, moving platen below the
//     window: counting them, 3 % of the particles came out `new`.) A B
//     particle none of whose voxels the map sends inside A was not in its
//     field: it is `new`, whatever a neighbour's refined shift (step 4)
//     brushes; and a particle clear of B's faces may have been cut by A's (a
//     sliver at A's face that moved in whole): every particle whose box the
//     map does not send wholly inside A is counted. A B particle that mostly
//     entered the field since A takes as parent a particle cut by A's faces
//     at least half of whose moved voxels land in it, whatever share of it
//     that covers (a grain pushed further in than the map, by its own
//     jitter: A's sliver of it is then smaller than what the map says A saw).
//  4. Refinement: each A particle's residual shift is the volume-weighted
//     centroid of its children minus its mapped centroid (grain jitter,
//     rotation of the packing, fragments drifting apart); step 3 is run once
//     more with it, and each B particle keeps the better covered of the two
//     passes (a thin chip on the side its body's centroid moved away from
//     stays with the first). One more pass over A's voxels buys the particles
//     that moved more than a few voxels off the global map. A B particle
//     still uncovered whose centroid lies within nearest_slack_vox of an A
//     particle's moved equivalent sphere (A at least a quarter of its volume)
//     takes that parent, with quality 0 (small pieces drifted off), unless
//     most of it entered the field since A. Such a particle (mostly entered
//     since A, no parent yet) and a particle cut by A's faces with no child,
//     not larger, whose moved centroid lies within its equivalent sphere +
//     nearest_slack_vox are one grain (quality 0): a sliver seen at A that the
//     grain's jitter moved off its voxels.
//  5. Events, from each A particle's children (ordered by volume, largest
//     first; f1 = largest child / all children):
//       no child           lost (left the field, merged, or fell below the
//                          detection limit: step 8 says which)
//       one child          intact, unless the particle lost more than the
//                          volume tolerance tol = max(min_volume_tolerance,
//                          3 d / r_eq) (d = surface_tolerance_vox, the
//                          segmentation's surface uncertainty: one voxel of
//                          radius changes a sphere's volume by 3 d / r) and
//                          neither stage cuts it at the border: then split
//                          when it kept at most hidden_split_fraction of its
//                          volume (a half whose twin is unseen: merged into a
//                          neighbour's label by the segmentation, or below
//                          its size limit), else chipping with the chips unseen
//                          ... and when it kept its volume within tol (either
//                          way: one that grew by more merged with something), a
//                          chip may have been absorbed by a NEIGHBOUR's
//                          label (a chip drifts outwards, lands face to face
//                          on the next grain, and no image method separates
//                          the two): chipping, with the chip counted as
//                          absorbed, when
//                            - a is still a whole stage-0 grain (no break in
//                              its chain: fragments' flat faces are re-cut
//                              against their neighbours by the segmentation
//                              from stage to stage, measured below),
//                            - T, the most voxels of a (moved, either pass of
//                              step 3/4) that land in one B label b whose
//                              parent n is another A particle, exceeds what a
//                              boundary shift by d between a and n moves: d
//                              times the faces S_an the two labels share at
//                              stage A (an existing contact), plus d times
//                              the patch a new contact opens (a sphere pressed
//                              by d: a cap of area 2 pi r_eq d), so
//                              T > d S_an + 2 pi r_eq d^2 (the second term is
//                              0.28 % of a grain of r_eq 23 voxels, 1.1 % at
//                              r_eq 11.6, for d = 1 voxel), where d =
//                              hypot(surface_tolerance_vox, e r_eq): under a
//                              strain increment e (1 - the map's axial scale)
//                              the neighbours of a grain along the axis come
//                              e 2 r_eq closer and press its contacts e r_eq
//                              deeper, a shift that grows with the grain in
//                              voxels. Measured (bench/track, data_synth
//                              series, segmented): whole grains that stayed
//                              intact have T / (2 pi r_eq) up to 1.7 at r_eq
//                              12 and 23 voxels and 9.1 at r_eq 55 (1220^3,
//                              e ~0.045 a stage); with d = 1 alone the 1220^3
//                              series had chipping precision 0.35 and 82 %
//                              intact broken against 70.9 %,
//                            - and the piece is seen to leave a or to arrive
//                              in n: a's loss (volume minus its child's) or
//                              n's gain (its children's volume minus its own)
//                              is at least absorbed_confirm_fraction T (a
//                              boundary that merely moved into a grain which
//                              itself swelled by a merger confirms neither).
//                          Measured (bench/track/RESULTS.md, 512^3 seed 11,
//                          whole grains with one child, segmented): truly
//                          intact ones have T <= 0.52 % of their volume
//                          (99.5 % <= 0.17 %), those whose chip a neighbour
//                          absorbed 0.41-6.8 % with S_an = 0 (the chip
//                          drifted onto a grain it did not touch); on the
//                          truth labels, intact grains pressed into a
//                          neighbour move up to 0.8 % (400 voxels) across an
//                          existing contact (S_an 56-377 faces), hence the
//                          d S_an term. One-child fragments that are truly
//                          intact reach T = 8 %, hence the first condition
//                          (a fragment's chip absorbed by a neighbour is not
//                          detected).
//                          ... and when neither rule calls it, a whole grain
//                          clear of the faces whose one child lost more than
//                          the stage's whole grains do is chipping, its chips
//                          unseen: its relative loss 1 - V(child) / V(a)
//                          exceeds median + loss_outlier_sigmas (4) x 1.4826
//                          MAD of that loss over the stage's whole one-child
//                          grains clear of the faces (at least 30 of them,
//                          else the rule is off), and loss_floor_fraction
//                          (1.5 %); a grain smaller than the sample's median
//                          r_eq (r_ref) has its loss weighed by (r_eq /
//                          r_ref)^loss_size_power (2), in the sample and the
//                          test: its label count varies more from stage to
//                          stage (segmented wide grading, another generator's
//                          R 12 series, 1.4826 MAD of the loss at stage 4:
//                          9.3 % under r_eq 4, 3.9 % at 4-6, 2.2 % at 8-11,
//                          0.95 % at 11-14, 0.69 % above), which one limit for
//                          all sizes read as chips of the small grains
//                          (bench/track/RESULTS.md "Wide gradings").
//                          A chip under the threshold, glued to its
//                          body or inside a neighbour's label by less than
//                          the threshold above leaves no piece to see, but
//                          its grain's label shrinks by it; the limit is the
//                          segmentation's own stage-to-stage spread, measured
//                          on the data, so it follows the scan's noise and
//                          grain size. Measured (bench/track/RESULTS.md,
//                          segmented, whole grains): data_synth 256^3 seed 11
//                          intact ones median 0.2 %, 1.4826 MAD 0.42-1.34 %
//                          (stage 1 -> 4): limits 1.9-5.6 %, its chipped ones
//                          lost 2.0-10 %; another generator's R 12 series
//                          limits 1.9-7.0 %; data_synth 512^3 the 1.5 %
//                          floor to 2.2 %. On exact truth labels intact grains
//                          move by up to 1.1 % (the voxels of a moving grain),
//                          hence the floor. k = 4 has the best pooled F1 of
//                          3-6 on the series measured, and was checked on five
//                          new ones: chipping recall on data_synth 256^3's
//                          middle setting 0.70 -> 0.90, precision 0.89 ->
//                          0.92 (new seeds 0.93 / 0.85, 0.91 / 0.90); on the
//                          R 12 series 0.72 -> 0.90 and 0.76 -> 0.78.
//       two or more        chipping when f1 >= chip_body_fraction (the body
//                          row says `chipping`, each small piece `chip`),
//                          else split (2 children) or fragmentation (>= 3)
//                          ... unless the small pieces are a piece the
//                          segmentation had glued to a at an earlier stage
//                          (a fragment of another grain pressed on it) coming
//                          apart again: when a's steps since its last break
//                          (or stage 0) were 1:1 intact continuations which
//                          GREW it by G (V0 its volume where that chain
//                          began, G > e V0, e = glued_volume_tolerance),
//                          its pieces now total P <= G + e V0 and its body
//                          keeps V0 (body >= V0 - e V0), a is intact and the
//                          pieces are `new` (their own ancestry went with
//                          the glue). A grain that really chips after such a
//                          gain loses from its body too (body < V0 - e V0)
//                          and stays chipping. Only where a was
//                          clear of the faces at every step of that chain (a grain
//                          entering the field of view grows by what comes
//                          in). Measured (bench/track/RESULTS.md,
//                          blind_series R 12 bottom seeds 2, 3, segmented,
//                          parents clear of the faces): it takes out 7 of
//                          the 36 false chipping events (P / G 0.4-0.97,
//                          body - V0 -0.2 % to +5 %), a true one after a
//                          gain had lost 8.5 % from its body; an intact
//                          label's volume changes by a median 0.8 % from
//                          stage to stage, hence e = 3 %. The same glue
//                          coming apart beside a's own break (f1 below
//                          chip_body_fraction): when exactly one child's
//                          volume is within e V0 of G, that child keeps no
//                          parent and the others are judged without it (two
//                          halves: split, not fragmentation; a body that
//                          kept V0 within e beside it: intact); two children
//                          within e V0 of G leave the verdict as it was (the
//                          glue is no surer than a fragment of a). Measured
//                          (bench/track/RESULTS.md, data_synth 256^3 blind
//                          range, segmented): 6 of the 14 false
//                          fragmentations at PSF 1 (seed 11) were two halves
//                          and a neighbour's fragment glued at the stage
//                          before (its volume within 0.2-2.6 % of V0 of
//                          G); fragmentation precision >= 0.95 at 18 of
//                          21 points (13 before), recall unchanged but one
//                          point (1.000 -> 0.993).
//                          ... and of three or more children of a break (a
//                          parent clear of the faces), one that a's moved
//                          voxels cover less than weak_piece_coverage (half)
//                          of is no piece of it: it keeps no parent, and the
//                          rest are judged alone (two left: split), unless
//                          fewer than two would be left. A neighbour's crumb
//                          beside two halves: measured (bench/track/RESULTS.md
//                          "A neighbour's crumb beside two halves",
//                          segmented, eleven series), 14 of the 18 false
//                          fragmentations were two halves and a piece of
//                          0.2-1.6 % of the parent, 10 of them covered
//                          0.00-0.46; the least covered piece of the 778 true
//                          fragmentations 0.57.
//                          ... and a piece of the break that a NEIGHBOUR's
//                          label absorbed (a fragment pressed on the next
//                          grain, which the segmentation joined to it)
//                          counts as one more child: T, the most of a's
//                          moved voxels landing in one B label whose parent
//                          n is another A particle, is at least
//                          absorbed_piece_fraction (15 %) of a, and a's loss
//                          and n's gain are both at least T / 2; the event
//                          is then decided on the children plus a piece of T
//                          (two seen + one absorbed: fragmentation). 15 %:
//                          above the 8 % a fragment's boundary moves between
//                          stages when pressed on a neighbour (above); a
//                          data_synth fragment of four is 17-29 %. Measured
//                          (bench/track/RESULTS.md, segmented): the 8
//                          fragmentation events data_synth 256^3 seed 11
//                          read as splits had every fragment segmented, one
//                          or two of them inside a neighbour's label.
//                          ... and a piece that its moved parent covers less
//                          than weak_piece_coverage (half) of (of the voxels
//                          stage A could see) is no evidence of a chip by
//                          itself: when every piece of a chipping of a parent
//                          clear of the faces is such, and the body lost no more than
//                          weak_piece_loss_share (0.6) of the stage's limit of
//                          the volume-loss rule (one child, below), a is
//                          intact and the pieces `new` (a fragment of another
//                          grain that the stage before had missed or glued,
//                          coming into view beside a). A body losing more
//                          than that share, with a piece beside it, is two
//                          weak signs of one chip: chipping. (Share 1, the
//                          rule before: data_synth 256^3 seed 12 chipping
//                          recall 0.884; 0.6: 0.913; over 31 firings on ten
//                          series the false ones' bodies lost at most 0.56 of
//                          the limit, the true ones' 0.20, 0.52, 0.70, 0.74.)
//                          Measured (bench/track/RESULTS.md, segmented): of
//                          the chippings whose every piece is covered less
//                          than half, 33 false and 15 true over data_synth
//                          256^3 / 512^3 and the other generator's series;
//                          the false ones' bodies lost -1 to +2.5 % (four
//                          3.3-21 %), the true ones' 1.1-8.5 %. Chipping
//                          precision +0.02 to +0.04 on every group of series,
//                          recall 0 to -0.014.
//                          ... and each child is weighed by what came from a:
//                          a child whose label also holds at least
//                          absorbed_piece_fraction of its voxels from other
//                          A particles' moved voxels (a fragment joined to a
//                          piece of another grain) counts without them in
//                          f1 (measured: chipping precision +0.007 to +0.035
//                          at every point of data_synth's 256^3 blind range,
//                          split recall +0.001 to +0.003; see RESULTS).
//                          ... and a parent that the scan's faces cut
//                          (cut_by_faces, step 7) one of whose smaller pieces
//                          they cut too is split (2 children) or
//                          fragmentation (>= 3) whatever f1 says: the faces
//                          hide an unknown part of each piece, so their
//                          visible shares cannot tell a chip from a half (a
//                          grain seen as a cap a few voxels deep, split
//                          across it, shows a large and a small piece).
//                          Splitting is the main mode (the study), so the
//                          count decides; a piece wholly inside the scan is
//                          still weighed by f1 (cut_pieces_by_count). Measured
//                          (bench/track/RESULTS.md, blind_series windows, R 8
//                          to 30, every parent): on the truth labels 72 of
//                          the 114 splits missed at R 12 were such chippings,
//                          chipping precision 0.40-0.52; with the rule split
//                          F1 +0.04 to +0.08, chipping F1 +0.07 to +0.24 but
//                          at R 30 (-0.07: its chips are cut by the faces
//                          too); segmented alike (split +0.03 to +0.08,
//                          chipping +0.10 to +0.20, R 30 -0.10). Not on
//                          data_synth's specimens (no grain cut by a face).
//     Children of B without a parent are `new`. Fragments are particles like
//     any other at the next stage, so they are tracked and can break again.
//  6. The stage-0 ancestor (`grain`) is carried down the lineage; a grain is
//     "intact" at stage s while every event of its chain is `intact`.
//  7. The % of intact grains broken (summary.csv) is counted over the
//     stage-0 grains the scan's faces do not cut (cut_by_faces: at least
//     kCutFootprintShare x pi r_eq^2 of their voxels on a face, r_eq their
//     equivalent radius). A grain cut by a face hides the part beyond it,
//     and most of its breaks with it: on windows of another generator's
//     series (bench/track/blind_series.py, R 12, seeds 2 and 3) the % over
//     every grain came out 4-5 points under the truth's on the truth labels
//     themselves (68.1, 65.4 against 72.5, 70.1), the % over the grains
//     clear of the faces within 1 (71.8, 71.1). A grain merely resting on a
//     face (data_synth's specimen: 0.2-11 % of pi r_eq^2 there) is not cut.
//     With fewer than kMinUncutGrains such grains every grain counts;
//     pct_intact_broken_all is the % over every grain.
//  8. Where a particle with no child went (events.csv `lost_as`, summary.csv
//     lost_*): its voxels, moved by the global map, are counted where they
//     land in the next stage, and the largest of three shares names it:
//     `left_field` (outside the next stage's volume: a window the specimen
//     moves through), `merged` (inside the next stage's labels; `into_label`
//     the one holding most: the segmentation joined it to a neighbour, as it
//     does a fragment pressed flat on the next grain; it is still there,
//     unseen), `vanished` (in the void: it fell below the detection limit).
//     No parameter. Measured (bench/track/RESULTS.md "Where lost particles
//     went").
//
// Stages out of order: the axial scale M_zz of the map is 1 - (strain
// increment); M_zz > 1 + extension_tolerance means the specimen got longer,
// which an oedometer never does: InputError naming both files, unless
// allow_extension is set (the map's scale is then reported as is).
//
// Rotation: with the stages' grey scans (Tracker::add_stage's `grey`, track
// --scans) each particle with a parent is registered rigidly on the earlier
// scan from where its parent's motion puts it (rigid_fit.hpp): its rotation
// vector and standard error. Without them it is NaN: near-spherical grains
// have no stable principal axes to read it from the labels. Displacement is
// the centroid's, child minus parent.
//
// Measured (bench/track/RESULTS.md, 789-grain zeolite series, shared 2-core
// VM): 0.2-0.3 s per stage at 256^3, 2.1-2.7 s at 512^3, file reading apart.
// Memory: the previous stage's label volume (4 B/voxel) and the current one,
// plus O(particles) tables: 8 B/voxel at peak. Time: two passes over each
// stage's solid voxels (affine per voxel, one lookup in B), O(V) with
// OpenMP slabs; the per-thread counts are integers merged in thread order,
// so the result is identical for any thread count.
#pragma once
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/dtype.hpp"
#include "core/table.hpp"
#include "core/volume.hpp"
#include "track/registration.hpp"

namespace tg::track {

// Events, as written in lineage.csv / events.csv.
enum class Event { intact, split, fragmentation, chipping, chip, new_particle, lost };
// Where a `lost` particle went (step 8); unknown for lineages read back or built outside the tracker.
enum class LostAs { unknown, left_field, merged, vanished };
const char* lost_as_name(LostAs l);  // "-", "left_field", "merged", "vanished"

const char* event_name(Event e);      // "intact", "split", "fragmentation", "chipping", "chip", "new", "lost"
Event event_from_name(const std::string& name);  // InputError on an unknown name

struct TrackOptions {
  MapOptions map;
  double min_overlap_fraction = 0.2;  // a child's voxels covered by its parent, at least
  double nearest_slack_vox = 2.0;     // uncovered children: centroid within the parent's moved sphere + this
  double surface_tolerance_vox = 1.0; // d above
  double min_volume_tolerance = 0.1;
  double chip_body_fraction = 0.7;    // f1 at or above this: chipping
  double hidden_split_fraction = 0.7; // one child keeping at most this share of the volume: split
  bool absorbed_chips = true;          // step 5: chips absorbed by a neighbour's label
  bool glued_pieces = true;            // step 5: pieces glued on at the stage before are not chips
  double glued_volume_tolerance = 0.03;  // e of that rule, a share of the volume before the gain
  bool absorbed_pieces = true;         // step 5: a break's piece in a neighbour's label counts as a child
  double absorbed_piece_fraction = 0.15;  // T of that rule, a share of the parent's volume, at least
  double absorbed_confirm_fraction = 0.5;  // a's loss or n's gain, at least this share of T
  // step 5: a whole grain whose one child lost more than the stage's whole grains usually do
  // (median + this many robust standard deviations of their relative loss) is chipping; 0: off
  double loss_outlier_sigmas = 4.0;
  double loss_floor_fraction = 0.015;  // ... and at least this share of its volume
  // ... a grain smaller than the stage's median r_eq has its relative loss weighed by
  // (r_eq / median)^this, in the statistics and the test: a small grain's label count
  // varies more from stage to stage (2 chosen on wide gradings; 0: one limit for all sizes)
  double loss_size_power = 2.0;
  // step 5: a chipping whose every piece its parent covers less than this share of (match
  // quality) needs its body to lose more than weak_piece_loss_share of the same limit, else
  // the pieces are `new`
  double weak_piece_coverage = 0.5;
  double weak_piece_loss_share = 0.6;
  // step 5: a parent cut by the faces whose smaller pieces the faces cut too is split or
  // fragmented by its count of pieces (their visible shares say nothing about chipping)
  bool cut_pieces_by_count = true;
  bool refine = true;                 // step 4
  bool allow_extension = false;       // accept stages whose map lengthens the specimen
  double extension_tolerance = 0.002;
  int threads = 0;                    // OpenMP threads; 0 = the default
  bool progress = false;
};

inline constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();

// One particle at one stage (lineage.csv).
struct LineageRow {
  int stage = 0;
  uint32_t label = 0, parent_label = 0, grain = 0;
  Event event = Event::intact;
  int64_t volume_vox = 0;
  std::array<double, 3> centroid_vox{0, 0, 0};       // (z, y, x), voxel coordinates
  std::array<int64_t, 3> box_lo{0, 0, 0}, box_hi{0, 0, 0};  // bounding box, voxel indices (hi one past; not in the CSV)
  std::array<double, 3> displacement_vox{0, 0, 0};   // centroid minus parent's (NaN without parent)
  double quality = 1;  // fraction of the particle's voxels covered by its moved parent (1 at stage 0, 0 if new)
  bool touches_border = false;
  int64_t face_vox = 0;  // voxels on the volume's faces (one per face an edge voxel lies on; 0 when unknown)
  // Rotation since the previous stage (rigid_fit.hpp, with the stages' grey scans): rotation vector,
  // axis times angle, degrees, (z, y, x); and its standard error. NaN where not fitted.
  std::array<double, 3> rotation_deg{kNoValue, kNoValue, kNoValue};
  double rotation_se_deg = kNoValue;
  // A break one of whose pieces a neighbour's label absorbed (step 5: the chip of a one-child
  // grain, or a piece of a break with two or more children): the voxels of the parent found in
  // that label (T), on the first (largest) child's row; 0 otherwise.
  int64_t absorbed_vox = 0;
};

// One event per parent particle and stage (events.csv), lost included.
struct EventRow {
  int stage = 0;  // the stage where the children are seen
  uint32_t parent_label = 0, grain = 0;
  Event type = Event::intact;
  std::vector<uint32_t> children;
  int64_t volume_before_vox = 0, volume_after_vox = 0;
  int64_t absorbed_vox = 0;  // voxels of a chip or piece a neighbour's label absorbed (0: none, or seen)
  double parent_z_vox = 0;
  int band = 0;  // height fifth of the parent in its stage (1 = bottom .. 5 = top)
  LostAs lost_as = LostAs::unknown;  // a `lost` event's fate (step 8)
  uint32_t into_label = 0;           // `merged`: the label of the event's stage that holds it
};

// A particle of stage s - 1 with no child at stage s, and where it went (step 8).
struct LostRow {
  int stage = 0;  // the stage where it is missing
  uint32_t label = 0;  // its label at stage - 1
  LostAs as = LostAs::unknown;
  uint32_t into_label = 0;
  int64_t outside_vox = 0, in_labels_vox = 0, void_vox = 0;  // the three shares of its moved voxels
};

// Per stage (summary.csv).
struct SummaryRow {
  int stage = 0;
  int64_t particles = 0, grains_intact = 0, grains_broken = 0, grains_lost = 0;
  double pct_intact_broken = 0;  // 100 broken / (intact + broken), stage-0 grains not cut by the faces (step 7); lost grains are in neither
  double pct_intact_broken_all = 0;  // the same over every stage-0 grain
  int64_t grains_cut = 0;            // stage-0 grains cut by the faces, left out of pct_intact_broken
  int64_t split = 0, fragmentation = 0, chipping = 0, chips = 0, lost = 0, new_particles = 0;
  int64_t chips_absorbed = 0;  // chipping events whose chip a neighbour's label absorbed (not in `chips`)
  int64_t lost_left_field = 0, lost_merged = 0, lost_vanished = 0;  // `lost` by where it went (step 8)
  std::array<int64_t, 5> breaks_band{0, 0, 0, 0, 0};     // breakage events of this stage by parent height fifth
  std::array<double, 5> pct_broken_band{0, 0, 0, 0, 0};  // stage-0 grains of each fifth broken by now, % (not cut by the faces)
  double axial_scale = 1;  // map from the previous stage (1 at stage 0)
  int map_matches = 0;
  std::string map_method = "-";
};

struct TrackResult {
  std::vector<std::string> stage_names;
  std::vector<StageMap> maps;  // maps[s] takes stage s-1 to s (maps[0] identity)
  std::vector<LineageRow> lineage;
  std::vector<EventRow> events;
  std::vector<SummaryRow> summary;
  std::vector<LostRow> lost;  // step 8, every stage
  std::vector<double> seconds;  // per stage: tracking only (track_files adds the reading below)
  // Set by track_files, per stage: wall time reading the file and tracking it, and the
  // peak resident memory of that (tg::reset_peak_rss; own_peak false: the process's peak).
  std::vector<double> stage_seconds;
  std::vector<int64_t> peak_rss_bytes;
  bool own_peak = false;
  int64_t voxels = 0;  // per stage (the largest, when stages were cropped differently)
};

// Step 5 for one pair of stages: given each B particle's parent (index into
// prev, -1 for none), sets parent_label, grain, event and displacement of
// `rows` (quality is left to the caller) by the classification above
// (volumes, border flags and the tolerances of `o`). Shared by the tracker and
// by exact lineages built outside it (compare/dem_lineage.hpp), so an event
// means the same everywhere.
//
// `ev`: what the tracker sees of the segmentation's mistakes (empty for exact
// lineages, which see every piece and glue nothing).
struct NeighbourTransfer {
  int32_t into = -1;  // index into rows; -1: none, or the A particle is not eligible
  int64_t voxels = 0;
  int64_t contact_faces = 0;  // S_an: faces the A particle shares with `into`'s parent at stage A
  // d of the rule (track.hpp step 5), voxels; 0: surface_tolerance_vox.
  double shift_vox = 0;
};
struct LinkEvidence {
  // Per A particle eligible for the absorbed-chip rule (a whole grain): the B particle of
  // another parent that received most of its moved voxels, and how many.
  std::vector<NeighbourTransfer> chip;
  // The same for every A particle (the absorbed-piece rule).
  std::vector<NeighbourTransfer> piece;
  // Per A particle: the voxels it gained over its chain of 1:1 intact steps (from the volume
  // where that chain began; 0 when it was in none, or a face cut it), for the glued-piece rule.
  std::vector<int64_t> gain;
  // Per A particle: still a whole stage-0 grain (no break in its chain), for the
  // volume-loss rule (empty: none is).
  std::vector<char> whole;
  // Per B particle: the share of its voxels its moved parent covers (its match quality; empty:
  // every piece counts as covered).
  std::vector<double> coverage;
  // Per B particle: voxels of A particles other than its parent found in it (their moved
  // voxels); a child holding at least absorbed_piece_fraction of such voxels is counted
  // without them when its parent's break is classified (a fragment the segmentation joined
  // to a piece of another grain).
  std::vector<int64_t> foreign;
};
// The part of the threshold on T that does not depend on the contact: 2 pi r_eq d^2.
double new_contact_voxels(double volume_vox, double d_vox);
void link_stage(const std::vector<LineageRow>& prev, std::vector<LineageRow>& rows, const std::vector<int32_t>& parent,
                const TrackOptions& o, const LinkEvidence& ev = {});

// Step 7: a stage-0 grain cut by the volume's faces, not merely resting on one.
inline constexpr double kCutFootprintShare = 0.2;
inline constexpr int64_t kMinUncutGrains = 20;
bool cut_by_faces(const LineageRow& r);

// Events and summary from a lineage (the tracker's or a truth lineage in the
// same columns): events group each stage's rows by parent; a parent of the
// previous stage without children is lost (where it went from `lost`, step 8, when given).
std::vector<EventRow> derive_events(const std::vector<LineageRow>& lineage, int stages,
                                    const std::vector<LostRow>& lost = {});
std::vector<SummaryRow> summarise(const std::vector<LineageRow>& lineage, const std::vector<EventRow>& events,
                                  int stages);

// Incremental tracker: feed the stages in loading order, then take the result.
// Keeps only the previous stage's labels.
class Tracker {
 public:
  explicit Tracker(TrackOptions options = {});
  // Stages must share the voxel size (InputError naming `name`); their shapes
  // may differ (each scan cropped to its own specimen): the map takes up the
  // offset, and displacements are in the frame of the files' origin_m.
  // Returns the stage before's labels, no longer needed (their storage can
  // hold the next stage: ReadOptions::reuse).
  // `grey`: the stage's scan, the labels' shape (empty: none). With the scans of two consecutive
  // stages each particle with a parent gets its rotation (rigid_fit.hpp); 2-4 B/voxel more.
  Volume<uint32_t> add_stage(Volume<uint32_t> labels, const std::string& name, AnyVolume grey = {});
  TrackResult result() const;  // derives events and summary
  int stages() const { return static_cast<int>(names_.size()); }
  // Moves the last stage's labels (4 B/voxel, kept for the next add_stage)
  // and its scan (when one was given) to `file` (HDF5, deflate level 1; removed when read back or when the
  // tracker goes): for a caller that images or segments the next stage in
  // between, as compare does at full size. The next add_stage reads them
  // back: the lineage is the same, for one write and one read of the labels
  // (~10 s at 1220^3 with tomograin's parallel deflate).
  void spill(const std::string& file);
  int64_t held_bytes() const {
    const int64_t grey = std::visit([](const auto& v) { return v.size() * int64_t(sizeof(v.data()[0])); }, prev_grey_);
    return prev_.size() * int64_t(sizeof(uint32_t)) + grey;
  }
  // Frees the last stage's labels (and any spill file) for a caller that adds
  // no more stages: result() does not need them. compare calls it after its
  // last stage, whose DEM imaging otherwise ran beside both trackers' labels
  // (12.7 B per XCT voxel at 1220^3, bench/scale/RESULTS.md). A later
  // add_stage is a logic error.
  void finish();
  ~Tracker();
  Tracker(Tracker&&) = default;
  Tracker& operator=(Tracker&&) = default;

 private:
  struct Particles;
  TrackOptions o_;
  std::vector<std::string> names_;
  Volume<uint32_t> prev_;
  AnyVolume prev_grey_;  // the last stage's scan (empty: none given)
  std::string spilled_;  // the file holding prev_ while it is out of memory
  bool finished_ = false;
  std::vector<LineageRow> prev_rows_;
  std::vector<char> prev_whole_;  // per prev_rows_: a stage-0 grain with no break in its chain
  std::vector<int64_t> prev_gain_;  // per prev_rows_: voxels gained over its chain of 1:1 intact steps (link_stage's gain)
  std::vector<int64_t> prev_base_;  // per prev_rows_: the volume where that chain began
  std::vector<LineageRow> lineage_;
  std::vector<LostRow> lost_;
  std::vector<StageMap> maps_;
  std::vector<double> seconds_;
  std::array<double, 3> prev_origin_m_{0, 0, 0};  // the last stage's origin_m (its labels may be spilled)
};

// Reads label volumes (an .h5 file's /labels by default) in the order given
// and tracks them. InputError names the file whose voxel size differs from
// the first, or the pair given out of order.
// `scans`: the stages' grey scans (empty, or one per stage, each its labels' shape: InputError
// naming the file otherwise), for the particles' rotations.
TrackResult track_files(const std::vector<std::string>& paths, const TrackOptions& options = {},
                        const std::vector<std::string>& scans = {});

// The three tables and their writer (DIR/lineage.csv, events.csv, summary.csv,
// each atomic; DIR is created).
Table lineage_table(const TrackResult& r);
Table events_table(const TrackResult& r);
Table summary_table(const TrackResult& r);
void write_outputs(const TrackResult& r, const std::string& dir);

// A lineage read back from CSV (tracker output or data_synth truth).
std::vector<LineageRow> read_lineage(const Table& t);

}  // namespace tg::track
