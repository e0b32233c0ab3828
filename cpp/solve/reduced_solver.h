// The interactive solver (paper section 5): BFGS in the reduced space x = x̄ + U q, with the
// energy evaluated on the ghost and the handle term exact on the fine mesh:
//
//   f(q) = E_ghost(s (x̄_s + U_s q)) + E_C(q)        (normalised frame, s = basis.scale)
//
// An iteration costs O(#ghost vertices · r) + O(r²), whatever the size of the fine mesh; only
// positions() touches the fine mesh. Warm start (paper): BFGS's initial inverse Hessian is the
// inverse of the reduced Hessian of f at rest, regularised where motions are free. The objective's
// terms and the regularisation: docs/design.md, "The reduced solver".
//
// Not thread-safe: one solver per thread.
#pragma once

#include <limits>
#include <memory>

#include "basis/basis.h"
#include "energy/make_energy.h"
#include "solve/bfgs.h"
#include "solve/handle_term.h"
#include "solve/reduced_map.h"

namespace modal_deform {

struct ReducedSolveStats {
  int iterations = 0;            // BFGS steps of this call
  int evaluations = 0;           // evaluations of f and ∇f by this call
  double energy = 0;             // f(q) at the end: deformation energy plus handle term
  double gradient_norm = 0;      // ‖∇f(q)‖
  bool converged = false;        // the stopping test holds (bfgs.h)
  bool stalled = false;          // not converged, and no step decreases f (BfgsResult::stalled)
  int line_search_failures = 0;  // line searches of this call that found no decrease
  double ms = 0;                 // wall time of the call, milliseconds
};

// The fields of ReducedSolveStats by name (the Python API's stats dict): visit(name, field) with
// `field` an accessor s -> s.member.
template <typename Visit>
void for_each_reduced_solve_stat(Visit&& visit) {
  visit("iterations", [](auto& s) -> auto& { return s.iterations; });
  visit("energy", [](auto& s) -> auto& { return s.energy; });
  visit("converged", [](auto& s) -> auto& { return s.converged; });
  visit("ms", [](auto& s) -> auto& { return s.ms; });
  visit("evaluations", [](auto& s) -> auto& { return s.evaluations; });
  visit("gradient_norm", [](auto& s) -> auto& { return s.gradient_norm; });
  visit("stalled", [](auto& s) -> auto& { return s.stalled; });
  visit("line_search_failures", [](auto& s) -> auto& { return s.line_search_failures; });
}

// The solver's options as the Python API takes them (option.h): visit(option, field) with `field`
// an accessor o -> o.member.
struct ReducedSolverOptions {
  double pull = kDefaultPull;
  EnergyKind energy = EnergyKind::kShells;
  bool warm_start = true;
};

template <typename Visit>
void for_each_reduced_solver_option(Visit&& visit) {
  visit(kPull, [](auto& o) -> auto& { return o.pull; });
  visit(
      Option{
          "energy",
          "The energy evaluated on the ghost: \"shells\" (with the basis's material) or \"arap\"."},
      [](auto& o) -> auto& { return o.energy; });
  visit(Option{"warm_start",
               "Start BFGS from the inverse of the reduced rest Hessian (the paper's warm start); "
               "False starts it "
               "from the identity, for comparison."},
        [](auto& o) -> auto& { return o.warm_start; });
}

// What one solve() may spend: a pose tick's share of a frame, or a Solve's iterations.
struct ReducedSolveOptions {
  int max_iterations = 10;
  double tolerance = 1e-6;
  double budget_ms = std::numeric_limits<double>::infinity();
};

template <typename Visit>
void for_each_reduced_solve_option(Visit&& visit) {
  visit(Option{"max_iterations", "BFGS iterations at most.", at_least(0)},
        [](auto& o) -> auto& { return o.max_iterations; });
  visit(Option{"tolerance", "ε of the Gill-Murray-Wright stopping test (paper eq. 14).",
               between_open(0, 1)},
        [](auto& o) -> auto& { return o.tolerance; });
  visit(Option{"budget_ms",
               "No iteration begins once this many milliseconds have passed (the one under way is "
               "finished, so a "
               "call always progresses); None: no limit.",
               above_up_to(0, std::numeric_limits<double>::infinity())},
        [](auto& o) -> auto& { return o.budget_ms; });
}

class ReducedSolver {
 public:
  // basis: validated here (validate_basis); it must outlive the solver, which keeps a reference
  // to its fine arrays. handles, weights: see checked_handle_weights (fine vertex indices; empty
  // weights mean 1), inside the basis's region if it has one (require_handles_in_region).
  // stiffness: μ > 0. energy: evaluated on the ghost. warm_start false starts BFGS from the
  // identity instead of the rest Hessian (for comparison). The solver starts at rest with identity
  // transforms.
  ReducedSolver(const Basis& basis, const Handles& handles, const VectorRef& weights,
                double stiffness, EnergyKind energy = EnergyKind::kShells, bool warm_start = true);
  // The same with the options of a table (checked).
  ReducedSolver(const Basis& basis, const Handles& handles, const VectorRef& weights,
                const ReducedSolverOptions& options)
      : ReducedSolver(basis, handles, weights, options.pull, options.energy, options.warm_start) {}
  ReducedSolver(const ReducedSolver&) = delete;
  ReducedSolver& operator=(const ReducedSolver&) = delete;

  // One rigid 4 by 4 transform per handle, applied to its rest positions (check_transforms).
  // O(r) per handle; the next solve continues from the current q and inverse Hessian.
  void set_transforms(const Transforms& transforms);

  // Up to max_iterations ≥ 0 BFGS iterations with stopping tolerance ε in (0, 1), none begun after
  // budget_ms milliseconds (Bfgs::minimize): a pose tick calls it once per frame.
  ReducedSolveStats solve(int max_iterations, double tolerance,
                          double budget_ms = std::numeric_limits<double>::infinity());
  // The same with the options of a table, checked (InputError naming the one out of range).
  ReducedSolveStats solve(const ReducedSolveOptions& options);

  // Back to rest (q = 0) and the initial inverse Hessian; the transforms stay.
  void reset();

  // x̄ + U q on the fine mesh, written into `out` (FinePositions::write). The map's 16-bit vectors
  // are made at the first call: a solver that only solves (a cache's static poses, played through
  // a simulation's map) never holds them.
  void positions(Eigen::Ref<Eigen::VectorXf> out) const;

  // f(q) with ∇f(q) (r) written into `gradient`; +inf where a ghost coordinate leaves the range
  // the energies take (kMaxCoordinate).
  double objective(const Eigen::VectorXd& q, Eigen::VectorXd& gradient);

  const Eigen::VectorXd& q() const { return bfgs_.x(); }
  int dimension() const { return ghost_energy_.dimension(); }
  int num_handles() const { return num_handles_; }

 private:
  const Basis& basis_;
  int num_handles_;
  GhostEnergy ghost_energy_;
  ReducedHandleTerm handle_term_;
  Eigen::MatrixXd initial_inverse_hessian_;
  Bfgs bfgs_;
  mutable std::unique_ptr<FinePositions> fine_positions_;  // made by the first positions()
  // Work space, sized once.
  Eigen::VectorXd handle_gradient_, handle_gradient_old_;
};

}  // namespace modal_deform
