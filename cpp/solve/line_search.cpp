#include "solve/line_search.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace modal_deform {
namespace {

// φ(α) = f(x + αp) and its slope φ'(α) = ∇f(x + αp)ᵀp at one trial step.
struct Sample {
  double step, value, slope;
};

// The next trial inside the bracket [lo, hi] (either order): the minimiser of the cubic
// interpolating φ and φ' at both ends (N&W eq. 3.59), else of the quadratic through φ(lo),
// φ'(lo) and φ(hi), else a tenth of the way from lo when φ(hi) could not be evaluated;
// clamped to the middle eight tenths of the bracket.
double interpolate(const Sample& lo, const Sample& hi) {
  const double width = hi.step - lo.step;
  double step = std::numeric_limits<double>::quiet_NaN();
  if (std::isfinite(hi.value) && std::isfinite(hi.slope)) {
    const double d1 = lo.slope + hi.slope - 3 * (lo.value - hi.value) / (lo.step - hi.step);
    const double discriminant = d1 * d1 - lo.slope * hi.slope;
    if (discriminant >= 0) {
      const double d2 = std::copysign(std::sqrt(discriminant), width);
      step = hi.step - width * (hi.slope + d2 - d1) / (hi.slope - lo.slope + 2 * d2);
    }
  }
  if (!std::isfinite(step) && std::isfinite(hi.value)) {
    const double curvature = hi.value - lo.value - lo.slope * width;
    if (curvature > 0) step = lo.step - lo.slope * width * width / (2 * curvature);
  }
  if (!std::isfinite(step)) step = lo.step + 0.1 * width;
  const double low = std::min(lo.step, hi.step) + 0.1 * std::abs(width);
  const double high = std::max(lo.step, hi.step) - 0.1 * std::abs(width);
  return std::clamp(step, low, high);
}

}  // namespace

LineSearchResult wolfe_line_search(const Objective& objective, const Eigen::VectorXd& x,
                                   double value, const Eigen::VectorXd& gradient,
                                   const Eigen::VectorXd& p, Eigen::VectorXd& x_new,
                                   double& value_new, Eigen::VectorXd& gradient_new,
                                   const WolfeConditions& conditions) {
  LineSearchResult result;
  const double slope0 = gradient.dot(p);
  const double decrease = conditions.sufficient_decrease * slope0;
  const double curvature = -conditions.curvature * slope0;
  double last_step = 0;
  auto evaluate = [&](double step) {
    x_new = x + step * p;
    value_new = objective(x_new, gradient_new);
    ++result.evaluations;
    last_step = step;
    if (!std::isfinite(value_new))
      return Sample{step, std::numeric_limits<double>::infinity(), std::nan("")};
    return Sample{step, value_new, gradient_new.dot(p)};
  };
  Sample best{0, value, slope0};  // the lowest point satisfying sufficient decrease
  auto sufficient = [&](const Sample& s) {
    const bool ok = s.value <= value + s.step * decrease;
    if (ok && s.value < best.value) best = s;
    return ok;
  };
  auto accept = [&](const Sample& s) {
    result.step = s.step;
    result.wolfe = true;
    return result;
  };
  if (!(slope0 < 0)) {
    x_new = x;
    value_new = value;
    gradient_new = gradient;
    return result;
  }

  // Bracketing (N&W algorithm 3.5): grow the step until it overshoots the minimum along p.
  Sample previous{0, value, slope0}, lo{}, hi{};
  double step = 1;
  bool bracketed = false;
  while (!bracketed && result.evaluations < conditions.max_evaluations) {
    const Sample s = evaluate(step);
    if (!sufficient(s) || (previous.step > 0 && s.value >= previous.value)) {
      lo = previous;
      hi = s;
      bracketed = true;
    } else if (std::abs(s.slope) <= curvature) {
      return accept(s);
    } else if (s.slope >= 0) {
      lo = s;
      hi = previous;
      bracketed = true;
    } else {
      previous = s;
      step *= 4;
    }
  }
  // Zoom (N&W algorithm 3.6): shrink the bracket, keeping lo the lowest sufficient point and the
  // minimum between lo and hi.
  while (bracketed && result.evaluations < conditions.max_evaluations &&
         std::abs(hi.step - lo.step) > 1e-12 * std::max(lo.step, hi.step)) {
    const Sample s = evaluate(interpolate(lo, hi));
    if (!sufficient(s) || s.value >= lo.value) {
      hi = s;
    } else {
      if (std::abs(s.slope) <= curvature) return accept(s);
      if (s.slope * (hi.step - lo.step) >= 0) hi = lo;
      lo = s;
    }
  }
  // No Wolfe point within the budget: fall back to the lowest sufficient one, or to no step.
  result.step = best.step;
  if (best.step == 0) {
    x_new = x;
    value_new = value;
    gradient_new = gradient;
  } else if (last_step != best.step) {
    evaluate(best.step);
  }
  return result;
}

BacktrackingResult backtracking_line_search(const Objective& objective, const Eigen::VectorXd& x,
                                            double value, const Eigen::VectorXd& gradient,
                                            const Eigen::VectorXd& p, Eigen::VectorXd& x_new,
                                            double& value_new, Eigen::VectorXd& gradient_new,
                                            double noise, double initial_step,
                                            double sufficient_decrease, int max_halvings) {
  BacktrackingResult result;
  const double slope = gradient.dot(p);
  if (slope < 0) {
    const double gradient_norm = gradient.norm();
    double step = initial_step;
    for (int halving = 0; halving <= max_halvings; ++halving, step /= 2) {
      x_new = x + step * p;
      value_new = objective(x_new, gradient_new);
      ++result.evaluations;
      if (!std::isfinite(value_new)) {
        ++result.undefined;
        continue;
      }
      const bool decreased = value_new <= value + sufficient_decrease * step * slope;
      const bool within_rounding = -step * slope < noise && value_new <= value + noise &&
                                   gradient_new.norm() < gradient_norm;
      if (decreased || within_rounding) {
        result.step = step;
        return result;
      }
      ++result.insufficient;
    }
  }
  x_new = x;
  value_new = value;
  gradient_new = gradient;
  return result;
}

}  // namespace modal_deform
