#include "solve/reduced_solver.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "mesh/normalization.h"
#include "reduction/region.h"
#include "util/errors.h"
#include "util/require_positions.h"
#include "util/require_weight.h"

namespace modal_deform {
namespace {

double checked_stiffness(double stiffness) {
  require_stiffness(stiffness);
  return stiffness;
}

const Basis& checked(const Basis& basis) {
  validate_basis(basis);
  return basis;
}

}  // namespace

ReducedSolver::ReducedSolver(const Basis& basis, const Handles& handles, const VectorRef& weights, double stiffness,
                             EnergyKind energy, bool warm_start)
    : basis_(checked(basis)),
      num_handles_(static_cast<int>(handles.size())),
      energy_(make_energy(energy, basis.scale * basis.ghost_vertices, basis.ghost_faces, ghost_material(basis))),
      ghost_rest_(basis.scale * flatten(basis.ghost_vertices)),
      ghost_vectors_(basis.scale * basis.ghost_vectors),
      handle_term_(HandleTerm(basis.rest, basis.mass, handles,
                              checked_handle_weights(handles, weights, basis.num_vertices()),
                              checked_stiffness(stiffness) * std::pow(basis.scale, 4)),
                   [&basis](int v) { return basis.vertex_rows(v); }, basis.dimension()),
      quantized_vectors_(basis.vectors),
      map_tolerance_(kMapTolerance * bounding_box_diagonal(basis.rest)) {
  require_handles_in_region(handles, basis.region);
  const Eigen::Index r = basis.dimension();
  if (warm_start) {
    const SparseMatrix K = energy_->hessian(ghost_rest_);
    const Eigen::MatrixXd KU = K * ghost_vectors_;
    Eigen::MatrixXd H = ghost_vectors_.transpose() * KU + handle_term_.hessian();
    H = 0.5 * (H + H.transpose()).eval();
    const double largest = H.diagonal().maxCoeff();
    H.diagonal().array() += largest > 0 ? 1e-8 * largest : 1.0;
    const Eigen::LLT<Eigen::MatrixXd> llt(H);
    if (llt.info() != Eigen::Success)
      throw NumericalError("reduced solver: the reduced Hessian at rest is not positive semidefinite");
    initial_inverse_hessian_ = llt.solve(Eigen::MatrixXd::Identity(r, r));
    initial_inverse_hessian_ = 0.5 * (initial_inverse_hessian_ + initial_inverse_hessian_.transpose()).eval();
  } else {
    initial_inverse_hessian_ = Eigen::MatrixXd::Identity(r, r);
  }
  ghost_x_.resize(ghost_rest_.size());
  ghost_gradient_.resize(ghost_rest_.size());
  handle_gradient_.resize(r);
  handle_gradient_old_.resize(r);
  if (basis.on_proxy()) proxy_displacement_.resize(basis.vectors.rows());
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

ReducedSolveStats ReducedSolver::solve(int max_iterations, double tolerance, double budget_ms) {
  const auto start = std::chrono::steady_clock::now();
  const BfgsResult result =
      bfgs_.minimize([this](const Eigen::VectorXd& q, Eigen::VectorXd& gradient) { return objective(q, gradient); },
                     max_iterations, tolerance, budget_ms);
  q_float_ = q().cast<float>();
  ReducedSolveStats stats;
  stats.iterations = result.iterations;
  stats.evaluations = result.evaluations;
  stats.converged = result.converged;
  stats.stalled = result.stalled;
  stats.line_search_failures = result.line_search_failures;
  stats.energy = bfgs_.value();
  stats.gradient_norm = bfgs_.gradient().norm();
  stats.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

void ReducedSolver::reset() {
  bfgs_.start(Eigen::VectorXd::Zero(dimension()), initial_inverse_hessian_);
  q_float_ = Eigen::VectorXf::Zero(dimension());
}

double ReducedSolver::objective(const Eigen::VectorXd& q, Eigen::VectorXd& gradient) {
  ghost_x_.noalias() = ghost_vectors_ * q;
  ghost_x_ += ghost_rest_;
  if (!positions_in_range(ghost_x_)) return std::numeric_limits<double>::infinity();
  const double energy = energy_->value_and_gradient(ghost_x_, ghost_gradient_);
  gradient.noalias() = ghost_vectors_.transpose() * ghost_gradient_;
  const double handles = handle_term_.value_and_gradient(q, handle_gradient_);
  gradient += handle_gradient_;
  return energy + handles;
}

void ReducedSolver::positions(Eigen::Ref<Eigen::VectorXf> out) const {
  const Eigen::Index fine_rows = 3 * static_cast<Eigen::Index>(basis_.num_vertices());
  if (out.size() != fine_rows)
    throw InputError(message("out: expected ", fine_rows, " values (3 per vertex), got ", out.size()));
  if (!basis_.on_proxy()) {
    quantized_vectors_.map(basis_.vectors, q_float_, basis_.rest.data(), map_tolerance_, out.data());
    return;
  }
  // On a proxy: its displacement U q, then x̄ + P (U q) on the fine vertices (convex weights: the
  // displacement's error bound holds there too).
  quantized_vectors_.map(basis_.vectors, q_float_, nullptr, map_tolerance_, proxy_displacement_.data());
  prolongate_positions(basis_.prolongation, basis_.rest.data(), proxy_displacement_.data(), out.data());
}

}  // namespace modal_deform
