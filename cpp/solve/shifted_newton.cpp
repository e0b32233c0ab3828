#include "solve/shifted_newton.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include "solve/line_search.h"
#include "util/errors.h"

namespace modal_deform {

ShiftedNewton::ShiftedNewton(const PoseObjective& objective)
    : objective_(objective), llt_(3), shift_(objective.smallest_shift()) {
  const Eigen::Index size = objective.mass_diagonal().size();
  for (Eigen::VectorXd* v :
       {&step_, &shifted_diagonal_, &residual_, &preconditioned_, &direction_, &product_})
    v->resize(size);
  for (NewtonPoint* p : {&trial_, &extended_}) {
    p->y.resize(size);
    p->gradient.resize(size);
  }
}

int ShiftedNewton::minimize(NewtonPoint& point, double target, int budget, double exact_below,
                            const std::function<void(const NewtonPoint&)>& after_iteration) {
  int iterations = 0, stalled = 0;
  previous_gradient_norm_ = 0;  // a new load: no forcing term from the last one's steps
  while (iterations < budget && stalled < kMaxStalledIterations && point.gradient.norm() > target) {
    const double gradient_norm = point.gradient.norm();
    stalled =
        iterate(point, gradient_norm <= exact_below, forcing(gradient_norm, target, exact_below))
            ? 0
            : stalled + 1;
    ++iterations;
    after_iteration(point);
  }
  stalled_ = stalled == kMaxStalledIterations;
  return iterations;
}

double ShiftedNewton::forcing(double gradient_norm, double target, double exact_below) const {
  // Eisenstat & Walker's choice 2, η = γ (‖∇F‖ / ‖∇F‖ before)^α with γ = 0.9, α = 2, and near the
  // minimum at most ‖∇F‖ / exact_below (η = O(‖∇F‖): Newton's quadratic convergence, Dembo,
  // Eisenstat & Steihaug 1982); at most kMaxForcing, and no tighter than reaching the target needs.
  const double ratio = previous_gradient_norm_ > 0 ? gradient_norm / previous_gradient_norm_ : 1;
  const double eta = std::min(0.9 * ratio * ratio, gradient_norm / exact_below);
  return std::min(kMaxForcing, std::max(eta, 0.5 * target / gradient_norm));
}

bool ShiftedNewton::iterate(NewtonPoint& point, bool near_minimum, double forcing) {
  previous_gradient_norm_ = point.gradient.norm();
  const bool try_exact = near_minimum && ++since_exact_failed_ > kRetryExactAfter;
  set_shifted_diagonal();
  // The exact Hessian by conjugate gradients, else factored; where it does not factor (not definite
  // at τ), the projected one the same way.
  bool exact = false;
  int cg_iterations = 0;
  if (try_exact) {
    objective_.hessian_into(point.y, false, hessian_);
    cg_iterations = factored_ ? solve_by_cg(hessian_, point.gradient, forcing) : 0;
    exact = cg_iterations > 0 || try_factorize(hessian_);
    if (!exact) since_exact_failed_ = 0;
  }
  if (!exact) {
    objective_.hessian_into(point.y, true, hessian_);
    cg_iterations = factored_ ? solve_by_cg(hessian_, point.gradient, forcing) : 0;
    if (cg_iterations == 0) factorize_shifted(hessian_);
  }
  if (cg_iterations == 0) {
    llt_.solve(point.gradient, step_);
    step_ = -step_;
  }
  const double slope = point.gradient.dot(step_);
  product_.noalias() = hessian_ * step_;
  const double curvature =
      step_.dot(product_) + step_.dot(objective_.constant_diagonal().cwiseProduct(step_));
  const double noise = kUnresolvableDecrease * (1 + std::abs(point.value));
  // The first trial stops short of the first triangle's turning point (an interior point method's
  // fraction to the boundary): halving from 1 lands anywhere between half of it and all of it. No
  // trial of the search turns a triangle over, so only extend() checks for it.
  const double initial_step =
      std::min(1.0, kToTurning * objective_.step_to_turning(point.y, step_));
  const BacktrackingResult search =
      backtracking_line_search(std::cref(objective_), point.y, point.value, point.gradient, step_,
                               trial_.y, trial_.value, trial_.gradient, noise, initial_step);
  // Cut only by the guard: every longer trial turned a triangle over (or left F's domain), none
  // fell short of the decrease.
  const bool guarded = search.step > 0 && search.step < 1 && search.insufficient == 0;
  const double ratio = search.step > 0 ? (point.value - trial_.value) /
                                             predicted_decrease(search.step, slope, curvature)
                                       : 0;
  NewtonIteration record{exact ? HessianModel::kExact : HessianModel::kProjected,
                         shift_,
                         search.step,
                         guarded,
                         ratio,
                         cg_iterations};
  update_shift(guarded ? 1 : search.step, ratio);
  if (search.step == 1 && ratio > kExtendAbove) {
    // A trial point beyond 1 that turns a triangle over counts as too far.
    record.step = extend(point, [&](const Eigen::VectorXd& trial, Eigen::VectorXd& trial_gradient) {
      if (objective_.turns_a_triangle_over(point.y, trial))
        return std::numeric_limits<double>::infinity();
      return objective_(trial, trial_gradient);
    });
  }
  if (search.step > 0) {
    record.progress =
        point.value - trial_.value > noise || trial_.gradient.norm() < 0.5 * point.gradient.norm();
    std::swap(point, trial_);
  }
  record.energy = point.value;
  record.gradient_norm = point.gradient.norm();
  history_.push_back(record);
  return record.progress;
}

double ShiftedNewton::extend(const NewtonPoint& point, const Objective& objective) {
  double step = 1;
  while (step < kMaxExtension) {
    extended_.y = point.y + 2 * step * step_;
    extended_.value = objective(extended_.y, extended_.gradient);
    if (!(extended_.value < trial_.value)) break;
    std::swap(trial_, extended_);
    step *= 2;
  }
  return step;
}

void ShiftedNewton::set_shifted_diagonal() {
  shifted_diagonal_ = objective_.constant_diagonal() + shift_ * objective_.mass_diagonal();
}

double ShiftedNewton::predicted_decrease(double alpha, double slope, double curvature) {
  return -alpha * slope - 0.5 * alpha * alpha * curvature;
}

int ShiftedNewton::solve_by_cg(const SparseMatrix& hessian, const Eigen::VectorXd& gradient,
                               double forcing) {
  // Preconditioned conjugate gradients (Nocedal & Wright, Numerical Optimization, algorithm 5.3)
  // on (H + C + τD) p = −∇F, with the residual r = −∇F − (H + C + τD) p.
  const double initial_norm = gradient.norm(), bound = forcing * initial_norm;
  step_.setZero();
  residual_ = -gradient;
  llt_.solve(residual_, preconditioned_);
  direction_ = preconditioned_;
  double residual_dot = residual_.dot(preconditioned_);
  for (int k = 1; k <= kMaxCgIterations; ++k) {
    product_.noalias() = hessian * direction_;
    product_ += shifted_diagonal_.cwiseProduct(direction_);
    const double curvature = direction_.dot(product_);
    if (!(curvature > 0)) return 0;
    const double alpha = residual_dot / curvature;
    step_ += alpha * direction_;
    residual_ -= alpha * product_;
    const double residual_norm = residual_.norm();
    if (residual_norm <= bound) return k;
    // Given up once the mean decrease so far would not reach the bound within the budget, from the
    // first iteration on: most attempts that fail do so while a crushed triangle's Hessian changes
    // fast, and waiting for a second iteration costs a solve each (bench/results/refine.json).
    const double mean_log_decrease = std::log(residual_norm / initial_norm) / k;
    if ((kMaxCgIterations - k) * mean_log_decrease > std::log(bound / residual_norm)) return 0;
    llt_.solve(residual_, preconditioned_);
    const double next_dot = residual_.dot(preconditioned_);
    direction_ = preconditioned_ + (next_dot / residual_dot) * direction_;
    residual_dot = next_dot;
  }
  return 0;
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
    // magnitude, which doubling alone would take ten iterations to reach).
    shift_ *= std::max(growth_, std::min(1 / cut, kMaxCutGrowth));
    growth_ = std::min(2 * growth_, kMaxGrowth);
  }
}

bool ShiftedNewton::try_factorize(const SparseMatrix& hessian) {
  ++factorizations_;
  factored_ = false;
  try {
    // Not refused for CHOLMOD's cheap condition estimate: ∇²F + τD with τ > 0 is definite when it
    // factors, and on large scans the estimate is tiny for every τ near its floor; refusing it
    // would hold τ above the floor, and the steps would creep.
    set_shifted_diagonal();
    llt_.factorize(hessian, shifted_diagonal_, 0);
    factored_ = true;
    return true;
  } catch (const NumericalError&) {
    return false;
  }
}

void ShiftedNewton::factorize_shifted(const SparseMatrix& hessian) {
  for (int attempt = 0; !try_factorize(hessian); ++attempt) {
    if (attempt == 60)
      throw NumericalError("solve_full: no shift of the Hessian could be factored");
    failed_shift_ = std::max(failed_shift_, shift_);
    shift_ *= 10;
  }
}

}  // namespace modal_deform
