// BFGS with a dense inverse Hessian, a strong Wolfe line search and the Gill–Murray–Wright
// stopping test: the reduced solver's minimiser (paper section 5).
//
// The state (x, the inverse Hessian H, f and ∇f at x) persists between calls of minimize, so an
// interactive session runs a few iterations per frame and continues from where it stopped. When
// the objective changes (a handle moved), the caller either says by how much f and ∇f changed at
// x (cheap when only a known term changed) or has them re-evaluated. Stopping: paper eq. 14 (GMW
// 8.2.3.2), and converged calls return at once until the objective changes. With
// Finish::kPredicted the quasi-Newton step that passes the test is taken unevaluated, for a caller
// that needs x alone. The test's bounds and why: docs/design.md, "BFGS".
#pragma once

#include <limits>

#include "solve/line_search.h"
#include "util/types.h"

namespace modal_deform {

// How a converging call ends (the stopping tests above).
enum class Finish {
  kEvaluated,  // at a point whose f and ∇f are evaluated
  kPredicted,  // possibly at the unevaluated x + p of a predicted step within the tolerance
};

struct BfgsResult {
  int iterations = 0;   // steps taken by this call
  int evaluations = 0;  // objective calls by this call
  bool converged = false;
  // The call ended because no step from x decreases f, even along −H0∇f (line-search failure):
  // x is not a minimum by the stopping test, but BFGS cannot leave it (a stall, not convergence).
  bool stalled = false;
  int line_search_failures = 0;  // line searches of this call that found no decrease
};

class Bfgs {
 public:
  // Starts at x (n) with the initial inverse Hessian H0 (n by n, symmetric positive definite),
  // kept for restarts; f and ∇f are evaluated by the next minimize.
  void start(const Eigen::VectorXd& x, const Eigen::MatrixXd& initial_inverse_hessian);

  // Moves to x (n) keeping the inverse Hessian, for an objective that changed by a linear term
  // (same curvature, e.g. the next time step's incremental potential); f and ∇f are evaluated by
  // the next minimize.
  void move_to(const Eigen::VectorXd& x);

  // f and ∇f at the current x are `value` and `gradient` (n), known to the caller (e.g. from the
  // terms of a state it holds): the next minimize starts from them without evaluating f there.
  void set_value_and_gradient(double value, const VectorRef& gradient);

  // The objective changed by `value_change` and `gradient_change` (n) at the current x.
  void objective_changed(double value_change, const VectorRef& gradient_change);
  // The objective changed in an unknown way: f and ∇f are evaluated again by the next minimize.
  void objective_changed();

  // Up to max_iterations ≥ 0 BFGS steps with the stopping test above (tolerance ε in (0, 1)),
  // and none begun once `budget_ms` milliseconds (> 0; infinity for no limit) have passed since the
  // call began: an interactive frame's share of time. The step under way when the budget runs out
  // is finished, so every call with max_iterations ≥ 1 makes progress.
  // Each step searches along p = −H∇f; H takes the BFGS update (N&W eq. 6.17) when the step's
  // curvature yᵀs is positive, as the Wolfe conditions ensure. When p is not a descent direction
  // or the line search finds no decrease, H restarts from H0 once; a second failure ends the
  // call unconverged and stalled (the objective cannot be decreased at this precision). Throws
  // NumericalError when f is not finite at the current x.
  BfgsResult minimize(const Objective& objective, int max_iterations, double tolerance,
                      double budget_ms = std::numeric_limits<double>::infinity(),
                      Finish finish = Finish::kEvaluated);

  const Eigen::VectorXd& x() const { return x_; }
  const Eigen::MatrixXd& inverse_hessian() const { return H_; }
  // f and ∇f at x; valid after a minimize, unless it ended on a predicted step
  // (Finish::kPredicted).
  double value() const { return value_; }
  const Eigen::VectorXd& gradient() const { return gradient_; }

 private:
  Eigen::VectorXd x_, gradient_;
  double value_ = 0;
  bool evaluated_ = false;  // value_ and gradient_ belong to x_ and the current objective
  bool converged_ = false;
  bool at_initial_ = true;  // H_ == H0_
  Eigen::MatrixXd H_, H0_;
  // Work space, sized once.
  Eigen::VectorXd p_, x_new_, gradient_new_, s_, y_, Hy_;
  double value_new_ = 0;
};

}  // namespace modal_deform
