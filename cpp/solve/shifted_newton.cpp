#include "solve/shifted_newton.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "solve/line_search.h"
#include "util/errors.h"

namespace modal_deform {

ShiftedNewton::ShiftedNewton(const PoseObjective& objective)
    : objective_(objective), llt_(3), shift_(objective.smallest_shift()) {
  const Eigen::Index size = objective.mass_diagonal().size();
  step_.resize(size);
  trial_.y.resize(size);
  trial_.gradient.resize(size);
}

int ShiftedNewton::minimize(NewtonPoint& point, double target, int budget, double exact_below,
                            const std::function<void(const NewtonPoint&)>& after_iteration) {
  int iterations = 0, stalled = 0;
  while (iterations < budget && stalled < kMaxStalledIterations && point.gradient.norm() > target) {
    const bool near_minimum = point.gradient.norm() <= exact_below;
    stalled = iterate(point, near_minimum) ? 0 : stalled + 1;
    ++iterations;
    after_iteration(point);
  }
  stalled_ = stalled == kMaxStalledIterations;
  return iterations;
}

bool ShiftedNewton::iterate(NewtonPoint& point, bool near_minimum) {
  const bool try_exact = near_minimum && ++since_exact_failed_ > kRetryExactAfter;
  const bool exact = try_exact && try_factorize(objective_.hessian(point.y));
  if (try_exact && !exact) since_exact_failed_ = 0;
  if (!exact) factorize_shifted(objective_.projected_hessian(point.y));
  llt_.solve(point.gradient, step_);
  step_ = -step_;
  const double slope = point.gradient.dot(step_);
  const double noise = 1e-12 * (1 + std::abs(point.value));
  // A trial point that turns a triangle over counts as too far.
  const Objective within_smooth_part = [&](const Eigen::VectorXd& trial, Eigen::VectorXd& trial_gradient) {
    if (objective_.turns_a_triangle_over(point.y, trial)) return std::numeric_limits<double>::infinity();
    return objective_(trial, trial_gradient);
  };
  const BacktrackingResult search = backtracking_line_search(within_smooth_part, point.y, point.value, point.gradient,
                                                             step_, trial_.y, trial_.value, trial_.gradient, noise);
  // Cut only by the guard: every longer trial turned a triangle over (or left F's domain), none
  // fell short of the decrease.
  const bool guarded = search.step > 0 && search.step < 1 && search.insufficient == 0;
  const double ratio = search.step > 0 ? (point.value - trial_.value) / predicted_decrease(search.step, slope) : 0;
  NewtonIteration record{exact, shift_, search.step, guarded, ratio};
  update_shift(guarded ? 1 : search.step, ratio);
  if (search.step > 0) {
    record.progress =
        point.value - trial_.value > noise || trial_.gradient.norm() < 0.5 * point.gradient.norm();
    std::swap(point, trial_);
  }
  record.value = point.value;
  record.gradient_norm = point.gradient.norm();
  history_.push_back(record);
  return record.progress;
}

double ShiftedNewton::predicted_decrease(double alpha, double slope) const {
  // pᵀ∇²F p = −∇Fᵀp − τ pᵀDp, since (∇²F + τD)p = −∇F.
  const double curvature = -slope - shift_ * step_.dot(objective_.mass_diagonal().cwiseProduct(step_));
  return -alpha * slope - 0.5 * alpha * alpha * curvature;
}

void ShiftedNewton::update_shift(double cut, double ratio) {
  failed_shift_ /= 3;  // the Hessian changes: a shift too small a while ago may do now
  if (cut == 1) {
    shift_ = std::max({objective_.smallest_shift(), failed_shift_,
                       shift_ * std::max(0.1, 1 - std::pow(2 * ratio - 1, 3))});
    growth_ = 2;
  } else {
    // Too long a step: lean towards steepest descent. Where τD dominates the Hessian (the floppy
    // parts that made the step too long) the step shrinks as 1/τ, so τ grows at least by the
    // factor the line search cut the step by (from a poor start, τ must rise by ten orders of
    // magnitude, which doubling alone took ten iterations to reach).
    shift_ *= std::max(growth_, std::min(1 / cut, kMaxCutGrowth));
    growth_ = std::min(2 * growth_, kMaxGrowth);
  }
}

bool ShiftedNewton::try_factorize(const SparseMatrix& hessian) {
  ++factorizations_;
  try {
    // Not refused for CHOLMOD's cheap condition estimate: ∇²F + τD with τ > 0 is definite when it
    // factors, and on the 100k dragon the estimate fell below 1e-13 for every τ below 4 times its
    // floor. Refusing it held τ there, and the steps crept: Refine at turn 30 took 120 iterations
    // and 268 factorisations; without, 24 and 27 (79 s).
    llt_.factorize(hessian, objective_.constant_diagonal() + shift_ * objective_.mass_diagonal(), 0);
    return true;
  } catch (const NumericalError&) {
    return false;
  }
}

void ShiftedNewton::factorize_shifted(const SparseMatrix& hessian) {
  for (int attempt = 0; !try_factorize(hessian); ++attempt) {
    if (attempt == 60) throw NumericalError("solve_full: no shift of the Hessian could be factored");
    failed_shift_ = std::max(failed_shift_, shift_);
    shift_ *= 10;
  }
}

}  // namespace modal_deform
