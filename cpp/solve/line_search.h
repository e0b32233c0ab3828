// Line searches: one for the strong Wolfe conditions (Nocedal & Wright, Numerical Optimization, 2nd
// ed., algorithms 3.5 and 3.6), used by BFGS, and Armijo backtracking, used by the full Newton
// solve (whose step is long where its model is poor, not short).
#pragma once

#include <functional>

#include "util/types.h"

namespace modal_deform {

// An objective for the minimisers: returns f(x) and writes ∇f(x) into `gradient` (sized like x).
// It may return +inf or NaN where it cannot be evaluated; the line search treats such a point as
// a step too far.
using Objective = std::function<double(const Eigen::VectorXd& x, Eigen::VectorXd& gradient)>;

struct WolfeConditions {
  double sufficient_decrease = 1e-4;  // c1: f(x + αp) ≤ f(x) + c1 α ∇f(x)ᵀp
  double curvature = 0.9;             // c2: |∇f(x + αp)ᵀp| ≤ c2 |∇f(x)ᵀp|
  int max_evaluations = 20;
};

struct LineSearchResult {
  double step = 0;      // α, 0 when no evaluated step satisfied sufficient decrease
  bool wolfe = false;   // both conditions hold at α
  int evaluations = 0;  // calls of the objective
};

// Searches along a descent direction p (∇f(x)ᵀp < 0) from x, with f(x) = `value` and ∇f(x) =
// `gradient`, for a step α satisfying the strong Wolfe conditions. The first trial is α = 1 (the
// quasi-Newton step, which usually passes at once); steps grow fourfold until the minimum is
// bracketed, and inside a bracket the next trial minimises the cubic through f and its slope at
// both ends, kept at least a tenth of the bracket away from either end. When max_evaluations
// run out, the lowest point found that satisfies sufficient decrease is returned (re-evaluated
// when it was not the last one), with wolfe = false. On return x_new = x + αp, value_new and
// gradient_new are f and ∇f there (x, value, gradient themselves when α = 0). x_new and
// gradient_new must be sized like x; nothing is allocated.
LineSearchResult wolfe_line_search(const Objective& objective, const Eigen::VectorXd& x,
                                   double value, const Eigen::VectorXd& gradient,
                                   const Eigen::VectorXd& p, Eigen::VectorXd& x_new,
                                   double& value_new, Eigen::VectorXd& gradient_new,
                                   const WolfeConditions& conditions = {});

struct BacktrackingResult {
  double step = 0;       // α, 0 when no halving gave a decrease
  int evaluations = 0;   // calls of the objective
  int undefined = 0;     // trials rejected because f was +inf or NaN there (beyond its domain)
  int insufficient = 0;  // trials rejected because f did not decrease enough
};

// A decrease below this fraction of 1 + |f| is lost in the rounding of f (a sum of thousands of
// rounded terms): the `noise` the searches' callers pass, and the predicted decrease below which a
// failed search finds x a minimum at working precision, not a stall.
constexpr double kUnresolvableDecrease = 1e-12;

// Halves α from `initial_step` (≤ 1) until f(x + αp) ≤ f(x) + c1 α ∇f(x)ᵀp (a point where f
// returns +inf or NaN counts as too far), at most max_halvings times. Near a minimum the decrease
// a step promises falls below the rounding of f; with noise > 0 (an absolute bound on that
// rounding) a step whose promised decrease is below it is also taken when f does not rise by more
// than noise and ‖∇f‖ falls (it would otherwise stall on rounding). On return x_new, value_new and
// gradient_new are the point taken and f, ∇f there (x, value, gradient themselves when α = 0);
// x_new and gradient_new must be sized like x.
BacktrackingResult backtracking_line_search(const Objective& objective, const Eigen::VectorXd& x,
                                            double value, const Eigen::VectorXd& gradient,
                                            const Eigen::VectorXd& p, Eigen::VectorXd& x_new,
                                            double& value_new, Eigen::VectorXd& gradient_new,
                                            double noise = 0, double initial_step = 1,
                                            double sufficient_decrease = 1e-4,
                                            int max_halvings = 40);

}  // namespace modal_deform
