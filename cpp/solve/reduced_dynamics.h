// Secondary motion: the dynamics M ẍ + D ẋ + ∇E(x) = f whose quasi-static limits are the poses
// (paper section 3), in the reduced space x = x̄ + U q of a baked basis, the energy on the ghost
// and the handle term exact on the fine mesh, as in ReducedSolver. The reduced mass is ρI (the
// basis is M-orthonormal). Each substep is the implicit midpoint rule (symplectic: no numerical
// damping), written as the minimisation of an incremental potential Φ over the middle state, with
// stiffness-proportional Rayleigh damping relative to the controllers' motion, and solved by the
// warm-started Bfgs. ρ and the damping β come from the artist's `period` (frames at `fps`) and
// damping ratio, exact for the lowest flexible mode. The midpoint rule conserves the energy of a
// quadratic potential only: on a nonlinear one it drifts either way (bench/results/dynamics.json,
// "energy"), and a check that only removes energy ratchets it down. So each
// substep ends with an energy correction: the end velocity is rescaled, up or down, to the energy
// the step should have, what it had plus the handles' work less the damping's (for a quadratic
// potential the midpoint rule's own: there the correction vanishes). It needs no evaluation of the
// energy, unlike a discrete-gradient step (Gonzalez 1996) that would evaluate it inside the solve,
// and keeps the period and the decrement the midpoint rule sets. No substep ends above the energy
// it had plus the handles' work (implicit Euler takes one whose potential alone would). The scheme,
// Φ, the parameters' derivation and the correction: docs/design.md, "Secondary motion
// (cpp/solve/reduced_dynamics.h)".
//
// On a rig (a constructor given skinning weights), q is a displacement of the mesh in its rest
// space, skinned with it: the world shape is skin(x̄ + U q, W, B). Each frame's bones B drive it by
// the inertial forces of the skinned motion felt in each vertex's frame (rig_forces.h): ρ q̈ gains
// ρ g, g from the second difference of the bones over the previous two frames and this one,
// constant over the frame (every substep sees the same g, so substeps change nothing in how the
// rig's motion is read); the handles stay in rest space (identity: held where the rig puts them).
// Before the first frame (and after a set_state without bones) the rig counts as having been still
// in the pose of the first frame it is given (set_state's or step's); the state carries the two
// frames' bones the next one needs (rig_previous, rig_current), so a frame is the same bits however
// reached. ρ and β are set by the lowest mode of the mesh as attached (K plus the handles' term)
// instead of K's: the wobble the artist sees on the rig. A frame on the rig costs O(bones · r) more
// than one without.
//
// Not thread-safe: one simulation per thread.
#pragma once

#include <memory>

#include "basis/basis.h"
#include "energy/make_energy.h"
#include "solve/bfgs.h"
#include "solve/handle_term.h"
#include "solve/reduced_map.h"
#include "solve/rig_forces.h"

namespace modal_deform {

// The artist's parameters and their defaults (the Python API and the add-on take them from here).
struct SimulationOptions {
  double pull = kDefaultPull;  // μ of the handle term (handle_term.h)
  double period = 12.0;        // of the lowest flexible mode, in frames
  double damping = 0.05;       // ζ of the lowest flexible mode, in [0, 1]
  double fps = 24.0;           // frames per second
  int substeps = 2;            // midpoint steps per frame
  // BFGS per substep: at most this many iterations, and the stopping tolerance (bfgs.h), which
  // keeps the frames within the map's precision (FinePositions::kTolerance) of a tight solve's
  // (bench/results/dynamics.json, "tolerance").
  int max_iterations = 20;
  double tolerance = 1e-8;
  // BFGS keeps what it learnt of Φ's curvature over at most this many frames (step()); 1: each
  // frame learns afresh.
  int memory_frames = 8;
};

// The shortest period accepted: a vibration faster than this is not seen as one at the frame rate,
// and the mass scale's map (tanh of ω h/2) needs ω h < π.
constexpr double kMinPeriodFrames = 3.0;
constexpr int kMaxSubsteps = 64;

// The options as the Python API and the add-on take them (option.h), with their defaults from
// SimulationOptions{}: visit(option, field) with field the accessor o -> o.member.
template <typename Visit>
void for_each_simulation_option(Visit&& visit) {
  visit(kPull, [](auto& o) -> auto& { return o.pull; });
  visit(Option{"period",
               "Frames one swing of the lowest flexible mode takes (the slowest wobble): more make "
               "the mesh heavier "
               "and lazier, fewer make it snappier.",
               closed(kMinPeriodFrames, 1e6)},
        [](auto& o) -> auto& { return o.period; });
  visit(Option{"damping",
               "Damping ratio of the lowest flexible mode, stiffer modes damped more: 0 swings on "
               "forever, 1 settles "
               "without overshooting.",
               closed(0, 1)},
        [](auto& o) -> auto& { return o.damping; });
  visit(Option{"fps", "Frames per second: velocities are per second.", above_up_to(0, 1000)},
        [](auto& o) -> auto& { return o.fps; });
  visit(Option{"substeps",
               "Midpoint steps per frame: more follow fast controllers more closely and cost more "
               "per frame.",
               closed(1, kMaxSubsteps)},
        [](auto& o) -> auto& { return o.substeps; });
  visit(Option{"max_iterations", "BFGS iterations per substep at most.", at_least(1)},
        [](auto& o) -> auto& { return o.max_iterations; });
  visit(Option{"tolerance", "BFGS's stopping tolerance per substep (bfgs.h).", between_open(0, 1)},
        [](auto& o) -> auto& { return o.tolerance; });
  visit(Option{"memory_frames",
               "The most frames BFGS's memory of the curvature spans before it is forgotten (1: "
               "each frame learns "
               "afresh).",
               at_least(1)},
        [](auto& o) -> auto& { return o.memory_frames; });
}

// The midpoint rule's parameters that give the lowest flexible mode of a reduced rest Hessian the
// artist's period and damping ratio (the header says how), and the substep; Simulation and
// Inbetween alike.
struct DynamicsParameters {
  double mass_scale = 0;        // ρ: the reduced mass is ρI
  double rayleigh = 0;          // β, seconds: the damping is β times the stiffness
  double substep = 0;           // h, seconds
  Eigen::VectorXd lowest_mode;  // the lowest flexible mode's unit eigenvector
};

// From `hessian` (r by r, symmetric: K, or on a rig K plus the handles' term) and the options
// (checked). Throws InputError when it has no flexible mode to set the period by, or when the
// options together give a mass scale, damping or substep beyond double precision (a tiny fps).
DynamicsParameters dynamics_parameters(const Eigen::MatrixXd& hessian,
                                       const SimulationOptions& options);

// The handles' term as the dynamics use it: μs⁴ on the fine mesh, restricted to the basis
// (handle_term.h); weights checked (checked_handle_weights) by the caller.
ReducedHandleTerm dynamics_handle_term(const Basis& basis, const Handles& handles,
                                       const Eigen::VectorXd& weights, double pull);

struct SimulationStepStats {
  int substeps = 0;
  int iterations = 0;     // BFGS iterations, all substeps
  int evaluations = 0;    // evaluations of Φ, all substeps
  bool converged = true;  // every substep's minimisation converged (bfgs.h)
  bool stalled = false;   // a substep's BFGS could not decrease Φ (its state was still taken)
  int line_search_failures = 0;
  int implicit_euler = 0;     // substeps taken by implicit Euler instead (violent steps)
  double energy_removed = 0;  // energy the energy correction took from the motion, all substeps
  double energy_added = 0;    // energy the energy correction gave to the motion, all substeps
  double ms = 0;              // wall time of the step, milliseconds
};

// The fields of SimulationStepStats by name (Simulation.stats in Python).
template <typename Visit>
void for_each_simulation_stat(Visit&& visit) {
  visit("substeps", [](auto& s) -> auto& { return s.substeps; });
  visit("iterations", [](auto& s) -> auto& { return s.iterations; });
  visit("evaluations", [](auto& s) -> auto& { return s.evaluations; });
  visit("converged", [](auto& s) -> auto& { return s.converged; });
  visit("stalled", [](auto& s) -> auto& { return s.stalled; });
  visit("line_search_failures", [](auto& s) -> auto& { return s.line_search_failures; });
  visit("implicit_euler", [](auto& s) -> auto& { return s.implicit_euler; });
  visit("energy_removed", [](auto& s) -> auto& { return s.energy_removed; });
  visit("energy_added", [](auto& s) -> auto& { return s.energy_added; });
  visit("ms", [](auto& s) -> auto& { return s.ms; });
}

class ReducedDynamics {
 public:
  // basis: validated (validate_basis), must outlive the simulation. handles: fine vertex indices
  // (checked_handle_weights; may be empty: a free body), weights one per handle (empty: 1).
  // Starts at rest (q = v = 0) with identity transforms. Throws InputError when the basis has no
  // flexible mode to set the period by.
  // rig: null, or #V by #bones skinning weights (check_skinning_weights): the simulation on a rig
  // (the header says what changes).
  ReducedDynamics(const Basis& basis, const Handles& handles, const VectorRef& weights,
                  const SimulationOptions& options, EnergyKind energy = EnergyKind::kShells,
                  const SkinningWeights* rig = nullptr);
  ReducedDynamics(const ReducedDynamics&) = delete;
  ReducedDynamics& operator=(const ReducedDynamics&) = delete;

  // Advances one frame, the controllers reaching `transforms` (one rigid 4 by 4 per handle,
  // check_transforms) at its end.
  //
  // BFGS's memory: Φ changes from substep to substep and from frame to frame by linear terms
  // and by the ghost energy's curvature along the motion, so what BFGS learnt of the curvature
  // (its inverse Hessian) serves the next minimisations better than the rest Hessian it starts
  // from. A step uses what the steps since the memory was last forgotten learnt, and forgets it
  // first when it holds memory_frames frames: a frame is a function of the state it starts from
  // and of the frames its memory holds, which a caller reproduces bit for bit by forgetting at
  // fixed blocks of memory_frames frames and, to reach a frame in the middle of a block, stepping
  // again from the block's first state (playback.Player.next).
  //
  // On a rig, `bones` are the bones' world skinning matrices at the frame's end (one per bone,
  // check_bone_matrices; required there, refused without a rig).
  SimulationStepStats step(const Transforms& transforms, const Transforms& bones = {});
  // Forgets BFGS's memory: the next step learns from the rest Hessian.
  void forget();
  // The frames stepped since the memory was last forgotten (at most memory_frames).
  int remembered_frames() const { return remembered_frames_; }
  int memory_frames() const { return options_.memory_frames; }

  // The state: q (r) and v = dq/dt (r, per second); transforms: the controllers' at this state
  // (one per handle; empty keeps the current ones). Throws InputError for a wrong size, a
  // non-finite entry or a q whose ghost leaves the coordinates the energies take. Forgets BFGS's
  // memory unless the state is the simulation's own (the same q, v and transforms).
  //
  // On a rig, rig_previous and rig_current: the bones at the frame before the state and at the
  // state; rig_current alone (rig_previous empty): the rig still in that pose until the state;
  // both empty: no history, the next step takes the rig as still in the pose it is given (as a
  // fresh simulation's first), so the frames from (q, v, transforms) are the same bits whatever
  // was stepped before. The rig's history is part of what makes the state the simulation's own.
  void set_state(const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                 const Transforms& transforms = {}, const Transforms& rig_previous = {},
                 const Transforms& rig_current = {});
  const Eigen::VectorXd& q() const { return q_; }
  const Eigen::VectorXd& v() const { return v_; }
  // On a rig: the bones at the frame before the state and at the state (empty until the rig is
  // first given and after a set_state without bones: the next step takes it as still in the pose
  // it is given).
  const Transforms& rig_previous() const { return rig_previous_; }
  const Transforms& rig_current() const { return rig_current_; }
  bool on_rig() const { return rig_ != nullptr; }
  int num_bones() const { return rig_ ? rig_->num_bones() : 0; }

  // H = ½ρ‖v‖² + E(q) + E_C(q) at the current transforms (normalised frame).
  double energy() const { return kinetic_energy() + potential_; }
  double kinetic_energy() const { return 0.5 * mass_scale_ * v_.squaredNorm(); }
  double potential_energy() const { return potential_; }

  // x̄ + U q on the fine mesh, written into `out` (FinePositions::write).
  void positions(Eigen::Ref<Eigen::VectorXf> out) const { fine_positions_.write(out); }
  // x̄ + U q for another q (a cached frame's), the state left alone. Throws InputError for a q of
  // the wrong size.
  void positions_of(const Eigen::VectorXd& q, Eigen::Ref<Eigen::VectorXf> out) const;
  // U q alone for a q (FinePositions::write_displacement): on a rig, the offset shown before the
  // Armature modifier, written without reading x̄. Throws InputError as positions_of.
  void displacement_of(const Eigen::VectorXd& q, Eigen::Ref<Eigen::VectorXf> out) const;

  int dimension() const { return ghost_energy_.dimension(); }
  int num_handles() const { return static_cast<int>(centres_.size()); }
  double mass_scale() const { return mass_scale_; }  // ρ
  // λ₁'s unit eigenvector of K (on a rig: of K plus the handles' term).
  const Eigen::VectorXd& lowest_mode() const { return lowest_mode_; }
  // On a rig, the last frame's g (rig_forces.h), per second squared.
  const Eigen::VectorXd& rig_acceleration() const { return rig_acceleration_; }

 private:
  // Throws InputError for a q of the wrong size.
  void check_coordinates(const Eigen::VectorXd& q) const;
  // Φ (above) for the current substep and scheme: ½‖x − prediction‖² + potential_weight
  // (damping_weight V(x) − damping_pullᵀx), V = E + E_C.
  double incremental_potential(const Eigen::VectorXd& x, Eigen::VectorXd& gradient);
  // The same with E(x) and ∇E(x) given.
  double incremental_potential(const Eigen::VectorXd& x, double elastic_energy,
                               const Eigen::VectorXd& elastic_gradient, Eigen::VectorXd& gradient);
  // The inverse of I + potential_weight damping_weight (K + 2A): Φ's Hessian at rest.
  Eigen::MatrixXd inverse_rest_hessian(const Eigen::MatrixXd& K, double potential_weight,
                                       double damping_weight) const;
  // Minimises the current Φ with `bfgs` from q_n, ending as `finish` says (bfgs.h), adding to
  // `stats`; `started`: bfgs has minimised this scheme's Φ since the memory was last forgotten.
  void minimize(Bfgs& bfgs, bool& started, const Eigen::MatrixXd& initial_inverse_hessian,
                Finish finish, SimulationStepStats& stats);
  // Transforms at fraction a of the way from start_ to target (per handle).
  Transforms interpolated(const Transforms& target, double a) const;
  void substep(const Transforms& start, const Transforms& middle, const Transforms& end,
               SimulationStepStats& stats);

  const Basis& basis_;
  SimulationOptions options_;
  GhostEnergy ghost_energy_;  // E(q)
  ReducedHandleTerm handle_term_;
  std::vector<Eigen::Vector3d> centres_;  // each handle's rest centre (interpolation)
  Transforms transforms_;                 // the controllers' at the current state
  FinePositions fine_positions_;

  double mass_scale_ = 0, rayleigh_ = 0, h_ = 0;  // ρ, β (seconds), the substep (seconds)
  Eigen::VectorXd lowest_mode_;
  // The midpoint rule's Φ (κ = h²/(4ρ)) and implicit Euler's (h²/ρ): weight, inverse Hessian at
  // rest, minimiser.
  double midpoint_weight_ = 0, euler_weight_ = 0;
  Eigen::MatrixXd midpoint_inverse_hessian_, euler_inverse_hessian_;
  Bfgs midpoint_bfgs_, euler_bfgs_;
  bool midpoint_started_ = false, euler_started_ = false;
  int remembered_frames_ = 0;

  // State: q, v, E(q) + E_C(q), E(q), ∇E(q).
  Eigen::VectorXd q_, v_, elastic_gradient_;
  double potential_ = 0, elastic_energy_ = 0;
  // The current Φ's terms: the prediction (q_n + (h/2) v_n for the midpoint rule), the damping
  // term's pull ((2β/h) ∇V(q_n, t_n)) and the weights (κ, 1 + 2β/h).
  Eigen::VectorXd prediction_, damping_pull_;
  double damping_weight_ = 1, potential_weight_ = 0;
  // On a rig: its forces, the bones at the frame before the state and at the state, and the
  // current frame's g (zero without a rig).
  std::unique_ptr<RigForces> rig_;
  Transforms rig_previous_, rig_current_;
  Eigen::VectorXd rig_acceleration_;
  // Work space, sized once.
  Eigen::VectorXd work_gradient_, handle_gradient_;
};

}  // namespace modal_deform
