// Physics in-betweens (spacetime constraints: Hildebrandt et al. 2012; Schulz et al. 2014): the
// animator keys where handles must be at a few frames, and the motion between is the one that
// needs the least control force to hit those keys under Simulation's dynamics, in the same basis,
// mass scale ρ, Rayleigh damping β and midpoint rule (reduced_dynamics.h).
//
// Unknowns: q_1 … q_N, the reduced states at every substep boundary (node) from the first key
// (node 0, q_0 fixed) to the last (node N = (last − first frame) · substeps). Each substep n is
// the midpoint rule's: with x_n = (q_n + q_{n+1})/2 and the substep's force
//   F_n = (1 + 2β/h) ∇V(x_n) − (2β/h) ∇V(q_n)    (V = E + E_C of the handles never keyed)
// (Φ's stationarity, reduced_dynamics.h), a free substep leaves node n with velocity
// v_n⁻ = (q_{n+1} − q_n)/h + (h/2ρ) F_n and reaches node n+1 with v_{n+1}⁺ = (q_{n+1} − q_n)/h −
// (h/2ρ) F_n. The control is an impulse at each node, the jump ρ(v_n⁻ − v_n⁺) (v_0⁺ = 0: the motion
// starts at rest); in h²/ρ units
//   R_0 = q_1 − q_0 + (h²/2ρ) F_0,   R_n = q_{n+1} − 2q_n + q_{n−1} + (h²/2ρ)(F_{n−1} + F_n),
// i.e. (h²/ρ) times the midpoint equation's control force averaged over the two substeps at the
// node: ∇Φ at each substep is its control force, and the midpoint rule reads one only through
// such sums. The problem:
//   minimise ½ Σ_{n<N} ‖R_n‖² + ½ w Σ_keys P_key(q at the key)
// ‖·‖ the mass metric's (the reduced mass is ρI). P_key is a penalty on each keyed handle's rigid
// fit: the squared mass-metric norm of the rigid part (translation and rotation moments about the
// target's centroid) of its vertices' miss x̄_i + U_i q − T x̄_i, zero when the fit is T to first
// order, whatever the handle's own deformation (which stays the physics'); w makes it outweigh
// the motion's own terms at the key node by kKeyDominance, so the keys are met well within
// posing's precision (which trades its handle term against the energy). A keyed handle acts only
// at its keys; a handle never keyed is a spring at the identity throughout (in V).
//
// A free motion of Simulation needs no impulse and meets keys taken as its handles' rigid fits:
// R = 0 and P = 0, and the solve reproduces it where Simulation's energy correction (a rescaling
// of the end velocity, not smooth) does nothing, i.e. where the energy is quadratic over a substep
// (small motions; bench: the reproduction error). The in-betweens measure the control on the
// midpoint equation alone.
//
// Solved by L-BFGS over all nodes at once (a quasi-Newton method on the whole motion), its initial
// inverse Hessian the inverse of a Gauss-Newton matrix: that of the dynamics linearised along the
// motion (each substep's ∇²V interpolated in time between the ∇²V at its keys' static poses, by
// differences of ghost gradients) plus the keys' penalty and a least curvature (kProximity),
// block-banded in time (r by r blocks, two either side of the diagonal), built and factored once
// by a banded block Cholesky. The gradient is exact (∇²V products by differences of ghost
// gradients) and a backtracking line search keeps each step a descent; the pairs learn how the
// curvature departs from the model's. Starting guess: the static poses at the keys (posing's
// minima) interpolated linearly per coordinate. Cost, N = frames × substeps: O(N r³) once for the
// model (and r + 1 ghost gradients a key); an iteration O(N) ghost gradients (4 a substep with
// damping, 2 without, each O(#ghost vertices · r)) and O(N r²) for the banded solve and the
// pairs. Small motions converge in tens of iterations; large ones (the bench's dragon, its head
// swung through 50°) converge linearly and slowly, not within 100 (bench/results/inbetween.json),
// and the alternatives measured cost more ghost gradients for the same control: the model rebuilt
// from ∇²V at every node along the motion saves iterations, but its steps still backtrack (the
// objective departs from any Gauss-Newton model within a step); a truncated Newton method
// (conjugate gradients on the exact Hessian, its products differences of gradients, the model as
// preconditioner) needs many products a step. Nor is the start what limits them: the linearised
// problem through the keys solved exactly (a wiggly spline) needs orders of magnitude more
// control than the linear interpolation. The nodes' ghost gradients are independent given the
// states: each objective and gradient evaluates them in parallel, in fixed runs of consecutive
// nodes on ghost energies of their own, and sums in node order (the same bits for any thread
// count).
//
// Before the first key the motion holds the static pose of that key (ReducedSolver's minimum with
// the handles keyed there at their transforms, the never-keyed at the identity, the others free)
// at rest; after the last key it is Simulation's from the state reached there, each keyed handle a
// spring at its last keyed transform, the never-keyed at the identity: frames are stepped in order
// from there and cached, so a frame is the same bits however it is reached.
//
// Not thread-safe: one in-between per thread.
#pragma once

#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "solve/reduced_dynamics.h"

namespace modal_deform {

// One key: a frame ≥ 0 and, per handle, its rigid transform there or none (not keyed there).
struct InbetweenKey {
  int frame = 0;
  std::vector<std::optional<Eigen::Matrix4d>> transforms;
};

// The most keys, and the longest span from the first key to the last, in frames: the unknowns
// are (span × substeps) states of r coordinates.
constexpr int kMaxInbetweenKeys = 100;
constexpr int kMaxInbetweenFrames = 10000;
// The latest frame that positions() and state() take (Simulation steps there from the last key).
constexpr int kMaxInbetweenFrame = 1000000;

struct InbetweenOptions {
  SimulationOptions simulation;  // the dynamics, and Simulation's after the last key
  int solve_iterations = 100;    // L-BFGS iterations at most
  double solve_tolerance = 1e-5;
};

// The options as the Python API takes them: Simulation's (the same names and meanings) and the
// solve's.
template <typename Visit>
void for_each_inbetween_option(Visit&& visit) {
  for_each_simulation_option([&](const Option& option, auto field) {
    visit(option, [field](auto& o) -> auto& { return field(o.simulation); });
  });
  visit(Option{"solve_iterations", "Quasi-Newton iterations over the whole motion at most.",
               at_least(1)},
        [](auto& o) -> auto& { return o.solve_iterations; });
  visit(Option{"solve_tolerance",
               "The solve has converged when a full quasi-Newton step moves no reduced "
               "coordinate by more than this (normalised frame: the mesh about unit size).",
               between_open(0, 1)},
        [](auto& o) -> auto& { return o.solve_tolerance; });
}

struct InbetweenStats {
  // The last step met solve_tolerance, or no step decreases the objective any more and it is
  // below kFloor (inbetween.cpp) of the starting guess's: as low as the differenced gradient lets
  // it go.
  bool converged = false;
  bool stalled = false;        // the line search found no decrease before convergence
  int iterations = 0;          // L-BFGS iterations
  int evaluations = 0;         // ghost gradients, posing's excepted
  int nodes = 0;               // N: substeps from the first key to the last
  double control = 0;          // ½ Σ ‖R_n‖² at the end
  double initial_control = 0;  // the same for the starting guess
  double ms = 0;               // wall time of solve(), milliseconds
};

template <typename Visit>
void for_each_inbetween_stat(Visit&& visit) {
  visit("converged", [](auto& s) -> auto& { return s.converged; });
  visit("stalled", [](auto& s) -> auto& { return s.stalled; });
  visit("iterations", [](auto& s) -> auto& { return s.iterations; });
  visit("evaluations", [](auto& s) -> auto& { return s.evaluations; });
  visit("nodes", [](auto& s) -> auto& { return s.nodes; });
  visit("control", [](auto& s) -> auto& { return s.control; });
  visit("initial_control", [](auto& s) -> auto& { return s.initial_control; });
  visit("ms", [](auto& s) -> auto& { return s.ms; });
}

class Inbetween {
 public:
  // basis: validated, must outlive this. handles: fine vertex indices, weights one per handle
  // (empty: 1), as Simulation's. keys: at least one, at most kMaxInbetweenKeys, at distinct frames
  // in [0, kMaxInbetweenFrame] spanning at most kMaxInbetweenFrames, in any order; each with one
  // entry per handle, rigid where given (check_transforms), keying at least one handle. Throws
  // InputError naming what is wrong.
  Inbetween(const Basis& basis, const Handles& handles, const VectorRef& weights,
            std::vector<InbetweenKey> keys, const InbetweenOptions& options,
            EnergyKind energy = EnergyKind::kShells);
  ~Inbetween();
  Inbetween(const Inbetween&) = delete;
  Inbetween& operator=(const Inbetween&) = delete;

  // Solves the whole motion (the header says how); again after a solve, the same bits.
  InbetweenStats solve();
  bool solved() const { return solved_; }

  // The state at `frame` in [0, kMaxInbetweenFrame]: q and v (per second). Solves first if
  // solve() has not run; beyond the last key, steps Simulation up to the frame once.
  void state(int frame, Eigen::VectorXd& q, Eigen::VectorXd& v);
  // x̄ + U q at `frame`, written into `out` (FinePositions::write).
  void positions(int frame, Eigen::Ref<Eigen::VectorXf> out);

  int dimension() const { return simulation_->dimension(); }
  int num_handles() const { return num_handles_; }
  int first_frame() const { return keys_.front().frame; }
  int last_frame() const { return keys_.back().frame; }
  double mass_scale() const { return parameters_.mass_scale; }

 private:
  class Problem;

  // The state at frame ≥ last_frame(), from the cache, stepping Simulation as far as needed.
  const std::pair<Eigen::VectorXd, Eigen::VectorXd>& after(int frame);
  // Posing's minimum for `key` (the header says which handles hold it).
  Eigen::VectorXd static_pose(const InbetweenKey& key) const;

  const Basis& basis_;
  Handles handles_;
  int num_handles_;
  Eigen::VectorXd weights_;
  std::vector<InbetweenKey> keys_;  // by frame
  InbetweenOptions options_;
  EnergyKind energy_;
  DynamicsParameters parameters_;
  std::unique_ptr<Problem> problem_;
  // Simulation after the last key: its handles' transforms there, the states it has stepped
  // (frame last_frame() + i), and the map to the fine mesh it holds.
  std::unique_ptr<ReducedDynamics> simulation_;
  Transforms last_transforms_;
  std::vector<std::pair<Eigen::VectorXd, Eigen::VectorXd>> after_;
  bool solved_ = false;
  // The solved nodes' states (q_n, v_n⁺), node 0 the first key's.
  std::vector<Eigen::VectorXd> q_, v_;
  InbetweenStats stats_;
};

}  // namespace modal_deform
