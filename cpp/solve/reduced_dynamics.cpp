#include "solve/reduced_dynamics.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <limits>

#include "reduction/region.h"
#include "util/errors.h"
#include "util/math_constants.h"
#include "util/require_positions.h"
#include "util/require_weight.h"

namespace modal_deform {
namespace {

// An eigenvalue of the reduced rest Hessian below this fraction of the largest is a rigid motion's
// or a mechanism's (numerically zero), not a flexible mode's.
constexpr double kZeroEigenvalue = 1e-8;

const Basis& checked(const Basis& basis) {
  validate_basis(basis);
  return basis;
}

const SimulationOptions& checked(const SimulationOptions& options) {
  check_options(options, [](auto visit) { for_each_simulation_option(visit); });
  return options;
}

// The handles' weights; a free body has neither handles nor weights.
Eigen::VectorXd checked_weights(const Handles& handles, const VectorRef& weights,
                                int num_vertices) {
  if (!handles.empty()) return checked_handle_weights(handles, weights, num_vertices);
  if (weights.size() != 0)
    throw InputError(
        message("weights: expected none (no handles: a free body), got ", weights.size()));
  return Eigen::VectorXd();
}

}  // namespace

DynamicsParameters dynamics_parameters(const Eigen::MatrixXd& hessian,
                                       const SimulationOptions& options) {
  const Eigen::Index r = hessian.rows();
  DynamicsParameters parameters;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(hessian);
  if (eigen.info() != Eigen::Success)
    throw NumericalError("simulation: the reduced rest Hessian has no eigenvalues");
  const double largest = eigen.eigenvalues().maxCoeff();
  Eigen::Index lowest = 0;
  while (lowest < r && !(eigen.eigenvalues()[lowest] > kZeroEigenvalue * largest)) ++lowest;
  if (lowest == r || !(largest > 0))
    throw InputError(
        "basis: no flexible mode (every direction of the basis is a rigid motion or a mechanism); "
        "the period is that of the lowest flexible mode");
  const double lowest_eigenvalue = eigen.eigenvalues()[lowest];
  parameters.lowest_mode = eigen.eigenvectors().col(lowest);

  // The poles the artist asks for, and the model's that the midpoint rule maps onto them.
  const double h = 1.0 / (options.fps * options.substeps);
  const double omega = 2 * kPi * options.fps / options.period;
  const std::complex<double> root =
      std::sqrt(std::complex<double>(options.damping * options.damping - 1, 0));
  std::complex<double> product = 1, sum = 0;
  for (const double sign : {1.0, -1.0}) {
    const std::complex<double> pole = omega * (-options.damping + sign * root);
    const std::complex<double> model_pole = (2 / h) * std::tanh(pole * (h / 2));
    product *= model_pole;
    sum += model_pole;
  }
  parameters.substep = h;
  parameters.mass_scale = lowest_eigenvalue / product.real();
  parameters.rayleigh = -sum.real() / product.real();
  // Options each within its range may together leave double precision (ρ and the frame's length
  // squared grow as fps⁻²): refused, naming them, rather than a simulation of infinities. The
  // midpoint rule and implicit Euler weigh the potential by h²/(4ρ) and h²/ρ, the damping by
  // 2β/h, and the rig's second difference divides by the frame's length squared.
  const double frame = 1 / options.fps;
  const double weight = h * h / parameters.mass_scale;
  if (!(std::isfinite(frame * frame) && std::isfinite(parameters.mass_scale) &&
        parameters.mass_scale > 0 && std::isfinite(parameters.rayleigh) &&
        std::isfinite(weight) && weight / 4 > 0 && std::isfinite(2 * parameters.rayleigh / h)))
    throw InputError(message("fps = ", options.fps, ", period = ", options.period,
                             ", damping = ", options.damping, ", substeps = ", options.substeps,
                             ": the mass scale (", parameters.mass_scale, "), the damping (",
                             parameters.rayleigh, " s) or the substep (", h,
                             " s) they give is beyond double precision (raise fps)"));
  return parameters;
}

ReducedHandleTerm dynamics_handle_term(const Basis& basis, const Handles& handles,
                                       const Eigen::VectorXd& weights, double pull) {
  return ReducedHandleTerm(
      HandleTerm(basis.rest, basis.mass, handles, weights, pull * std::pow(basis.scale, 4)),
      [&basis](int v) { return basis.vertex_rows(v); }, basis.dimension());
}

ReducedDynamics::ReducedDynamics(const Basis& basis, const Handles& handles,
                                 const VectorRef& weights, const SimulationOptions& options,
                                 EnergyKind energy, const SkinningWeights* rig)
    : basis_(checked(basis)),
      options_(checked(options)),
      ghost_energy_(basis, energy),
      handle_term_(dynamics_handle_term(
          basis, handles, checked_weights(handles, weights, basis.num_vertices()), options.pull)),
      transforms_(handles.size(), Eigen::Matrix4d::Identity()),
      fine_positions_(basis) {
  require_handles_in_region(handles, basis.region);
  for (const std::vector<int>& handle : handles) {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (int v : handle) centre += basis.rest.row(v).transpose();
    centres_.push_back(centre / static_cast<double>(handle.size()));
  }
  const Eigen::Index r = basis.dimension();
  if (rig) {
    rig_ = std::make_unique<RigForces>(basis, *rig);
    rig_acceleration_ = Eigen::VectorXd::Zero(r);
  }
  // K = U_sᵀ ∇²E(x̄_s) U_s and its lowest flexible mode; on a rig, the lowest of the mesh as
  // attached, K plus the handles' term.
  Eigen::MatrixXd K = ghost_energy_.rest_hessian();
  K = 0.5 * (K + K.transpose()).eval();
  Eigen::MatrixXd attached;
  if (rig_) {
    attached = K + handle_term_.hessian();
    attached = 0.5 * (attached + attached.transpose()).eval();
  }
  DynamicsParameters parameters = dynamics_parameters(rig_ ? attached : K, options);
  mass_scale_ = parameters.mass_scale;
  rayleigh_ = parameters.rayleigh;
  h_ = parameters.substep;
  lowest_mode_ = std::move(parameters.lowest_mode);
  midpoint_weight_ = h_ * h_ / (4 * mass_scale_);
  euler_weight_ = h_ * h_ / mass_scale_;
  midpoint_inverse_hessian_ = inverse_rest_hessian(K, midpoint_weight_, 1 + 2 * rayleigh_ / h_);
  euler_inverse_hessian_ = inverse_rest_hessian(K, euler_weight_, 1);

  work_gradient_.resize(r);
  handle_gradient_.resize(r);
  set_state(Eigen::VectorXd::Zero(r), Eigen::VectorXd::Zero(r));
}

Eigen::MatrixXd ReducedDynamics::inverse_rest_hessian(const Eigen::MatrixXd& K,
                                                      double potential_weight,
                                                      double damping_weight) const {
  Eigen::MatrixXd H = (potential_weight * damping_weight) * (K + handle_term_.hessian());
  H.diagonal().array() += 1;
  H = 0.5 * (H + H.transpose()).eval();
  const Eigen::LLT<Eigen::MatrixXd> llt(H);
  if (llt.info() != Eigen::Success)
    throw NumericalError(
        "simulation: the incremental potential's Hessian at rest is not positive definite");
  Eigen::MatrixXd inverse = llt.solve(Eigen::MatrixXd::Identity(H.rows(), H.cols()));
  return 0.5 * (inverse + inverse.transpose());
}

void ReducedDynamics::positions_of(const Eigen::VectorXd& q,
                                   Eigen::Ref<Eigen::VectorXf> out) const {
  check_coordinates(q);
  fine_positions_.write(q.cast<float>(), out);
}

void ReducedDynamics::displacement_of(const Eigen::VectorXd& q,
                                      Eigen::Ref<Eigen::VectorXf> out) const {
  check_coordinates(q);
  fine_positions_.write_displacement(q.cast<float>(), out);
}

void ReducedDynamics::check_coordinates(const Eigen::VectorXd& q) const {
  if (q.size() != dimension())
    throw InputError(message("q: expected ", dimension(), " reduced coordinates, got ", q.size()));
}

void ReducedDynamics::set_state(const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                const Transforms& transforms, const Transforms& rig_previous,
                                const Transforms& rig_current) {
  const Eigen::Index r = dimension();
  if (q.size() != r)
    throw InputError(message("q: expected ", r, " reduced coordinates, got ", q.size()));
  if (v.size() != r)
    throw InputError(message("v: expected ", r, " reduced velocities, got ", v.size()));
  if (!q.allFinite()) throw InputError("q: has non-finite entries");
  if (!v.allFinite() || !std::isfinite(0.5 * mass_scale_ * v.squaredNorm()))
    throw InputError("v: has non-finite entries, or a kinetic energy beyond double precision");
  if (!transforms.empty()) check_transforms(transforms, num_handles());
  if (!rig_ && !(rig_previous.empty() && rig_current.empty()))
    throw InputError("bones: given to a simulation without a rig");
  if (rig_current.empty() && !rig_previous.empty())
    throw InputError("bones: the previous frame's bones given without the current ones");
  if (!rig_current.empty()) check_bone_matrices(rig_current, num_bones());
  if (!rig_previous.empty()) check_bone_matrices(rig_previous, num_bones());
  // No bones: no rig history (rig_current_ empty), as before the first frame.
  const Transforms& previous = rig_previous.empty() ? rig_current : rig_previous;
  const bool own_rig = rig_current == rig_current_ && previous == rig_previous_;
  // The simulation's own state (playback sets each frame's cached state before stepping from it)
  // is kept: its energy and gradient were evaluated there, at these transforms, by the last step,
  // and BFGS's memory is the one that step left.
  if (q_.size() == r && q == q_ && v == v_ && (transforms.empty() || transforms == transforms_) &&
      own_rig)
    return;
  Eigen::VectorXd gradient(r);
  const double elastic_energy = ghost_energy_.value_and_gradient(q, gradient);
  if (!std::isfinite(elastic_energy))
    throw InputError(message("q: moves the mesh beyond the coordinates the energies take (",
                             kMaxCoordinate, ")"));
  if (!transforms.empty()) {
    transforms_ = transforms;
    handle_term_.set_transforms(transforms_);
  }
  rig_previous_ = previous;
  rig_current_ = rig_current;
  forget();
  q_ = q;
  v_ = v;
  elastic_energy_ = elastic_energy;
  elastic_gradient_ = std::move(gradient);
  potential_ = elastic_energy + handle_term_.value_and_gradient(q_, handle_gradient_);
  fine_positions_.set(q_);
}

double ReducedDynamics::incremental_potential(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) {
  const double elastic_energy = ghost_energy_.value_and_gradient(x, work_gradient_);
  if (!std::isfinite(elastic_energy)) return elastic_energy;
  return incremental_potential(x, elastic_energy, work_gradient_, gradient);
}

double ReducedDynamics::incremental_potential(const Eigen::VectorXd& x, double elastic_energy,
                                              const Eigen::VectorXd& elastic_gradient,
                                              Eigen::VectorXd& gradient) {
  const double handles = handle_term_.value_and_gradient(x, handle_gradient_);
  gradient = x - prediction_;
  const double inertia = 0.5 * gradient.squaredNorm();
  gradient +=
      potential_weight_ * (damping_weight_ * (elastic_gradient + handle_gradient_) - damping_pull_);
  return inertia +
         potential_weight_ * (damping_weight_ * (elastic_energy + handles) - damping_pull_.dot(x));
}

Transforms ReducedDynamics::interpolated(const Transforms& target, double a) const {
  if (a == 1) return target;
  Transforms result(target.size());
  for (size_t h = 0; h < target.size(); ++h) {
    const Eigen::Matrix4d& from = transforms_[h];
    const Eigen::Matrix4d& to = target[h];
    const Eigen::Quaterniond rotation_from(Eigen::Matrix3d(from.topLeftCorner<3, 3>()));
    const Eigen::Quaterniond rotation_to(Eigen::Matrix3d(to.topLeftCorner<3, 3>()));
    const Eigen::Matrix3d R =
        rotation_from.normalized().slerp(a, rotation_to.normalized()).toRotationMatrix();
    const Eigen::Vector3d centre_from =
        from.topLeftCorner<3, 3>() * centres_[h] + from.topRightCorner<3, 1>();
    const Eigen::Vector3d centre_to =
        to.topLeftCorner<3, 3>() * centres_[h] + to.topRightCorner<3, 1>();
    result[h].setIdentity();
    result[h].topLeftCorner<3, 3>() = R;
    result[h].topRightCorner<3, 1>() = (1 - a) * centre_from + a * centre_to - R * centres_[h];
  }
  return result;
}

SimulationStepStats ReducedDynamics::step(const Transforms& transforms, const Transforms& bones) {
  const auto start = std::chrono::steady_clock::now();
  check_transforms(transforms, num_handles());
  if (rig_) {
    if (bones.empty()) throw InputError("bones: required on a rig, one matrix per bone");
    check_bone_matrices(bones, rig_->num_bones());
    // Before the first frame given, the rig was still in that frame's pose.
    if (rig_current_.empty()) rig_previous_ = rig_current_ = bones;
    rig_->acceleration(rig_previous_, rig_current_, bones, 1 / options_.fps, rig_acceleration_);
  } else if (!bones.empty()) {
    throw InputError("bones: given to a simulation without a rig");
  }
  SimulationStepStats stats;
  const int substeps = options_.substeps;
  Transforms substep_start = transforms_;
  if (remembered_frames_ == options_.memory_frames) forget();
  for (int k = 0; k < substeps; ++k) {
    const Transforms middle = interpolated(transforms, (k + 0.5) / substeps);
    const Transforms end = interpolated(transforms, static_cast<double>(k + 1) / substeps);
    substep(substep_start, middle, end, stats);
    substep_start = end;
  }
  transforms_ = transforms;
  if (rig_) {
    rig_previous_ = std::move(rig_current_);
    rig_current_ = bones;
  }
  fine_positions_.set(q_);
  ++remembered_frames_;
  stats.ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

void ReducedDynamics::forget() {
  midpoint_started_ = euler_started_ = false;
  remembered_frames_ = 0;
}

void ReducedDynamics::minimize(Bfgs& bfgs, bool& started,
                               const Eigen::MatrixXd& initial_inverse_hessian, Finish finish,
                               SimulationStepStats& stats) {
  // Φ changes from substep to substep by linear terms only: BFGS keeps what it learnt of its
  // curvature (the step's header comment says for how long).
  if (started)
    bfgs.move_to(q_);
  else
    bfgs.start(q_, initial_inverse_hessian);
  started = true;
  // From q_n, where the state holds E and ∇E: the first trial is the quasi-Newton step −H∇Φ(q_n),
  // for a quadratic energy the minimiser itself, at no evaluation of the ghost energy.
  Eigen::VectorXd gradient(q_.size());
  const double value = incremental_potential(q_, elastic_energy_, elastic_gradient_, gradient);
  bfgs.set_value_and_gradient(value, gradient);
  const BfgsResult result = bfgs.minimize(
      [this](const Eigen::VectorXd& x, Eigen::VectorXd& gradient) {
        return incremental_potential(x, gradient);
      },
      options_.max_iterations, options_.tolerance, std::numeric_limits<double>::infinity(), finish);
  stats.iterations += result.iterations;
  stats.evaluations += result.evaluations;
  stats.converged = stats.converged && result.converged;
  stats.stalled = stats.stalled || result.stalled;
  stats.line_search_failures += result.line_search_failures;
}

void ReducedDynamics::substep(const Transforms& start, const Transforms& middle,
                              const Transforms& end, SimulationStepStats& stats) {
  ++stats.substeps;
  const double energy_before = energy();
  // The midpoint rule: Φ over the middle state.
  prediction_ = q_ + (h_ / 2) * v_;
  // The rig's force ρ g, a linear term of Φ: −(h²/4) gᵀx, folded into the prediction.
  if (rig_) prediction_ += (h_ * h_ / 4) * rig_acceleration_;
  handle_term_.value_and_gradient(q_, handle_gradient_);
  damping_pull_ = (2 * rayleigh_ / h_) * (elastic_gradient_ + handle_gradient_);
  damping_weight_ = 1 + 2 * rayleigh_ / h_;
  potential_weight_ = midpoint_weight_;
  handle_term_.set_transforms(middle);
  // Its result is checked below: it may end on BFGS's predicted step, unevaluated (bfgs.h).
  minimize(midpoint_bfgs_, midpoint_started_, midpoint_inverse_hessian_, Finish::kPredicted, stats);
  const Eigen::VectorXd& middle_state = midpoint_bfgs_.x();
  Eigen::VectorXd q_next = 2 * middle_state - q_;
  Eigen::VectorXd v_next = (4 / h_) * (middle_state - q_) - v_;
  // The damping's work over the substep, h v_mᵀ F_d with F_d = (2β/h) ∇V(x, t_m) − damping_pull_
  // (∇V(x, t_m) from Φ's stationarity at x: no evaluation there): for a quadratic potential, what
  // the midpoint rule dissipates exactly. At least zero: damping gives no energy, even where V is
  // not convex.
  double dissipated = 0;
  if (rayleigh_ > 0) {
    const double ratio = (2 * rayleigh_ / h_) / damping_weight_;
    Eigen::VectorXd& damping_force = work_gradient_;
    damping_force = ratio * (damping_pull_ - (middle_state - prediction_) / potential_weight_);
    damping_force -= damping_pull_;
    dissipated = std::max(0.0, 2 * (middle_state - q_).dot(damping_force));
  }
  // The handles' work over the substep, at the middle state.
  handle_term_.set_transforms(start);
  double work = -handle_term_.value_and_gradient(middle_state, handle_gradient_);
  handle_term_.set_transforms(end);
  work += handle_term_.value_and_gradient(middle_state, handle_gradient_);
  // And the rig's force's, ρ gᵀ(q_{n+1} − q_n) (g constant over the substep).
  if (rig_) work += mass_scale_ * rig_acceleration_.dot(q_next - q_);
  Eigen::VectorXd gradient_next(q_.size());
  double elastic_next = ghost_energy_.value_and_gradient(q_next, gradient_next);
  double potential_next = elastic_next + handle_term_.value_and_gradient(q_next, handle_gradient_);
  // The energy the substep ends with: what it had, plus the handles' work, less the damping's.
  double target = energy_before + work - dissipated;
  if (!(potential_next <= energy_before + work)) {
    // The end state holds more energy than the step had (a non-quadratic energy's error, amplified
    // by an unconverged minimisation in a violent motion): take the substep by implicit Euler
    // instead, Φ_E(x) = ½‖x − q_n − h v_n‖² + (h²/ρ) V(x, t_{n+1}), undamped, from q_n. BFGS only
    // decreases Φ_E (it ends at an evaluated point), so V(q_{n+1}, t_{n+1}) ≤ Φ_E(q_n) ρ/h² =
    // ½ρ‖v_n‖² + V(q_n, t_{n+1}): within the energy the step had plus the handles' work at q_n, and
    // the correction below brings the total to the target from there. On a rig Φ_E has the
    // force's term −h² gᵀx, and the bound gains its work ρ gᵀ(q_{n+1} − q_n).
    ++stats.implicit_euler;
    prediction_ = q_ + h_ * v_;
    if (rig_) prediction_ += (h_ * h_) * rig_acceleration_;
    damping_pull_.setZero();
    damping_weight_ = 1;
    potential_weight_ = euler_weight_;
    minimize(euler_bfgs_, euler_started_, euler_inverse_hessian_, Finish::kEvaluated, stats);
    q_next = euler_bfgs_.x();
    v_next = (q_next - q_) / h_;
    handle_term_.set_transforms(start);
    work = -handle_term_.value_and_gradient(q_, handle_gradient_);
    handle_term_.set_transforms(end);
    work += handle_term_.value_and_gradient(q_, handle_gradient_);
    if (rig_) work += mass_scale_ * rig_acceleration_.dot(q_next - q_);
    elastic_next = ghost_energy_.value_and_gradient(q_next, gradient_next);
    potential_next = elastic_next + handle_term_.value_and_gradient(q_next, handle_gradient_);
    target = energy_before + work - dissipated;
  }
  // The energy correction: the velocity is scaled so that the total reaches the target, down by
  // all the kinetic energy at most, up by at most the kinetic energy itself (a near-zero velocity
  // is not blown up).
  const double kinetic_next = 0.5 * mass_scale_ * v_next.squaredNorm();
  const double change =
      std::clamp(target - potential_next - kinetic_next, -kinetic_next, kinetic_next);
  if (change != 0) {
    v_next *= std::sqrt((kinetic_next + change) / kinetic_next);
    (change > 0 ? stats.energy_added : stats.energy_removed) += std::abs(change);
  }
  q_ = std::move(q_next);
  v_ = std::move(v_next);
  elastic_energy_ = elastic_next;
  elastic_gradient_ = std::move(gradient_next);
  potential_ = potential_next;
}

}  // namespace modal_deform
