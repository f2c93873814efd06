// The sequential breakage model of the reference study (§3.2, §4.2) on top
// of the DEM engine: parallel bonds inside fragments, grain splitting by the
// maximum contact force, replacement by two bonded 17-sphere fragments, and
// the records the study reports.
//
// Per step (engine force hook, after the contact forces are gathered):
//   every intact bond is updated (parallel_bond.hpp) from the half-step
//   velocities, its forces and moments (and its dashpot's force, when
//   bond damping is on) are added to its two spheres, and it
//   breaks (is removed) once its peak normal or shear stress exceeds the
//   strength. The bond acts IN PARALLEL with the Hertz–Mindlin contact of the
//   two spheres, as in Potyondy & Cundall (2004): bonded spheres are created
//   exactly tangent, so the contact only carries compression, and after the
//   bond breaks the plain contact is all that remains.
// Every `check_interval` steps (check()):
//   for every sphere with d ≥ min_split_diameter (and, with split_bonded
//   false, no intact bond or an overlap past fines_overlap × r), F_max = its largest normal
//   contact force (sphere and wall contacts, last force evaluation);
//   σ = F_max/d² is compared with its strength (strength.hpp). Each sphere
//   over its strength (ascending index) is split: splitting plane from its
//   contacts (splitting_plane.hpp), replaced by 34 spheres (replacement.hpp):
//   the first takes the mother's index, 33 are appended through the
//   particle field list (Particles::resize + copy_sphere: every field is
//   inherited, then position/size/mass/velocity/force are set); its bonds
//   are dropped (recorded apart from bonds broken by stress); the
//   fragment's 40 internal bonds are created; particle ids are relabelled
//   (a particle = connected set of bonded spheres, id = smallest sphere
//   index of the set); the time step is lowered if the new spheres need it.
//
// Time step: dt ≤ safety × min over spheres of √(m/k_Hertz(r)) (k at 5 %
// overlap against a wall, the stiffest partner a sphere can have), and for
// bonded spheres √(m/Σ k̄n A) and √(I/Σ k̄n I_b) over their bonds;
// re-evaluated after each split, never raised. Selective density scaling
// (min_time_step_s) scales the mass and inertia of new spheres that would
// pull it below the minimum; sub-limit spheres that meet the criterion or
// are squeezed past fines_overlap are removed as fines (SublimitPolicy).
// Both are modelling decisions of this implementation, argued and measured
// in dem/breakage/README.md.
//
// Known approximations (stated, not hidden): the sphere that takes the
// mother's index inherits the tangential histories of the mother's sphere
// pairs (the engine carries histories by index pair); the tangential part of
// wall forces is not seen by the average stress (only wall normal forces).
//
// A scene without breakage never constructs this class: no bond arrays, no
// hook, no checks. Cost with breakage: O(bonds) per step, O(pairs) per check.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "dem/breakage/parallel_bond.hpp"
#include "dem/breakage/replacement.hpp"
#include "dem/breakage/splitting_plane.hpp"
#include "dem/breakage/strength.hpp"
#include "dem/engine.hpp"

namespace tg::dem::breakage {

// What happens to a sphere below the minimum split diameter that meets the
// breakage criterion or is squeezed into a neighbour (README: "Sub-limit spheres").
enum class SublimitPolicy {
  kRemove,  // removed as fines (volume counted as lost: below the 0.2 mm XCT resolution)
  kKeep,    // stays; the engine's overlap limit may then stop the run
  // Stays and never breaks (the study: spheres under 0.2 mm are kept,
  // unbreakable); removed as fines only when squeezed past fines_overlap or
  // born past it (a fragment sphere in its mother's contact), which no Hertz
  // contact of so small a sphere can hold: kKeep's stable form.
  kKeepUnbreakable,
};

// What a new fragment sphere does with the overlap it is born with (issue 21,
// frag21). Fragment spheres lie inside their mother, so none overlaps a
// neighbour or wall by more than the mother did (triangle inequality); but
// an outer sphere at the mother's contact can inherit a large part of that
// overlap, i.e. a Hertz force of several N on a sphere whose bonds hold ~1 N
// (README: "Fragments born loaded").
enum class BirthOverlap {
  kInherit,  // placed as the template says (today)
  // A sphere overlapping a neighbour or wall by more, relative to its own
  // radius, than the mother did (δ/r > δm/R, δm the mother's largest
  // overlap) is shrunk (centre fixed) to δ/r = δm/R: it is born no more
  // strained than the mother was.
  kMotherRatio,
  kNone,  // shrunk until it only touches (δ = 0): fragments are born unloaded
};

struct BreakageOptions {
  int64_t check_interval = 10;       // steps between grain checks (the study: 10)
  double min_split_diameter_m = 2e-4;  // smaller spheres never split (the study: 0.2 mm)
  StrengthParams strength;           // Weibull law; d0 must be set to the mean grain size
  ParallelBondParams bond;           // E and G should match the engine's material
  // dt ≤ safety × critical step when spheres appear; 0.5 × √(m/k) is ~0.35
  // of the two-body Verlet limit √(2m/k).
  double time_step_safety = 0.5;
  // Selective density scaling: a sphere made by a split whose own critical
  // step × time_step_safety is below this gets its mass and inertia scaled
  // up by the smallest factor that lifts it to this, so the run's step never
  // falls below it. Default 1e-8 s: the study's smallest step. 0 = off (the
  // step follows the smallest fragment down to ~3e-9 s).
  double min_time_step_s = 1e-8;
  // Which spheres the check may split: true, any sphere of at least
  // min_split_diameter (cluster elements too); false, only spheres with no
  // intact bond (grains, and fragment elements whose bonds have all broken):
  // the study's reading, replacement for grains, bond breakage for fragments
  // ("isolated spherical grains can always break"). Except that a bonded
  // sphere over its strength and squeezed past fines_overlap × r (by a
  // neighbour or a wall) splits all the same, its bonds dropped with it:
  // bonds only carry compression there, so nothing else stops a bonded
  // 0.2 mm element from being pushed through the grain that crushes it
  // (with λ ≥ 2 this stopped full runs on the engine's overlap limit).
  bool split_bonded = true;
  SublimitPolicy sublimit = SublimitPolicy::kRemove;
  // kRemove, kKeepUnbreakable: a sub-limit sphere whose largest contact overlap exceeds this
  // fraction of its radius is removed too (the engine stops at overlap_limit,
  // default 0.5, so this must be below it to act first); so is a new
  // fragment sphere (any size) born overlapping a neighbour of its mother or
  // a wall by more than this (the crushed zone at the mother's contact).
  double fines_overlap = 0.3;
  // Birth overlap of fragment spheres (above). A shrunk sphere keeps its
  // centre and density (its mass follows its radius; the shaved volume is
  // counted in volume_lost); its bonds are sized from the radii it is born
  // with (bond_section), so the bonds of a shrunk sphere span a small gap.
  // Shrinking never takes more than half of a sphere's radius; spheres born
  // past fines_overlap are fines first (SublimitPolicy), as with kInherit.
  BirthOverlap birth_overlap = BirthOverlap::kInherit;
};

// Counters for the history table.
struct BreakageRecord {
  int64_t grains_broken = 0;                  // original (generation 0) spheres that split
  std::vector<int64_t> splits_by_generation;  // [g] = splits of spheres of generation g
  int64_t bonds_broken = 0;                   // by stress (σmax > σ̄c or τmax > τ̄c)
  int64_t bonds_dropped = 0;                  // removed with a cluster element that split
  int64_t bonds_intact = 0;
  int64_t spheres = 0;
  int64_t particles = 0;                      // connected bonded sets
  double volume_lost_m3 = 0;                  // template loss + fines, m³
  int64_t fines_removed = 0;                  // sub-limit spheres removed (SublimitPolicy::kRemove)
  double fines_volume_m3 = 0;                 // their volume (part of volume_lost_m3)
  double added_mass_kg = 0;                   // density scaling: Σ (m - m_nominal) over the spheres
  double added_mass_fraction = 0;             // added_mass_kg / Σ m_nominal
};

// One split, for tests and logs.
//   mother_overlap_ratio: the mother's largest overlap with a neighbour or
//     wall (positions of the check) / her radius;
//   fragment_overlap_ratio: the largest overlap / own radius of the 34 new
//     spheres as the template places them (before fines and birth_overlap);
//   fragment_contacts, fragment_force_N: touching contacts of the new
//     spheres as born (after birth_overlap) and the largest Hertz normal
//     force among them, estimated from the overlap with the grain-grain law
//     (r_eff = r for a wall), N — to set against f_max_N and the bond
//     strength σ̄c·A of the fragment's bonds (~1 N for a 1.3 mm grain).
// Neighbours = spheres touching the mother at the check (and their own new
// fragments when they split in the same check) and walls.
struct SplitEvent {
  int64_t step = 0;
  double time_s = 0;      // engine time of the check
  int64_t sphere = 0;     // index of the mother (now the first fragment sphere)
  Vec3 position;          // the mother's centre, m
  int generation = 0;     // of the mother
  double diameter_m = 0;
  double f_max_N = 0, stress_Pa = 0, strength_Pa = 0;
  SplittingPlane plane;
  double volume_retained_m3 = 0, volume_mother_m3 = 0;
  double mother_overlap_ratio = 0, fragment_overlap_ratio = 0;
  int64_t fragment_contacts = 0;
  double fragment_force_N = 0;
};

// One bond broken by stress (not dropped with a split element), for the
// diagnosis of how long fragments hold together (bond_breaks.csv).
// age: number of steps the bond was updated / simulated time since it was
// made (a fragment's bonds are made at its split, so this is the fragment's
// age); generation: of its spheres; tensile: σmax/σ̄c ≥ τmax/τ̄c.
struct BondBreak {
  int64_t step = 0;            // the step in which it broke
  double time_s = 0;           // engine time at the end of that step
  int64_t born_step = 0;       // engine step count when it was made
  int64_t age_steps = 0;
  double age_s = 0;
  int generation = 0;
  double radius_a_m = 0, radius_b_m = 0;
  bool tensile = false;
};

class BreakageModel {
 public:
  // Validates the options (InputError), draws the strengths of the engine's
  // spheres (key = sphere index), installs the engine force hook. The model
  // must outlive the engine's use of the hook (it holds a pointer to itself).
  BreakageModel(Engine& engine, const BreakageOptions& opt);
  BreakageModel(const BreakageModel&) = delete;
  BreakageModel& operator=(const BreakageModel&) = delete;

  // Runs `steps` engine steps, checking grains every check_interval steps
  // (counted on the engine's step counter).
  void run(int64_t steps);
  // One grain check now; returns the number of spheres split.
  int check();
  // Whether a check is due after the engine's last step: every
  // check_interval steps, and at once after a step in which a sub-limit
  // sphere was squeezed past the engine's overlap limit (the engine's
  // overlap hook: such a sphere is fines, removed by that check, where the
  // run used to stop as unstable; README, "Sub-limit spheres").
  bool check_due() const { return !squeezed_.empty() || eng_.step_count() % opt_.check_interval == 0; }
  // Removes these spheres (indices now) as fines: volume to volume_lost and
  // fines_volume, their bonds dropped, the others renumbered in order
  // (Engine::remove_spheres). Used by check(); public for tests.
  void remove_fines(const std::vector<int64_t>& spheres);
  // A new intact bond between spheres a and b (any order, a != b), section
  // from the options, no stored force; particle ids follow at the next check.
  // Used by the splits; public for tests (a bond between two given spheres).
  void add_bond(int64_t a, int64_t b);
  // Density scaling factor of sphere s (1 = nominal mass).
  double mass_factor(int64_t s) const { return mass_factor_[s]; }

  const BreakageRecord& record() const { return rec_; }
  const std::vector<SplitEvent>& events() const { return events_; }
  // Every bond broken by stress since the model was built or restored.
  const std::vector<BondBreak>& bond_break_log() const { return bond_breaks_; }
  double strength(int64_t s) const { return strength_[s]; }
  int generation(int64_t s) const { return generation_[s]; }
  // Intact bonds (sphere index pairs) and their state, for snapshots.
  int64_t bond_count() const { return static_cast<int64_t>(ba_.size()); }
  int64_t bond_a(int64_t b) const { return ba_[b]; }
  int64_t bond_b(int64_t b) const { return bb_[b]; }
  const BondState& bond_state(int64_t b) const { return state_[b]; }
  // The whole model state as text (bit-exact %.17g; keys, generations, bonds
  // with their forces, records, the engine's current time step), for the
  // checkpoint; restore() reads it back into a model built on the restored
  // engine (strengths are recomputed from keys and diameters). Throws
  // InputError on a malformed or mismatched state.
  std::string encode() const;
  void restore(const std::string& state);
  // Largest normal contact force of every sphere in the last force evaluation, N.
  std::vector<double> max_normal_forces() const;

 private:
  void add_bond_forces(Engine& e);
  // Replaces sphere s, whose bonds the caller has dropped, by two fragments;
  // `neighbours`: the spheres the new ones may overlap (besides walls).
  // Fills ev's birth figures and born_overlap[k] = largest overlap (m) of
  // new sphere k as placed (the fines rule's), with `fines_neighbours` only.
  Replacement split(int64_t s, const SplittingPlane& plane, const std::vector<int64_t>& neighbours,
                    const std::vector<int64_t>& fines_neighbours, SplitEvent& ev, std::vector<double>& born_overlap);
  // The contact loads (point, force on the sphere) of each of `spheres`, in
  // one pass over the pair list: O(pairs + spheres).
  std::vector<std::vector<ContactLoad>> contact_loads(const std::vector<int64_t>& spheres) const;
  void relabel_particles();
  void update_time_step();
  void update_mass_record();
  // √(m/k) of one sphere: Hertz at 5 % overlap against a wall, its bonds'
  // axial and bending springs (kt, kr: sums over its bonds; 0 = none).
  double own_critical_step(double m, double inertia, double r, double kt, double kr) const;
  // Largest contact overlap of every sphere / its radius (last positions).
  std::vector<double> max_overlap_ratios() const;
  double wall_overlap(int64_t s) const;  // largest overlap with a wall, m (0 = none)
  double wall_overlap(Vec3 x, double r) const;  // the same for a sphere at x of radius r
  // Removes the bonds flagged in broken_; adds their count to *counter;
  // `log`: record each in bond_breaks_ (broken by stress, in the force hook).
  void compact_bonds(int64_t* counter, bool log = false);
  // Drops (counted in bonds_dropped) every bond with an end marked non-zero.
  void drop_bonds_of(const std::vector<uint8_t>& marked);

  Engine& eng_;
  BreakageOptions opt_;
  BreakageRecord rec_;
  std::vector<SplitEvent> events_;
  // Per sphere, in the engine's sphere order. The declared list below drives
  // every resize and move, as Particles::for_each_field does for the spheres.
  std::vector<double> strength_;
  std::vector<uint64_t> key_;
  std::vector<int> generation_;
  std::vector<double> mass_factor_;  // density scaling, inherited by fragments
  template <class F>
  void for_each_sphere_field(F&& f) {
    f(strength_), f(key_), f(generation_), f(mass_factor_);
  }
  HertzMindlin law_;                 // for the per-sphere critical step
  // Bonds (structure of arrays), with their declared list.
  std::vector<int64_t> ba_, bb_;
  std::vector<BondSection> section_;
  std::vector<BondState> state_;
  std::vector<uint8_t> broken_;
  std::vector<int64_t> born_step_;  // engine step count when made (diagnostics)
  std::vector<double> born_time_;   // engine time then, s
  template <class F>
  void for_each_bond_field(F&& f) {
    f(ba_), f(bb_), f(section_), f(state_), f(broken_), f(born_step_), f(born_time_);
  }
  std::vector<BondBreak> bond_breaks_;
  std::vector<BondLoads> loads_;  // scratch, one per bond
  bool bonds_changed_ = false;
  std::vector<int64_t> squeezed_;  // sub-limit spheres past the engine's overlap limit this step: fines now
  bool take_squeezed(int64_t i, int64_t j);  // the engine's overlap hook
};

}  // namespace tg::dem::breakage
