#include "solve/reduced_solver.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>

#include "reduction/region.h"
#include "util/errors.h"
#include "util/require_weight.h"

namespace modal_deform {
namespace {

double checked_stiffness(double stiffness) {
  check_option(kPull, stiffness);
  return stiffness;
}

const Basis& checked(const Basis& basis) {
  validate_basis(basis);
  return basis;
}

}  // namespace

ReducedSolver::ReducedSolver(const Basis& basis, const Handles& handles, const VectorRef& weights,
                             double stiffness, EnergyKind energy, bool warm_start)
    : basis_(checked(basis)),
      num_handles_(static_cast<int>(handles.size())),
      ghost_energy_(basis, energy),
      handle_term_(
          HandleTerm(basis.rest, basis.mass, handles,
                     checked_handle_weights(handles, weights, basis.num_vertices()),
                     checked_stiffness(stiffness) * std::pow(basis.scale, 4)),
          [&basis](int v) { return basis.vertex_rows(v); }, basis.dimension()) {
  require_handles_in_region(handles, basis.region);
  const Eigen::Index r = basis.dimension();
  if (warm_start) {
    Eigen::MatrixXd H = ghost_energy_.rest_hessian() + handle_term_.hessian();
    H = 0.5 * (H + H.transpose()).eval();
    const double largest = H.diagonal().maxCoeff();
    H.diagonal().array() += largest > 0 ? 1e-8 * largest : 1.0;
    const Eigen::LLT<Eigen::MatrixXd> llt(H);
    if (llt.info() != Eigen::Success)
      throw NumericalError(
          "reduced solver: the reduced Hessian at rest is not positive semidefinite");
    initial_inverse_hessian_ = llt.solve(Eigen::MatrixXd::Identity(r, r));
    initial_inverse_hessian_ =
        0.5 * (initial_inverse_hessian_ + initial_inverse_hessian_.transpose()).eval();
  } else {
    initial_inverse_hessian_ = Eigen::MatrixXd::Identity(r, r);
  }
  handle_gradient_.resize(r);
  handle_gradient_old_.resize(r);
  reset();
}

void ReducedSolver::set_transforms(const Transforms& transforms) {
  check_transforms(transforms, num_handles_);
  // Only the handle term changes: tell BFGS by how much at the current q, in O(r²).
  const double old_value = handle_term_.value_and_gradient(q(), handle_gradient_old_);
  handle_term_.set_transforms(transforms);
  const double new_value = handle_term_.value_and_gradient(q(), handle_gradient_);
  handle_gradient_ -= handle_gradient_old_;
  bfgs_.objective_changed(new_value - old_value, handle_gradient_);
}

ReducedSolveStats ReducedSolver::solve(const ReducedSolveOptions& options) {
  check_options(options, [](auto visit) { for_each_reduced_solve_option(visit); });
  return solve(options.max_iterations, options.tolerance, options.budget_ms);
}

ReducedSolveStats ReducedSolver::solve(int max_iterations, double tolerance, double budget_ms) {
  const auto start = std::chrono::steady_clock::now();
  const BfgsResult result =
      bfgs_.minimize([this](const Eigen::VectorXd& q,
                            Eigen::VectorXd& gradient) { return objective(q, gradient); },
                     max_iterations, tolerance, budget_ms);
  ReducedSolveStats stats;
  stats.iterations = result.iterations;
  stats.evaluations = result.evaluations;
  stats.converged = result.converged;
  stats.stalled = result.stalled;
  stats.line_search_failures = result.line_search_failures;
  stats.energy = bfgs_.value();
  stats.gradient_norm = bfgs_.gradient().norm();
  stats.ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

void ReducedSolver::reset() {
  bfgs_.start(Eigen::VectorXd::Zero(dimension()), initial_inverse_hessian_);
}

void ReducedSolver::positions(Eigen::Ref<Eigen::VectorXf> out) const {
  if (!fine_positions_) fine_positions_ = std::make_unique<FinePositions>(basis_);
  fine_positions_->write(q().cast<float>(), out);
}

double ReducedSolver::objective(const Eigen::VectorXd& q, Eigen::VectorXd& gradient) {
  const double energy = ghost_energy_.value_and_gradient(q, gradient);
  if (!std::isfinite(energy)) return energy;
  const double handles = handle_term_.value_and_gradient(q, handle_gradient_);
  gradient += handle_gradient_;
  return energy + handles;
}

}  // namespace modal_deform
