// The reference solve: Newton's method on the full mesh for the reduced solver's objective, to
// measure how far the reduced answer is from the true minimiser and to polish a pose on the full
// mesh (Refine, refine.h). In the normalised frame y = s x (s = normalizing_scale(V)):
//
//   F(y) = E(y) + μ Σ_h w_h Σ_{i∈h} s²m_i ‖y_i − s (R_h x̄_i + t_h)‖²
//
// The pieces: the objective (pose_objective.h), a start's stretched vertices relaxed first
// (relax_stretched.h), Newton on the shifted Hessian (shifted_newton.h), load steps from rest
// (load_steps.h). A solve that stops on a kink of F rather than a minimum reports that it did not
// converge. Why each piece: docs/design.md, "The full solve".
#pragma once

#include <vector>

#include "energy/make_energy.h"
#include "solve/handle_term.h"
#include "solve/shifted_newton.h"
#include "util/progress.h"
#include "util/types.h"

namespace modal_deform {

struct FullSolveOptions {
  EnergyKind energy = EnergyKind::kShells;
  Material material =
      {};  // the shells weights and their painting (ignored by ARAP, which takes no paint)
  // In (0, 1): the factor by which ‖∇F‖ must drop below the larger of its values at rest and at
  // `initial` at the full load.
  double tolerance = 1e-8;
  // ≥ 0: Newton iterations at most, all load steps together. Strong poses of scans need hundreds
  // while F falls steadily (triangles on the inside of a bend are crushed one after another, each
  // cutting a step): bench/results/refine.json, the 23k dragon's bend.
  int max_iterations = 1000;
  // Called as ("solve", fraction done) at most every 0.1 s; returning false cancels (Cancelled).
  ProgressCallback progress = nullptr;
  // Vertices held exactly where the solve starts (at rest, or at `initial`): a region bake's
  // outside, which Refine keeps still. Their coordinates leave the unknowns.
  std::vector<int> held = {};
};

// The options as the Python API takes them (option.h), with their defaults from
// FullSolveOptions{} (the callback apart): visit(option, field) with `field` an accessor
// o -> o.member. The pull μ is solve_full's argument (kPull).
template <typename Visit>
void for_each_full_solve_option(Visit&& visit) {
  visit(Option{"energy", "The deformation energy: \"shells\" or \"arap\"."},
        [](auto& o) -> auto& { return o.energy; });
  for_each_material_option(visit);
  visit(Option{"tolerance",
               "Stops when the gradient norm is below this fraction of its value at rest (or at "
               "`initial`, if "
               "larger).",
               between_open(0, 1)},
        [](auto& o) -> auto& { return o.tolerance; });
  visit(
      Option{"max_iterations", "Newton iterations at most, all load steps together.", at_least(0)},
      [](auto& o) -> auto& { return o.max_iterations; });
  visit(Option{"held",
               "Vertex indices held exactly where the solve starts (at rest, or at `initial`), as "
               "a region bake's "
               "outside is; None holds none."},
        [](auto& o) -> auto& { return o.held; });
}

struct FullSolveResult {
  RowMatrixX3d positions;     // #V by 3, mesh units
  int steps = 0;              // load steps
  int iterations = 0;         // Newton steps, all load steps together
  int factorizations = 0;     // numeric factorisations, failed ones (τ too small) included
  double energy = 0;          // F at the result: deformation energy plus handle term
  double gradient_norm = 0;   // ‖∇F‖ at the result (normalised frame)
  double gradient_scale = 0;  // the larger ‖∇F‖ at rest and at `initial`: the tolerance's unit
  double initial_energy = 0;  // F at the start (rest, or `initial`) under the full transforms
  int relaxed_vertices = 0;   // vertices of `initial` relaxed before Newton (relax_stretched.h)
  double seconds = 0;         // wall time of the solve
  bool converged = false;     // gradient_norm ≤ tolerance · gradient_scale at the full load
  bool stalled = false;       // stopped because F no longer decreased (not converged)
  std::vector<NewtonIteration> history;  // every Newton iteration, all load steps together
};

// The scalar fields of a FullSolveResult by name (the Python API's stats; positions and history
// apart): visit(name, field) with `field` an accessor r -> r.member.
template <typename Visit>
void for_each_full_solve_stat(Visit&& visit) {
  visit("steps", [](auto& r) -> auto& { return r.steps; });
  visit("iterations", [](auto& r) -> auto& { return r.iterations; });
  visit("energy", [](auto& r) -> auto& { return r.energy; });
  visit("converged", [](auto& r) -> auto& { return r.converged; });
  visit("gradient_norm", [](auto& r) -> auto& { return r.gradient_norm; });
  visit("gradient_scale", [](auto& r) -> auto& { return r.gradient_scale; });
  visit("factorizations", [](auto& r) -> auto& { return r.factorizations; });
  visit("initial_energy", [](auto& r) -> auto& { return r.initial_energy; });
  visit("relaxed_vertices", [](auto& r) -> auto& { return r.relaxed_vertices; });
  visit("seconds", [](auto& r) -> auto& { return r.seconds; });
  visit("stalled", [](auto& r) -> auto& { return r.stalled; });
}

// V: #V by 3 rest positions, F: #F by 3 triangles (validate_mesh); handles and weights as in
// checked_handle_weights; transforms: one rigid 4 by 4 transform per handle (check_transforms);
// stiffness μ > 0. Starts at rest in load steps, or at `initial` (#V by 3, mesh units) when given,
// in a single load step (Refine: the reduced pose, or an animation's previous frame). Throws
// InputError for bad input, Cancelled when options.progress says stop, and NumericalError when
// no shift makes the Hessian factorisable. Non-convergence (the iteration budget spent, or F no
// longer decreasing at working precision) is reported in the result, not thrown. Runs
// single-threaded but for CHOLMOD's BLAS and the energy's own threads.
FullSolveResult solve_full(const VerticesRef& V, const FacesRef& F, const Handles& handles,
                           const VectorRef& weights, const Transforms& transforms, double stiffness,
                           const FullSolveOptions& options = {},
                           const RowMatrixX3d* initial = nullptr);

}  // namespace modal_deform
