// One check of an exact derivative against centred differences, for every energy's test (discrete
// shells, ARAP, the handle terms, the reduced objective).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "energy/energy.h"
#include "util/types.h"

namespace modal_deform::testing {

// Steps of the centred differences: largest_step and four decades below it.
inline std::vector<double> difference_steps(double largest_step) {
  return {largest_step, largest_step / 1e1, largest_step / 1e2, largest_step / 1e3,
          largest_step / 1e4};
}

// Expects `exact` (a derivative along some direction, any length) to match difference(h), the
// centred difference of step h, at difference_steps(largest_step). Their error, relative to the
// larger of the exact value and the difference at the largest step (the exact value is 0 at rest),
// must fall like h², by at least 30 times a decade over the first two, until it is below
// `tolerance`, and reach it before round-off takes over. A wrong derivative leaves an error that
// does not fall; the differences of a quadratic are exact from the first step.
inline void expect_matches_centred_differences(
    const Eigen::VectorXd& exact, const std::function<Eigen::VectorXd(double)>& difference,
    const std::string& what, double tolerance = 1e-6, double largest_step = 1e-3) {
  std::vector<Eigen::VectorXd> differences;
  for (double h : difference_steps(largest_step)) differences.push_back(difference(h));
  const double scale = std::max(exact.norm(), differences.front().norm());
  std::vector<double> errors;
  char text[32];
  std::snprintf(text, sizeof text, "%.0e", largest_step);
  std::string where = what + ": relative errors at h = " + text + " / 10^k:";
  for (const Eigen::VectorXd& d : differences) {
    errors.push_back((d - exact).norm() / scale);
    std::snprintf(text, sizeof text, " %.1e", errors.back());
    where += text;
  }
  for (size_t k = 0; k < 2; ++k)
    EXPECT_TRUE(errors[k] < tolerance || errors[k + 1] < errors[k] / 30)
        << where << " (not second order)";
  EXPECT_LT(*std::min_element(errors.begin(), errors.end()), tolerance) << where;
}

// The same for the derivative of a scalar function f along d at x (exact: ∇f(x) · d).
inline void expect_slope_matches(const std::function<double(const Eigen::VectorXd&)>& f,
                                 const Eigen::VectorXd& x, const Eigen::VectorXd& d, double exact,
                                 const std::string& what, double tolerance = 1e-6,
                                 double largest_step = 1e-3) {
  expect_matches_centred_differences(
      Eigen::VectorXd::Constant(1, exact),
      [&](double h) {
        return Eigen::VectorXd::Constant(1, (f(x + h * d) - f(x - h * d)) / (2 * h));
      },
      what, tolerance, largest_step);
}

// The same for the derivative of a vector function g along d at x (exact: ∇g(x) d).
inline void expect_derivative_matches(
    const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& g, const Eigen::VectorXd& x,
    const Eigen::VectorXd& d, const Eigen::VectorXd& exact, const std::string& what,
    double tolerance = 1e-6, double largest_step = 1e-3) {
  expect_matches_centred_differences(
      exact, [&](double h) { return Eigen::VectorXd((g(x + h * d) - g(x - h * d)) / (2 * h)); },
      what, tolerance, largest_step);
}

// An energy's derivatives at x, each from the one below it: ∇E(x) · d from E, ∇²E(x) d from ∇E,
// ∇³E(x)(u, d) from ∇²E(x) d.
inline void expect_gradient_matches(const Energy& energy, const Eigen::VectorXd& x,
                                    const Eigen::VectorXd& d, const std::string& where,
                                    double tolerance = 1e-6, double largest_step = 1e-3) {
  Eigen::VectorXd gradient(x.size());
  energy.value_and_gradient(x, gradient);
  expect_slope_matches([&](const Eigen::VectorXd& y) { return energy.value(y); }, x, d,
                       gradient.dot(d), "gradient, " + where, tolerance, largest_step);
}

inline void expect_hessian_matches(const Energy& energy, const Eigen::VectorXd& x,
                                   const Eigen::VectorXd& d, const std::string& where,
                                   double tolerance = 1e-6, double largest_step = 1e-3) {
  const auto gradient = [&](const Eigen::VectorXd& y) {
    Eigen::VectorXd g(y.size());
    energy.value_and_gradient(y, g);
    return g;
  };
  expect_derivative_matches(gradient, x, d, energy.hessian(x) * d, "Hessian, " + where, tolerance,
                            largest_step);
}

inline void expect_third_matches(const Energy& energy, const Eigen::VectorXd& x,
                                 const Eigen::VectorXd& u, const Eigen::VectorXd& d,
                                 const std::string& where, double tolerance = 1e-6,
                                 double largest_step = 1e-3) {
  expect_derivative_matches(
      [&](const Eigen::VectorXd& y) { return Eigen::VectorXd(energy.hessian(y) * d); }, x, u,
      energy.third(x, u, d), "third, " + where, tolerance, largest_step);
}

}  // namespace modal_deform::testing
