#include "solve/bfgs.h"

#include <chrono>
#include <cmath>

#include "util/errors.h"

namespace modal_deform {
namespace {

// The update is skipped unless sᵀy exceeds this fraction of ‖s‖‖y‖: a pair with less curvature
// along the step would make H near singular or indefinite.
constexpr double kMinCurvatureCosine = 1e-12;

}  // namespace

void Bfgs::start(const Eigen::VectorXd& x, const Eigen::MatrixXd& initial_inverse_hessian) {
  const Eigen::Index n = x.size();
  if (initial_inverse_hessian.rows() != n || initial_inverse_hessian.cols() != n)
    throw InputError(message("initial_inverse_hessian: expected ", n, " by ", n, ", got ",
                             initial_inverse_hessian.rows(), " by ",
                             initial_inverse_hessian.cols()));
  x_ = x;
  H0_ = initial_inverse_hessian;
  H_ = H0_;
  at_initial_ = true;
  evaluated_ = converged_ = false;
  gradient_.resize(n);
  for (Eigen::VectorXd* v : {&p_, &x_new_, &gradient_new_, &s_, &y_, &Hy_}) v->resize(n);
}

void Bfgs::move_to(const Eigen::VectorXd& x) {
  if (x.size() != x_.size())
    throw InputError(message("x: expected ", x_.size(), " values, got ", x.size()));
  x_ = x;
  evaluated_ = converged_ = false;
}

void Bfgs::set_value_and_gradient(double value, const VectorRef& gradient) {
  if (gradient.size() != x_.size())
    throw InputError(message("gradient: expected ", x_.size(), " values, got ", gradient.size()));
  value_ = value;
  gradient_ = gradient;
  evaluated_ = true;
  converged_ = false;
}

void Bfgs::objective_changed(double value_change, const VectorRef& gradient_change) {
  converged_ = false;
  if (!evaluated_) return;
  value_ += value_change;
  gradient_ += gradient_change;
}

void Bfgs::objective_changed() { evaluated_ = converged_ = false; }

BfgsResult Bfgs::minimize(const Objective& objective, int max_iterations, double tolerance,
                          double budget_ms, Finish finish) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  if (max_iterations < 0)
    throw InputError(message("max_iterations: expected at least 0, got ", max_iterations));
  if (!(tolerance > 0 && tolerance < 1))
    throw InputError(message("tolerance: expected a value in (0, 1), got ", tolerance));
  if (!(budget_ms > 0))
    throw InputError(message("budget_ms: expected a time > 0 (or infinity), got ", budget_ms));
  const auto within_budget = [&] {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count() < budget_ms;
  };
  BfgsResult result;
  if (!evaluated_) {
    value_ = objective(x_, gradient_);
    ++result.evaluations;
    if (!std::isfinite(value_))
      throw NumericalError("BFGS: the objective is not finite at the current point");
    evaluated_ = true;
  }
  const double sqrt_tolerance = std::sqrt(tolerance), cbrt_tolerance = std::cbrt(tolerance);
  while (!converged_ && result.iterations < max_iterations &&
         (result.iterations == 0 || within_budget())) {
    if (gradient_.norm() <= tolerance * (1 + std::abs(value_))) {
      converged_ = true;
      break;
    }
    p_.noalias() = -H_ * gradient_;
    const double scale = 1 + std::abs(value_), model_decrease = -0.5 * gradient_.dot(p_);
    if (finish == Finish::kPredicted && model_decrease >= 0 && model_decrease < tolerance * scale &&
        p_.norm() < sqrt_tolerance * (1 + x_.norm()) &&
        gradient_.norm() <= cbrt_tolerance * scale) {
      x_ += p_;
      evaluated_ = false;
      converged_ = true;
      ++result.iterations;
      break;
    }
    LineSearchResult search;
    if (gradient_.dot(p_) < 0) {
      search = wolfe_line_search(objective, x_, value_, gradient_, p_, x_new_, value_new_,
                                 gradient_new_);
      result.evaluations += search.evaluations;
    }
    if (search.step == 0) {
      ++result.line_search_failures;
      const double predicted_decrease = -gradient_.dot(p_);
      if (predicted_decrease > 0 &&
          predicted_decrease <= kUnresolvableDecrease * (1 + std::abs(value_))) {
        converged_ = true;
        break;
      }
      if (at_initial_) {
        result.stalled = true;
        break;
      }
      H_ = H0_;
      at_initial_ = true;
      continue;
    }
    s_ = x_new_ - x_;
    y_ = gradient_new_ - gradient_;
    const double previous_value = value_;
    x_.swap(x_new_);
    gradient_.swap(gradient_new_);
    value_ = value_new_;
    ++result.iterations;
    const double sy = s_.dot(y_);
    if (sy > kMinCurvatureCosine * s_.norm() * y_.norm()) {
      // H ← (I − ρsyᵀ) H (I − ρysᵀ) + ρssᵀ, ρ = 1/yᵀs, expanded to rank-one updates (H symmetric).
      const double rho = 1 / sy;
      Hy_.noalias() = H_ * y_;
      const double yHy = y_.dot(Hy_);
      H_.noalias() -= rho * (s_ * Hy_.transpose());
      H_.noalias() -= rho * (Hy_ * s_.transpose());
      H_.noalias() += (rho * rho * yHy + rho) * (s_ * s_.transpose());
      at_initial_ = false;
    }
    converged_ = previous_value - value_ < tolerance * (1 + std::abs(value_)) &&
                 s_.norm() < sqrt_tolerance * (1 + x_.norm()) &&
                 gradient_.norm() <= cbrt_tolerance * (1 + std::abs(value_));
  }
  result.converged = converged_;
  return result;
}

}  // namespace modal_deform
