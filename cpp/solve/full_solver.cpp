#include "solve/full_solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "mesh/mesh_check.h"
#include "solve/load_steps.h"
#include "solve/pose_objective.h"
#include "solve/relax_stretched.h"
#include "solve/shifted_newton.h"
#include "util/errors.h"
#include "util/require_positions.h"
#include "util/require_weight.h"

namespace modal_deform {
namespace {

// Intermediate loads need only be near their minimum: the next load's Newton steps start there.
constexpr double kIntermediateTolerance = 1e-3;
// Newton iterations an intermediate load step may take before the path moves on regardless.
constexpr int kIterationsPerIntermediateStep = 20;
// Newton uses the exact Hessian once ‖∇F‖ is below this fraction of its scale (quadratic
// convergence near the minimum), the projected one above it (each element's Hessian made
// semidefinite: a sliver hinge bent far from rest is strongly indefinite, and the shift that
// would make the exact Hessian definite damps the whole mesh, so iterations creep).
constexpr double kExactHessianBelow = 1e-3;

// The checks solve_full makes before any work; returns the handles' weights.
Eigen::VectorXd checked_input(const VerticesRef& V, const FacesRef& F, const Handles& handles,
                              const VectorRef& weights, const Transforms& transforms,
                              double stiffness, const FullSolveOptions& options,
                              const RowMatrixX3d* initial) {
  validate_mesh(V, F);  // before the handles, which index into it
  const int n = static_cast<int>(V.rows());
  Eigen::VectorXd handle_weights = checked_handle_weights(handles, weights, n);
  check_transforms(transforms, static_cast<int>(handles.size()));
  check_option(kPull, stiffness);
  check_options(options, [](auto visit) { for_each_full_solve_option(visit); });
  if (initial) require_positions(flatten(*initial), 3 * n, "initial");
  for (size_t i = 0; i < options.held.size(); ++i)
    if (options.held[i] < 0 || options.held[i] >= n)
      throw InputError(
          message("held[", i, "] = ", options.held[i], " is not a vertex (0 to ", n - 1, ")"));
  return handle_weights;
}

// F and ∇F at y under the objective's current transforms.
void evaluate(const PoseObjective& objective, NewtonPoint& point) {
  point.value = objective(point.y, point.gradient);
}

// The predictor of a load step: the point moved on along the path the last load step took, by
// `ratio` times that step, y_previous → y. Kept when F is lower there.
void extrapolate(const PoseObjective& objective, double ratio, const Eigen::VectorXd& y_previous,
                 NewtonPoint& point) {
  NewtonPoint guess{point.y + ratio * (point.y - y_previous), 0, Eigen::VectorXd(point.y.size())};
  evaluate(objective, guess);
  if (guess.value < point.value) std::swap(point, guess);
}

// The share of the progress bar that the load path takes, when there is one.
constexpr double kLoadPathShare = 0.5;

// Fraction of the work done for the progress bar: the load path first (when there is one), then
// the final load's gradient decrease on a log scale.
double fraction_done(double load, bool stepping, double gradient_norm, double scale,
                     double tolerance) {
  const double path = stepping ? kLoadPathShare * load : 0;
  if (load < 1) return path;
  const double decrease =
      std::log(std::max(gradient_norm / scale, tolerance)) / std::log(tolerance);
  return path + (stepping ? 1 - kLoadPathShare : 1.0) * std::clamp(decrease, 0.0, 1.0);
}

}  // namespace

FullSolveResult solve_full(const VerticesRef& V, const FacesRef& F, const Handles& handles,
                           const VectorRef& weights, const Transforms& transforms, double stiffness,
                           const FullSolveOptions& options, const RowMatrixX3d* initial) {
  const Eigen::VectorXd handle_weights =
      checked_input(V, F, handles, weights, transforms, stiffness, options, initial);
  const auto start = std::chrono::steady_clock::now();
  Progress progress(options.progress);
  progress.report("solve", 0);

  PoseObjective objective(V, F, handles, handle_weights, stiffness, options.energy,
                          options.material, options.held);
  const LoadPath path(V, handles, transforms);
  ShiftedNewton newton(objective);

  // The gradient's scale: the larger ‖∇F‖ under the full transforms at rest and at `initial`.
  FullSolveResult result;
  NewtonPoint point{objective.rest_positions(), 0, Eigen::VectorXd(3 * V.rows())};
  objective.set_transforms(transforms);
  evaluate(objective, point);
  result.gradient_scale = point.gradient.norm();
  if (initial) {
    point.y = objective.scale() * flatten(*initial);
    evaluate(objective, point);
    result.gradient_scale = std::max(result.gradient_scale, point.gradient.norm());
  }
  result.initial_energy = point.value;
  if (initial) result.relaxed_vertices = relax_stretched(objective, point);

  LoadSchedule schedule(!initial, path.suggested_steps());
  Eigen::VectorXd y_previous;  // the answer at the load before, for the predictor
  double done = 0;
  while (!schedule.done()) {
    const double next = schedule.next(result.iterations >= options.max_iterations);
    const bool final = next == 1;
    objective.set_transforms(path.at(next));
    evaluate(objective, point);
    if (schedule.previous_increment() > 0) {
      Eigen::VectorXd y_load = point.y;
      extrapolate(objective, (next - schedule.load()) / schedule.previous_increment(), y_previous,
                  point);
      y_previous.swap(y_load);
    } else if (schedule.stepping()) {
      y_previous = point.y;
    }
    const double target =
        (final ? options.tolerance : std::max(options.tolerance, kIntermediateTolerance)) *
        result.gradient_scale;
    const int left = options.max_iterations - result.iterations;
    const int budget = final ? left : std::min(kIterationsPerIntermediateStep, left);
    const int iterations = newton.minimize(
        point, target, budget, kExactHessianBelow * result.gradient_scale,
        [&](const NewtonPoint& now) {
          // ‖∇F‖ may rise for a step: the bar never goes back.
          done = std::max(done, fraction_done(next, schedule.stepping(), now.gradient.norm(),
                                              result.gradient_scale, options.tolerance));
          progress.report("solve", done);
        });
    result.iterations += iterations;
    ++result.steps;
    schedule.advance(next, iterations, point.gradient.norm() <= target);
  }
  progress.report("solve", 1);
  result.factorizations = newton.factorizations();
  result.energy = point.value;
  result.gradient_norm = point.gradient.norm();
  result.converged = result.gradient_norm <= options.tolerance * result.gradient_scale;
  result.stalled = !result.converged && newton.stalled();
  result.history = newton.history();
  result.positions =
      Eigen::Map<const RowMatrixX3d>(point.y.data(), V.rows(), 3) / objective.scale();
  // Held vertices are where they started to the last bit, not through the frame's scaling.
  const VerticesRef started_at = initial ? VerticesRef(*initial) : V;
  for (int v : options.held) result.positions.row(v) = started_at.row(v);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace modal_deform
