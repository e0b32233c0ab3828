#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>

#include "solve/bfgs.h"
#include "solve/line_search.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

// The extended Rosenbrock function, Σ 100 (x_{2k+1} − x_{2k}²)² + (1 − x_{2k})²: minimum 0 at 1.
double rosenbrock(const Eigen::VectorXd& x, Eigen::VectorXd& g) {
  double f = 0;
  g.setZero(x.size());
  for (Eigen::Index k = 0; k + 1 < x.size(); k += 2) {
    const double a = x[k + 1] - x[k] * x[k], b = 1 - x[k];
    f += 100 * a * a + b * b;
    g[k] += -400 * a * x[k] - 2 * b;
    g[k + 1] += 200 * a;
  }
  return f;
}

Eigen::VectorXd rosenbrock_start(int n) {
  Eigen::VectorXd x(n);
  for (int k = 0; k < n; k += 2) x.segment<2>(k) = Eigen::Vector2d(-1.2, 1.0);
  return x;
}

// f = ½ xᵀAx − bᵀx with A symmetric positive definite.
struct Quadratic {
  Eigen::MatrixXd A;
  Eigen::VectorXd b;
  explicit Quadratic(int n) {
    std::srand(3);
    const Eigen::MatrixXd R = Eigen::MatrixXd::Random(n, n);
    A = R * R.transpose() + Eigen::MatrixXd::Identity(n, n);
    b = Eigen::VectorXd::Random(n);
  }
  double operator()(const Eigen::VectorXd& x, Eigen::VectorXd& g) const {
    g = A * x - b;
    return 0.5 * x.dot(A * x) - b.dot(x);
  }
};

void expect_strong_wolfe(const Objective& f, const Eigen::VectorXd& x, const Eigen::VectorXd& p,
                         const LineSearchResult& result, double value_new,
                         const Eigen::VectorXd& x_new, const Eigen::VectorXd& gradient_new) {
  Eigen::VectorXd g(x.size());
  const double value = f(x, g);
  const WolfeConditions c;
  ASSERT_TRUE(result.wolfe);
  EXPECT_LE((x_new - (x + result.step * p)).norm(), 1e-15 * (1 + x_new.norm()));
  EXPECT_LE(value_new, value + c.sufficient_decrease * result.step * g.dot(p));
  EXPECT_LE(std::abs(gradient_new.dot(p)), c.curvature * std::abs(g.dot(p)));
  Eigen::VectorXd check(x.size());
  EXPECT_EQ(f(x_new, check), value_new);
  EXPECT_EQ(check, gradient_new);
}

TEST(WolfeLineSearch, TheNewtonStepOfAQuadraticCostsOneEvaluation) {
  const Quadratic f(6);
  const Eigen::VectorXd x = Eigen::VectorXd::Random(6);
  Eigen::VectorXd g(6), x_new(6), g_new(6);
  const double value = f(x, g);
  const Eigen::VectorXd p = -f.A.llt().solve(g);
  double value_new;
  const LineSearchResult result = wolfe_line_search(f, x, value, g, p, x_new, value_new, g_new);
  EXPECT_EQ(result.step, 1.0);
  EXPECT_EQ(result.evaluations, 1);
  expect_strong_wolfe(f, x, p, result, value_new, x_new, g_new);
}

TEST(WolfeLineSearch, ShrinksLongStepsAndGrowsShortOnes) {
  const Quadratic f(6);
  const Eigen::VectorXd x = Eigen::VectorXd::Random(6);
  Eigen::VectorXd g(6), x_new(6), g_new(6);
  const double value = f(x, g);
  const Eigen::VectorXd newton = -f.A.llt().solve(g);
  for (double scale : {1e4, 30.0, 1e-2, 1e-5}) {
    const Eigen::VectorXd p = scale * newton;
    double value_new;
    const LineSearchResult result = wolfe_line_search(f, x, value, g, p, x_new, value_new, g_new);
    expect_strong_wolfe(f, x, p, result, value_new, x_new, g_new);
    EXPECT_LT(result.evaluations, 12) << "scale " << scale;
    if (scale > 1) {
      EXPECT_LT(result.step, 1.0);
    } else {
      EXPECT_GT(result.step, 1.0);
    }
  }
}

TEST(WolfeLineSearch, BacksOffFromPointsThatCannotBeEvaluated) {
  // Rosenbrock, undefined beyond |x| = 2: the first trial lands there.
  const Objective f = [](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
    return x.norm() > 2 ? std::numeric_limits<double>::infinity() : rosenbrock(x, g);
  };
  const Eigen::VectorXd x = Eigen::Vector2d(0, 0);
  Eigen::VectorXd g(2), x_new(2), g_new(2);
  const double value = f(x, g);
  const Eigen::VectorXd p = -100 * g;
  double value_new;
  const LineSearchResult result = wolfe_line_search(f, x, value, g, p, x_new, value_new, g_new);
  expect_strong_wolfe(f, x, p, result, value_new, x_new, g_new);
}

TEST(WolfeLineSearch, AnAscentDirectionTakesNoStep) {
  const Quadratic f(4);
  const Eigen::VectorXd x = Eigen::VectorXd::Random(4);
  Eigen::VectorXd g(4), x_new(4), g_new(4);
  const double value = f(x, g);
  double value_new;
  const LineSearchResult result = wolfe_line_search(f, x, value, g, g, x_new, value_new, g_new);
  EXPECT_EQ(result.step, 0.0);
  EXPECT_EQ(result.evaluations, 0);
  EXPECT_EQ(x_new, x);
  EXPECT_EQ(value_new, value);
}

TEST(BacktrackingLineSearch, HalvesUntilSufficientDecreaseSkippingWhatCannotBeEvaluated) {
  const Quadratic quadratic(6);
  const Eigen::VectorXd x = Eigen::VectorXd::Random(6);
  Eigen::VectorXd g(6), x_new(6), g_new(6);
  const double value = quadratic(x, g);
  const Eigen::VectorXd newton = -quadratic.A.llt().solve(g);
  double value_new;
  // The Newton step passes at once; 8 times too long, after three halvings (α = 1/8).
  EXPECT_EQ(backtracking_line_search(quadratic, x, value, g, newton, x_new, value_new, g_new).step,
            1.0);
  BacktrackingResult result =
      backtracking_line_search(quadratic, x, value, g, 8 * newton, x_new, value_new, g_new);
  EXPECT_EQ(result.step, 0.125);
  EXPECT_EQ(result.evaluations, 4);
  EXPECT_EQ(result.insufficient, 3);
  EXPECT_EQ(result.undefined, 0);
  EXPECT_LE((x_new - (x + newton)).norm(), 1e-12);
  // Undefined beyond a radius: those trials count as too far.
  const Objective bounded = [&](const Eigen::VectorXd& y, Eigen::VectorXd& gradient) {
    return (y - x).norm() > 0.3 * newton.norm() ? std::nan("") : quadratic(y, gradient);
  };
  result = backtracking_line_search(bounded, x, value, g, newton, x_new, value_new, g_new);
  EXPECT_EQ(result.step, 0.25);
  EXPECT_EQ(result.undefined,
            2);  // why the step was cut: the domain, not the decrease (full_solver)
  EXPECT_EQ(result.insufficient, 0);
  Eigen::VectorXd check(6);
  EXPECT_EQ(quadratic(x_new, check), value_new);
  EXPECT_EQ(check, g_new);
  // An ascent direction takes no step and leaves the point as it was.
  result = backtracking_line_search(quadratic, x, value, g, -newton, x_new, value_new, g_new);
  EXPECT_EQ(result.step, 0.0);
  EXPECT_EQ(result.evaluations, 0);
  EXPECT_EQ(x_new, x);
  EXPECT_EQ(value_new, value);
}

TEST(Bfgs, MinimisesRosenbrockWithMonotoneDecrease) {
  Bfgs bfgs;
  bfgs.start(rosenbrock_start(10), Eigen::MatrixXd::Identity(10, 10));
  double previous = std::numeric_limits<double>::infinity();
  int iterations = 0;
  for (; iterations < 500; ++iterations) {
    const BfgsResult result = bfgs.minimize(rosenbrock, 1, 1e-15);
    EXPECT_LE(bfgs.value(), previous);
    previous = bfgs.value();
    if (result.converged) break;
  }
  EXPECT_LT(iterations, 200);
  EXPECT_LE((bfgs.x() - Eigen::VectorXd::Ones(10)).norm(), 1e-4);
}

// Paper eq. 14: the call reports convergence exactly when the three conditions hold for its last
// step (or the gradient was already negligible).
TEST(Bfgs, StopsWhenTheGillMurrayWrightConditionsHold) {
  for (double tolerance : {1e-4, 1e-8, 1e-12}) {
    Bfgs bfgs;
    bfgs.start(rosenbrock_start(4), Eigen::MatrixXd::Identity(4, 4));
    bfgs.minimize(rosenbrock, 0, tolerance);  // evaluates f at the start
    bool converged = false;
    int steps = 0;
    for (int call = 0; call < 500 && !converged; ++call) {
      const Eigen::VectorXd x_before = bfgs.x();
      const double f_before = bfgs.value();
      const BfgsResult result = bfgs.minimize(rosenbrock, 1, tolerance);
      steps += result.iterations;
      converged = result.converged;
      const double f = bfgs.value();
      const double theta = 1 + std::abs(f);
      const bool u1 = f_before - f < tolerance * theta;
      const bool u2 = (x_before - bfgs.x()).norm() < std::sqrt(tolerance) * (1 + bfgs.x().norm());
      const bool u3 = bfgs.gradient().norm() <= std::cbrt(tolerance) * theta;
      if (result.iterations == 1) {
        EXPECT_EQ(converged, u1 && u2 && u3) << "tolerance " << tolerance << " step " << steps;
      } else {
        EXPECT_TRUE(converged && bfgs.gradient().norm() <= tolerance * theta);
      }
    }
    EXPECT_TRUE(converged) << "tolerance " << tolerance;
    EXPECT_LE(bfgs.gradient().norm(), std::cbrt(tolerance) * (1 + std::abs(bfgs.value())));
  }
}

TEST(Bfgs, StatePersistsAcrossCalls) {
  Bfgs once, twice;
  once.start(rosenbrock_start(6), Eigen::MatrixXd::Identity(6, 6));
  twice.start(rosenbrock_start(6), Eigen::MatrixXd::Identity(6, 6));
  const BfgsResult ten = once.minimize(rosenbrock, 10, 1e-12);
  const BfgsResult first = twice.minimize(rosenbrock, 5, 1e-12);
  const BfgsResult second = twice.minimize(rosenbrock, 5, 1e-12);
  EXPECT_EQ(ten.iterations, 10);
  EXPECT_EQ(first.iterations + second.iterations, 10);
  EXPECT_EQ(first.evaluations + second.evaluations, ten.evaluations);
  EXPECT_EQ(once.x(), twice.x());
  EXPECT_EQ(once.inverse_hessian(), twice.inverse_hessian());
}

// A spent budget stops the call after the step under way; the state is the same as after that
// many steps without a budget, so the next call continues seamlessly.
TEST(Bfgs, ATimeBudgetEndsTheCallAfterItsFirstStep) {
  Bfgs budgeted, unlimited;
  budgeted.start(rosenbrock_start(6), Eigen::MatrixXd::Identity(6, 6));
  unlimited.start(rosenbrock_start(6), Eigen::MatrixXd::Identity(6, 6));
  for (int call = 0; call < 3; ++call) {
    const BfgsResult result = budgeted.minimize(rosenbrock, 100, 1e-12, 1e-9);
    EXPECT_EQ(result.iterations, 1);
  }
  unlimited.minimize(rosenbrock, 3, 1e-12);
  EXPECT_EQ(budgeted.x(), unlimited.x());
  // A generous budget leaves the iteration count to max_iterations.
  EXPECT_EQ(budgeted.minimize(rosenbrock, 5, 1e-12, 6e4).iterations, 5);
  for (double budget : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN()})
    EXPECT_THROW(budgeted.minimize(rosenbrock, 1, 1e-12, budget), InputError) << budget;
}

TEST(Bfgs, TheExactInverseHessianSolvesAQuadraticInOneStep) {
  const Quadratic f(8);
  Bfgs bfgs;
  bfgs.start(Eigen::VectorXd::Zero(8), f.A.inverse());
  const BfgsResult result = bfgs.minimize(f, 10, 1e-10);
  EXPECT_TRUE(result.converged);
  EXPECT_EQ(result.iterations, 1);
  EXPECT_EQ(result.evaluations, 2);  // the start and the unit step
  EXPECT_LE((bfgs.x() - f.A.llt().solve(f.b)).norm(), 1e-12);
  // Converged: nothing more to do until the objective changes.
  const BfgsResult again = bfgs.minimize(f, 10, 1e-10);
  EXPECT_TRUE(again.converged);
  EXPECT_EQ(again.evaluations, 0);
}

TEST(Bfgs, AKnownChangeOfTheObjectiveEqualsReevaluation) {
  // f_c = rosenbrock + cᵀx: moving c changes f by Δcᵀx and ∇f by Δc.
  Eigen::VectorXd c = Eigen::VectorXd::Zero(4);
  const Objective f = [&c](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
    const double value = rosenbrock(x, g) + c.dot(x);
    g += c;
    return value;
  };
  Bfgs told, reevaluated;
  told.start(rosenbrock_start(4), Eigen::MatrixXd::Identity(4, 4));
  reevaluated.start(rosenbrock_start(4), Eigen::MatrixXd::Identity(4, 4));
  told.minimize(f, 6, 1e-12);
  reevaluated.minimize(f, 6, 1e-12);
  const Eigen::VectorXd change = Eigen::Vector4d(0.3, -0.2, 0.1, 0.5);
  c += change;
  told.objective_changed(change.dot(told.x()), change);
  reevaluated.objective_changed();
  const BfgsResult a = told.minimize(f, 6, 1e-12);
  const BfgsResult b = reevaluated.minimize(f, 6, 1e-12);
  EXPECT_EQ(a.evaluations + 1, b.evaluations);
  EXPECT_LE((told.x() - reevaluated.x()).norm(), 1e-10);
}

TEST(Bfgs, AKnownValueAndGradientAtTheStartSaveItsEvaluation) {
  Bfgs told, evaluated;
  told.start(rosenbrock_start(4), Eigen::MatrixXd::Identity(4, 4));
  evaluated.start(rosenbrock_start(4), Eigen::MatrixXd::Identity(4, 4));
  Eigen::VectorXd g(4);
  told.set_value_and_gradient(rosenbrock(rosenbrock_start(4), g), g);
  const BfgsResult a = told.minimize(rosenbrock, 8, 1e-12);
  const BfgsResult b = evaluated.minimize(rosenbrock, 8, 1e-12);
  EXPECT_EQ(a.evaluations + 1, b.evaluations);
  EXPECT_EQ(told.x(), evaluated.x());
  EXPECT_THROW(told.set_value_and_gradient(0, Eigen::VectorXd::Zero(3)), InputError);
}

// Finish::kPredicted ends a converging call one evaluation early, at the unevaluated point the
// quasi-Newton step predicts, within the tolerance of the evaluated finish's point.
TEST(Bfgs, APredictedFinishSavesTheConfirmingEvaluation) {
  for (double tolerance : {1e-8, 1e-10, 1e-12}) {
    Bfgs predicted, evaluated;
    predicted.start(rosenbrock_start(6), Eigen::MatrixXd::Identity(6, 6));
    evaluated.start(rosenbrock_start(6), Eigen::MatrixXd::Identity(6, 6));
    const BfgsResult a = predicted.minimize(
        rosenbrock, 500, tolerance, std::numeric_limits<double>::infinity(), Finish::kPredicted);
    const BfgsResult b = evaluated.minimize(rosenbrock, 500, tolerance);
    ASSERT_TRUE(a.converged && b.converged) << tolerance;
    EXPECT_LT(a.evaluations, b.evaluations) << tolerance;
    EXPECT_LE((predicted.x() - Eigen::VectorXd::Ones(6)).norm(), 10 * std::sqrt(tolerance))
        << tolerance;
    EXPECT_LE((predicted.x() - evaluated.x()).norm(),
              std::sqrt(tolerance) * (1 + evaluated.x().norm()))
        << tolerance;
    // Converged: f and ∇f at the point taken are evaluated by the next call, which returns at once.
    const BfgsResult again = predicted.minimize(rosenbrock, 10, tolerance);
    EXPECT_TRUE(again.converged);
    EXPECT_EQ(again.iterations, 0);
  }
}

TEST(Bfgs, MoveToKeepsTheCurvatureLearnt) {
  // A quadratic learnt from the identity, then the same curvature with another linear term (the
  // next time step's incremental potential): from the same start, move_to keeps what BFGS learnt.
  Quadratic f(8);
  const Eigen::VectorXd start = Eigen::VectorXd::Zero(8);
  Bfgs kept, fresh;
  kept.start(start, Eigen::MatrixXd::Identity(8, 8));
  ASSERT_TRUE(kept.minimize(f, 100, 1e-12).converged);
  f.b = Eigen::VectorXd::LinSpaced(8, -1.0, 1.0);
  kept.move_to(start);
  fresh.start(start, Eigen::MatrixXd::Identity(8, 8));
  const BfgsResult with_curvature = kept.minimize(f, 100, 1e-12);
  const BfgsResult without = fresh.minimize(f, 100, 1e-12);
  ASSERT_TRUE(with_curvature.converged && without.converged);
  EXPECT_LT(with_curvature.iterations, without.iterations);
  EXPECT_LE((kept.x() - f.A.llt().solve(f.b)).norm(), 1e-6);
  EXPECT_THROW(kept.move_to(Eigen::VectorXd::Zero(7)), InputError);
}

// An objective whose gradient points the wrong way (as a jump in f can make it): no step lowers
// f, from H or from H0, and the call says it stalled instead of passing for convergence.
TEST(Bfgs, ReportsAStallWhenNoStepDecreases) {
  const Objective misleading = [](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
    g = -x;
    return 0.5 * x.squaredNorm();
  };
  Bfgs bfgs;
  bfgs.start(Eigen::VectorXd::Constant(3, 1.0), Eigen::MatrixXd::Identity(3, 3));
  const BfgsResult stalled = bfgs.minimize(misleading, 10, 1e-8);
  EXPECT_TRUE(stalled.stalled);
  EXPECT_FALSE(stalled.converged);
  EXPECT_EQ(stalled.iterations, 0);
  EXPECT_EQ(stalled.line_search_failures, 1);

  const Quadratic f(4);
  bfgs.start(Eigen::VectorXd::Zero(4), Eigen::MatrixXd::Identity(4, 4));
  const BfgsResult converged = bfgs.minimize(std::cref(f), 100, 1e-10);
  EXPECT_TRUE(converged.converged);
  EXPECT_FALSE(converged.stalled);
  EXPECT_EQ(converged.line_search_failures, 0);
}

// Every step away from x0 raises f by 1e-9, as the rounding of a large sum can: no line search
// succeeds. Where the predicted decrease (‖x0‖² with H0 = I, g = x) is below what f resolves, that
// is a minimum at working precision; where it is not, a stall.
TEST(Bfgs, AMinimumAtWorkingPrecisionIsNoStall) {
  for (const double x0 : {1e-5, 1.0}) {
    const Objective rounded = [x0](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
      g = x;
      return x[0] == x0 ? 1e6 : 1e6 + 1e-9;
    };
    Bfgs bfgs;
    bfgs.start(Eigen::VectorXd::Constant(1, x0), Eigen::MatrixXd::Identity(1, 1));
    const BfgsResult result = bfgs.minimize(rounded, 10, 1e-13);
    EXPECT_EQ(result.converged, x0 < 1) << x0;
    EXPECT_EQ(result.stalled, x0 == 1) << x0;
    EXPECT_EQ(result.line_search_failures, 1) << x0;
  }
}

}  // namespace
}  // namespace modal_deform
