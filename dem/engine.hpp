// The DEM engine: spheres (Particles), Hertz–Mindlin contacts between them
// and with three rigid walls, velocity-Verlet integration, a Verlet
// neighbour list with skin, and OpenMP parallelism whose result is bit for
// bit independent of the number of threads.
//
// One step (velocity Verlet, Allen & Tildesley §3.2):
//   v += dt/2 F/m, ω += dt/2 T/I, x += dt v, walls move      (kick-drift)
//   rebuild the pair list if some sphere moved > skin/2 since the last build
//   F, T = contacts(x, v½, ω½) + gravity, then local damping  (forces)
//   v += dt/2 F/m, ω += dt/2 T/I                              (kick)
// Velocity-dependent forces (dashpots, friction) use the half-step velocity,
// as LAMMPS/LIGGGHTS do.
//
// Determinism with threads: forces are never summed in an order that the
// thread count can change. (1) The pair list is cut into kForceParts parts
// by the pairs' rows (i in two contiguous ranges, cut where the rows' touching
// pairs are half done, found again every kBalanceEvery steps from the
// touching pairs and kept in checkpoints); each part computes its pairs' forces
// and torques (and updates their tangential histories) and sums them, in
// ascending pair order, into a per-sphere array of its own, each sphere's
// weight in the part of its row. The parts run on the OpenMP team. (2) A
// parallel loop over spheres adds the parts in order (skipping those that
// cannot hold a sum for it), then its wall contacts. (3) Wall reaction forces are
// summed serially over spheres. Every sum therefore has the same operands
// in the same order for any thread count; as the parts depend on the pairs'
// indices only, not on which non-touching pairs the neighbour list holds,
// the sums do not depend on the skin or on when the list was rebuilt either
// (a restart continues bit for bit). Tests compare 1- and 2-thread histories
// and runs with different skins byte for byte.
//
// The contact law runs on 2, 4 or 8 contacts at once (SSE2, AVX2 or AVX-512
// lanes, chosen at run time: dem/contact/kernels.hpp), pairs filled from a
// branch-free list of the touching pairs of each block, wall contacts from
// lists per block of spheres; lane arithmetic is the scalar law's, bit for
// bit, so every kernel gives the same run.
//
// Walls: bottom platen z = 0 (fixed), top platen z = top_z moving at top_vz
// (velocity-controlled; its reaction force is recorded), inner surface of a
// cylinder of radius R about the z axis. Sphere–wall contacts use the same
// Hertz–Mindlin law with R* = r (flat wall; the cylinder's concave curvature
// is neglected, as LIGGGHTS does) and their own friction coefficients.
//
// Extension points (breakage, issue 7):
//  * contact loop: Engine::compute_pair_forces() is the single place where
//    a pair's force is made. With a force hook installed (breakage), each
//    touching pair's force and torques are also kept in its slot (PairData)
//    for the hook's model to read (pair_force()); without one they are not
//    written.
//  * per-sphere contact statistics (max contact force, average stress tensor
//    σ_ij = 1/V Σ (x^c - x^p)_i F_j) are computed by the hook's model from
//    the kept slots (dem/breakage/breakage.cpp).
//  * sphere replacement: edit particles() (append_sphere/copy_sphere/resize),
//    then call request_rebuild(); pair histories are carried over for pairs
//    whose (i, j) indices survive and dropped otherwise — when indices are
//    renumbered, clear them with reset_pair_history().
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "dem/contact/hertz_mindlin.hpp"
#include "dem/contact/kernels.hpp"
#include "dem/neighbor_grid.hpp"
#include "dem/particles.hpp"

namespace tg::dem {

// Thrown when the integration blows up (overlap beyond the limit, non-finite
// force): the message names the step, the spheres and the time step versus
// the critical one. An InputError, so the CLI reports it in one line (exit 2).
struct SimulationError : InputError {
  using InputError::InputError;
};

struct Walls {
  bool bottom = true;            // platen at z = 0
  bool top = true;               // platen at z = top_z
  double top_z = 0.03;           // m
  double top_vz = 0;             // m/s (negative = moving down)
  bool cylinder = true;          // inner wall of radius cylinder_radius about z
  double cylinder_radius = 7.5e-3;  // m (Ø15 mm cell of the study)
  double platen_friction = 0.5;     // μ sphere–platen
  double cylinder_friction = 0.5;   // μ sphere–cylinder
};

struct EngineOptions {
  Material material;              // Table 1 of the study
  double friction = 0.5;          // μ sphere–sphere (Table 1)
  // Viscous normal+tangential damping from a restitution coefficient; 1 = off.
  // Default 0.5: the value of the LIGGGHTS peer runs, so that the two engines
  // dissipate alike; quasi-static loading needs some dissipation.
  double restitution = 0.5;
  // PFC local non-viscous damping α (F -= α |F| sign v per component); 0 = off.
  double local_damping = 0.0;
  // What local damping acts on. false: the contact, wall and gravity forces
  // (the gather damps them before the force hook adds bond forces, so a
  // bonded cluster is an undamped spring network); true: the total force on
  // each sphere, bond forces included (PFC damps the unbalanced force). The
  // same without a force hook (nothing is added after the gather).
  bool local_damping_total = false;
  double gravity_z = -9.81;       // m/s²
  double time_step = 1e-7;        // s (the study: 1e-8 .. 1e-7)
  double skin = 2e-4;             // neighbour skin, m (LIGGGHTS peer: 0.2 mm)
  // Overlap (fraction of the smaller radius) beyond which the run is
  // declared exploded; real oedometer contacts stay far below.
  double overlap_limit = 0.5;
  // Loops shorter than this run on one thread: below a few thousand items
  // the OpenMP fork/barrier costs more than the work (and results do not
  // depend on it either way).
  int64_t parallel_min_items = 512;
  // The contact kernels' instruction set (dem/contact/kernels.hpp): the
  // widest the CPU has by default. Every kernel gives the same bits.
  KernelIsa kernel_isa = KernelIsa::kAuto;
  Walls walls;
};

// Sums over the wall contacts of the last force evaluation (force on the
// wall by the spheres, N).
struct WallForces {
  double bottom_z = 0;     // force on the bottom platen, z component (< 0 when loaded)
  double top_z = 0;        // force on the top platen, z component (> 0 when loaded)
  double cylinder_radial = 0;  // outward radial force on the cylinder, N
};

class Engine {
 public:
  // Validates the options (throws InputError) and builds the first pair list.
  Engine(Particles p, const EngineOptions& opt);

  void step() { advance(false); }
  // `steps` steps. Within the run, each step's gather also makes the next
  // step's opening half kick and drift (one pass over the spheres and one
  // parallel region less a step; the same operations in the same order, so
  // the same bits as calling step() `steps` times). Between runs, and after
  // step(), velocities and positions are at the same time, as observers
  // (history, snapshots, the force hook) need.
  void run(int64_t steps);

  Particles& particles() { return p_; }
  const Particles& particles() const { return p_; }
  const EngineOptions& options() const { return opt_; }
  Walls& walls() { return opt_.walls; }
  const WallForces& wall_forces() const { return wf_; }
  double time() const { return time_; }
  int64_t step_count() const { return steps_; }
  int64_t rebuild_count() const { return rebuilds_; }

  // Diagnostics (serial sums in sphere order: thread-independent).
  double kinetic_energy() const;     // translational + rotational, J
  double elastic_energy() const;     // Hertz normal energy of pair + wall contacts, J
  double potential_energy() const;   // gravity, J (zero at z = 0)
  int64_t contact_count() const;     // touching sphere pairs
  // 2 (pair contacts) / spheres with at least one contact.
  double coordination_number() const;

  void request_rebuild() { force_rebuild_ = true; }

  // Breakage hooks (issue 7, dem/breakage/). The force hook runs after the
  // contact forces are gathered into particles().f*/t* and before the
  // closing kick: the bond law adds its forces there. No hook: one branch.
  void set_force_hook(std::function<void(Engine&)> hook) {
    force_hook_ = std::move(hook);
    slot_.assign(force_hook_ ? static_cast<size_t>(list_.pairs()) : 0, PairData{});  // kept only with a hook
  }
  // Overlap hook (breakage): called for each sphere pair (i, j) whose overlap
  // passes overlap_limit × the smaller radius, or a sphere i (j = -1) that
  // passes it into a wall, in the step's force evaluation. It returns true
  // when its model removes the sphere before the next step (a sub-limit
  // sphere squeezed through its neighbour between two checks is fines, not
  // an unstable run); the step then ends as usual, and run() returns after
  // it so that the model can act. false, or no hook: the run stops with
  // SimulationError, as before.
  void set_overlap_hook(std::function<bool(int64_t, int64_t)> hook) { overlap_hook_ = std::move(hook); }
  // Replaces the time step (> 0): breakage creates smaller spheres.
  void set_time_step(double dt);
  // Read-only view of the last force evaluation (per-sphere contact statistics).
  int64_t pair_count() const { return list_.pairs(); }
  int64_t pair_i(int64_t k) const { return pi_[k]; }
  int64_t pair_j(int64_t k) const { return list_.j[k]; }
  bool pair_touching(int64_t k) const { return touching_[k] == kTouching; }
  // Valid inside the force hook and after a step of an engine that has one:
  // without a hook the slots are not kept.
  const PairData& pair_force(int64_t k) const { return slot_[k]; }
  // Sphere s's wall reactions: force on the bottom platen (z), on the top
  // platen (z) and outward radial force on the cylinder, N.
  const double* sphere_wall_forces(int64_t s) const { return &wall_f_[3 * s]; }
  void reset_pair_history();
  // Removes the spheres with remove[s] != 0 (breakage: fines), keeping the
  // survivors in their order (index s -> old_to_new[s], -1 when removed),
  // and rebuilds the pair list. Tangential histories of surviving pairs and
  // the spheres' wall histories are kept (the map is monotone, so the CSR
  // order survives), i.e. nothing else in the run is perturbed. Returns the map.
  std::vector<int64_t> remove_spheres(const std::vector<uint8_t>& remove);

  // Full state for checkpoints: pair list with histories and time.
  struct PairHistory {
    std::vector<int64_t> i, j;
    std::vector<double> xi;  // 3 per pair
  };
  PairHistory pair_history() const;
  // Restores time/steps and pair histories after constructing from restored
  // particles (whose forces are restored too): the next step() continues
  // exactly as the saved run would have.
  void restore(double time, int64_t steps, const PairHistory& h);
  // The cut between the pair list's two parts (first row of part 1; -1:
  // half the spheres): part of the state a checkpoint keeps, as it decides
  // the order of the force sums.
  int64_t part_split() const { return split_next_; }  // the cut the next step uses
  void set_part_split(int64_t split);

 private:
  void rebuild();
  // One step; fuse_next: its gather makes the next step's opening kick and drift.
  void advance(bool fuse_next);
  // Forces of this step; kick: each sphere also gets its closing half kick;
  // drift_next: and the next step's opening half kick and drift.
  void compute_forces(bool kick, bool drift_next);
  void compute_pair_forces();
  void update_inverse_masses();
  // Whether a loop over `items` runs on the OpenMP team (enough items, and
  // more than one thread).
  bool parallel(int64_t items) const;
  // alpha: the local damping the gather applies (0 when it is applied to
  // the total force after the hook instead).
  void gather_forces(bool kick, bool drift_next, double alpha);
  // Local damping of the total force and torque of every sphere (after the hook).
  void damp_total_forces();
  [[noreturn]] void explode(const std::string& what) const;

  Particles p_;
  EngineOptions opt_;
  HertzMindlin law_pp_, law_platen_, law_cyl_;
  WallForces wf_;
  double time_ = 0;
  int64_t steps_ = 0, rebuilds_ = 0;
  bool force_rebuild_ = false;
  bool drifted_ = false;    // this step's opening kick and drift are done (run())
  int pending_moved_ = 0;   // their skin test: 1 moved beyond skin/2, 3 not finite
  std::function<void(Engine&)> force_hook_;
  std::function<bool(int64_t, int64_t)> overlap_hook_;
  bool overlap_handed_ = false;  // this step passed a deep overlap to the hook: run() returns after it

  // Pair list (CSR by i, ascending j) with per-pair history and force slot.
  PairListCSR list_;
  std::vector<int64_t> pi_;        // i of each pair
  std::vector<double> xi_;         // tangential history, 3 per pair
  std::vector<double> inv_m_, inv_i_;  // 1/m and 1/I per sphere (see step())
  bool keep_slots_ = true;             // slot_ written this step (see compute_forces())
  // The pair list's parts, each summed into its own per-sphere array (f then
  // t): two threads share the contact loop and nothing else of each other's.
  static constexpr int kForceParts = 2;
  std::vector<double> acc_;            // per part and sphere: f, t in a 64-byte line (engine.cpp kAccStride)
  std::array<PartRange, kForceParts> part_range_{};  // per part: its rows, the spheres its sums may touch
  int64_t part_range_n_ = -1;                        // the sphere count they were found for
  // The first row of part 1 (-1: half the spheres). Found every
  // kBalanceEvery steps so that each part holds half the touching pairs:
  // where contacts crowd (the loaded half of a specimen, a crushing zone),
  // halves of the rows left one thread with 87 % of them (1e4 spheres).
  int64_t split_ = -1, split_next_ = -1;  // the cut in use, and the one the next step takes
  static constexpr int64_t kBalanceEvery = 1000;
  void update_part_ranges();
  void balance_parts();
  std::vector<PairData> slot_;     // this step's force
  // Per pair: kTouching, kHistoryOnly or kNotTouching (contact/kernels.hpp).
  std::vector<uint8_t> touching_;
  ContactKernels kernels_;  // the contact loop of one part and the gather
  // Positions at the last rebuild (skin criterion).
  std::vector<double> x0_, y0_, z0_;
  // Per-sphere wall reaction this step (bottom z, top z, cylinder radial).
  std::vector<double> wall_f_;
  std::vector<uint8_t> wall_state_;  // per sphere: GatherArgs::wall_state
  std::vector<uint8_t> bad_;  // per-pair / per-sphere failure flags
};

}  // namespace tg::dem
