#include "solve/full_solver.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "linalg/cholmod_llt.h"
#include "mesh/mass.h"
#include "mesh/mesh_check.h"
#include "mesh/normalization.h"
#include "util/errors.h"
#include "util/require_positions.h"
#include "util/require_weight.h"

namespace modal_deform {
namespace {

constexpr double kPi = 3.14159265358979323846;
// The most load steps a solve takes: a handle moved farther than 10 diagonals moves by more than a
// tenth of the diagonal per step (a move of 1e6 diagonals, a typo in a transform, would otherwise
// take 1e7 steps and hang the caller).
constexpr int kMaxLoadSteps = 100;

// F(y) = E(y) + E_C(y), with ∇F(y) written into `gradient`.
double objective(const Energy& energy, const HandleTerm& handle_term, const Eigen::VectorXd& y,
                 Eigen::VectorXd& gradient) {
  const double value = energy.value_and_gradient(y, gradient);
  return value + handle_term.add_value_and_gradient(y, gradient);
}

// Transforms of mesh units as transforms of the normalised frame y = s x.
Transforms normalised(Transforms transforms, double s) {
  for (Eigen::Matrix4d& T : transforms) T.topRightCorner<3, 1>() *= s;
  return transforms;
}

// T a fraction `t` of the way from the identity: the rotation by t times its angle about the
// handle's centre c, which moves along the straight line to T(c).
Eigen::Matrix4d partial_transform(const Eigen::Matrix4d& T, const Eigen::Vector3d& c, double t) {
  const Eigen::AngleAxisd rotation(Eigen::Matrix3d(T.topLeftCorner<3, 3>()));
  const Eigen::Matrix3d R = Eigen::AngleAxisd(t * rotation.angle(), rotation.axis()).toRotationMatrix();
  const Eigen::Vector3d moved = T.topLeftCorner<3, 3>() * c + T.topRightCorner<3, 1>();
  Eigen::Matrix4d partial = Eigen::Matrix4d::Identity();
  partial.topLeftCorner<3, 3>() = R;
  partial.topRightCorner<3, 1>() = c + t * (moved - c) - R * c;
  return partial;
}

}  // namespace

FullSolveResult solve_full(const VerticesRef& V, const FacesRef& F, const Handles& handles, const VectorRef& weights,
                           const Transforms& transforms, double stiffness, EnergyKind energy_kind, double bending,
                           double membrane, double tolerance, int max_iterations, const RowMatrixX3d* initial) {
  validate_mesh(V, F);  // before the handles, which index into it
  const int n = static_cast<int>(V.rows());
  const Eigen::VectorXd handle_weights = checked_handle_weights(handles, weights, n);
  check_transforms(transforms, static_cast<int>(handles.size()));
  require_stiffness(stiffness);
  if (!(tolerance > 0 && tolerance < 1))
    throw InputError(message("tolerance: expected a value in (0, 1), got ", tolerance));
  if (max_iterations < 0) throw InputError(message("max_iterations: expected at least 0, got ", max_iterations));
  if (initial) require_positions(flatten(*initial), 3 * n, "initial");
  const double s = normalizing_scale(V);
  const RowMatrixX3d rest = s * V;
  const std::unique_ptr<Energy> energy = make_energy(energy_kind, rest, F, bending, membrane);
  const Eigen::VectorXd mass = lumped_mass(V, F);

  // E_C in the normalised frame: masses s²m, coefficient μ. Its Hessian is constant and diagonal.
  HandleTerm handle_term(rest, s * s * mass, handles, handle_weights, stiffness);
  const Eigen::VectorXd handle_diagonal = handle_term.hessian_diagonal(n);
  // D of the Hessian modification, and a fixed diagonal for the coordinates of vertices in no
  // energy term and no handle (no mass, zero Hessian block): nothing moves them.
  Eigen::VectorXd y = flatten(rest);
  const SparseMatrix rest_hessian = energy->hessian(y);
  const Eigen::VectorXd hessian_diagonal = rest_hessian.diagonal();
  Eigen::VectorXd D(3 * n);
  for (int v = 0; v < n; ++v) D.segment<3>(3 * v).setConstant(s * s * mass[v]);
  const double mean_mass = D.mean();
  D = D.cwiseMax(1e-6 * mean_mass);
  Eigen::VectorXd fixed = Eigen::VectorXd::Zero(3 * n);
  for (int v = 0; v < n; ++v)
    if (mass[v] == 0 && hessian_diagonal.segment<3>(3 * v).isZero(0) && handle_diagonal.segment<3>(3 * v).isZero(0))
      fixed.segment<3>(3 * v).setConstant(mean_mass);
  // The smallest τ tried: 1e-8 of the mean curvature per unit mass at rest.
  const double tau_min = 1e-8 * (hessian_diagonal + handle_diagonal).cwiseAbs().mean() / mean_mass;

  // Load steps: each turns a handle by at most 30° about its centre and moves the centre by at
  // most a tenth of the bounding-box diagonal.
  std::vector<Eigen::Vector3d> centres;
  int steps = 1;
  if (!initial) {
    const double diagonal = (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
    for (size_t h = 0; h < handles.size(); ++h) {
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (int v : handles[h]) c += V.row(v).transpose();
      c /= static_cast<double>(handles[h].size());
      centres.push_back(c);
      const Eigen::AngleAxisd rotation(Eigen::Matrix3d(transforms[h].topLeftCorner<3, 3>()));
      const double move = (transforms[h].topLeftCorner<3, 3>() * c + transforms[h].topRightCorner<3, 1>() - c).norm();
      const double wanted = std::max(std::abs(rotation.angle()) / (kPi / 6), move / (0.1 * diagonal));
      steps = std::max(steps, static_cast<int>(std::ceil(std::min<double>(wanted - 1e-9, kMaxLoadSteps))));
    }
  }

  FullSolveResult result;
  result.steps = steps;
  Eigen::VectorXd gradient(3 * n), y_trial(3 * n), gradient_trial(3 * n), shift(3 * n), p(3 * n);
  handle_term.set_transforms(normalised(transforms, s));
  double value = objective(*energy, handle_term, y, gradient);
  result.gradient_scale = gradient.norm();
  if (initial) {
    y = s * flatten(*initial);
    objective(*energy, handle_term, y, gradient);
    result.gradient_scale = std::max(result.gradient_scale, gradient.norm());
  }
  const double target = tolerance * result.gradient_scale;
  CholmodLLT llt(3);
  llt.analyze(rest_hessian);
  double tau = 0;
  for (int step = 1; step <= steps; ++step) {
    Transforms partial = transforms;
    if (step < steps)
      for (size_t h = 0; h < handles.size(); ++h)
        partial[h] = partial_transform(transforms[h], centres[h], double(step) / steps);
    handle_term.set_transforms(normalised(partial, s));
    value = objective(*energy, handle_term, y, gradient);
    for (int iteration = 0; iteration < max_iterations && gradient.norm() > target; ++iteration) {
      const SparseMatrix H = energy->hessian(y);
      tau = tau / 10 >= tau_min ? tau / 10 : 0;
      for (int attempt = 0;; ++attempt) {
        shift = handle_diagonal + fixed + tau * D;
        ++result.factorizations;
        try {
          llt.factorize(H, shift);
          break;
        } catch (const NumericalError&) {
          if (attempt == 60) throw NumericalError("solve_full: no shift of the Hessian could be factored");
          tau = std::max(10 * tau, tau_min);
        }
      }
      p = -llt.solve(gradient);
      const double slope = gradient.dot(p);
      // Near the solution the decrease a step promises falls below the rounding of F; then a
      // step that reduces the gradient norm is taken instead (it would otherwise creep on noise).
      const double noise = 1e-12 * (1 + std::abs(value));
      double length = 1;
      bool decreased = false;
      for (int halving = 0; halving < 60 && slope < 0; ++halving, length /= 2) {
        y_trial = y + length * p;
        if (!positions_in_range(y_trial)) continue;  // beyond what the energy takes: too long a step
        const double value_trial = objective(*energy, handle_term, y_trial, gradient_trial);
        if (value_trial <= value + 1e-4 * length * slope ||
            (-length * slope < noise && value_trial <= value + noise && gradient_trial.norm() < gradient.norm())) {
          decreased = true;
          value = value_trial;
          break;
        }
      }
      if (!decreased) break;  // F cannot decrease at this precision along the Newton direction
      y.swap(y_trial);
      gradient.swap(gradient_trial);
      ++result.iterations;
    }
  }
  result.energy = value;
  result.gradient_norm = gradient.norm();
  result.converged = result.gradient_norm <= target;
  result.positions = Eigen::Map<const RowMatrixX3d>(y.data(), n, 3) / s;
  return result;
}

}  // namespace modal_deform
