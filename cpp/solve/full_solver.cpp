#include "solve/full_solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <vector>

#include "linalg/cholmod_llt.h"
#include "mesh/mass.h"
#include "mesh/mesh_check.h"
#include "mesh/normalization.h"
#include "solve/line_search.h"
#include "util/errors.h"
#include "util/require_positions.h"
#include "util/require_weight.h"

namespace modal_deform {
namespace {

constexpr double kPi = 3.14159265358979323846;
// The fewest load steps a long motion is cut into is at most this (a move of 1e6 diagonals, a
// typo in a transform, would otherwise start with a step of a millionth of the way).
constexpr int kMaxLoadSteps = 100;
// Intermediate loads need only be near their minimum: the next load's Newton steps start there.
constexpr double kIntermediateTolerance = 1e-3;
// Newton iterations an intermediate load step may take before the path moves on regardless.
constexpr int kIterationsPerIntermediateStep = 20;
// Above this many iterations a load step was hard: the next increment is halved; at most
// kFewIterations, it was easy: the next one doubles.
constexpr int kManyIterations = 10;
constexpr int kFewIterations = 4;
// Consecutive Newton iterations without progress (ShiftedNewton::iterate) after which the solve
// is taken to be as far as working precision goes: each grows τ, shrinking the step towards
// steepest descent, and at a kink of F (a triangle collapsed, its bending terms' angles
// undefined) F stops decreasing while ‖∇F‖ does not fall.
constexpr int kMaxStalledIterations = 3;
// Newton uses the exact Hessian once ‖∇F‖ is below this fraction of its scale (quadratic
// convergence near the minimum), the projected one above it (each element's Hessian made
// semidefinite: a sliver hinge bent far from rest is strongly indefinite, and the shift that
// would make the exact Hessian definite damps the whole mesh; on the 5k dragon it reached 1e5
// times the mean curvature, and iterations crept).
constexpr double kExactHessianBelow = 1e-3;
// From rest, the first load step is this fraction of the suggested one.
constexpr double kFirstStepDivisor = 6;

// F, its gradient, and the parts of its Hessian that do not change, in the normalised frame.
class PoseObjective {
 public:
  PoseObjective(const VerticesRef& V, const FacesRef& F, const Handles& handles, const Eigen::VectorXd& weights,
                double stiffness, const FullSolveOptions& options)
      : scale_(normalizing_scale(V)),
        rest_(scale_ * V),
        energy_(make_energy(options.energy, rest_, F, options.bending, options.membrane, options.paint)),
        handle_term_(rest_, scale_ * scale_ * lumped_mass(V, F), handles, weights, stiffness),
        faces_(F) {
    const int n = static_cast<int>(V.rows());
    const Eigen::VectorXd mass = lumped_mass(V, F);
    const Eigen::VectorXd handle_diagonal = handle_term_.hessian_diagonal(n);
    const Eigen::VectorXd hessian_diagonal = energy_->hessian(rest_positions()).diagonal();
    mass_diagonal_.resize(3 * n);
    for (int v = 0; v < n; ++v) mass_diagonal_.segment<3>(3 * v).setConstant(scale_ * scale_ * mass[v]);
    const double mean_mass = mass_diagonal_.mean();
    mass_diagonal_ = mass_diagonal_.cwiseMax(1e-6 * mean_mass);
    // Coordinates of vertices in no energy term and no handle (no mass, a zero Hessian block)
    // get a fixed diagonal: nothing moves them.
    constant_diagonal_ = handle_diagonal;
    for (int v = 0; v < n; ++v)
      if (mass[v] == 0 && hessian_diagonal.segment<3>(3 * v).isZero(0) && handle_diagonal.segment<3>(3 * v).isZero(0))
        constant_diagonal_.segment<3>(3 * v).setConstant(mean_mass);
    smallest_shift_ = 1e-8 * (hessian_diagonal + handle_diagonal).cwiseAbs().mean() / mean_mass;
  }

  double scale() const { return scale_; }
  Eigen::VectorXd rest_positions() const { return flatten(rest_); }
  const Energy& energy() const { return *energy_; }
  // D: the normalised lumped mass per coordinate, the shape of the Hessian's shift.
  const Eigen::VectorXd& mass_diagonal() const { return mass_diagonal_; }
  // The handle term's Hessian (diagonal, constant) and the fixed unreferenced coordinates.
  const Eigen::VectorXd& constant_diagonal() const { return constant_diagonal_; }
  // The smallest shift τ used: 1e-8 of the mean curvature per unit mass at rest.
  double smallest_shift() const { return smallest_shift_; }

  // Whether a triangle turns over between y and y_new: its normal reverses (a triangle with no
  // normal at y, collapsed already, is not counted). F has a kink where a triangle collapses (its
  // hinges' angles flip by π as its normal does), and a step through it lands beyond the smooth
  // part of F that Newton's method can converge in, often lower: iterates are kept out of it.
  bool turns_a_triangle_over(const Eigen::VectorXd& y, const Eigen::VectorXd& y_new) const {
    for (Eigen::Index f = 0; f < faces_.rows(); ++f) {
      const int a = faces_(f, 0), b = faces_(f, 1), c = faces_(f, 2);
      const Eigen::Vector3d n =
          (y.segment<3>(3 * b) - y.segment<3>(3 * a)).cross(y.segment<3>(3 * c) - y.segment<3>(3 * a));
      const Eigen::Vector3d n_new =
          (y_new.segment<3>(3 * b) - y_new.segment<3>(3 * a)).cross(y_new.segment<3>(3 * c) - y_new.segment<3>(3 * a));
      if (n.dot(n_new) < 0) return true;
    }
    return false;
  }

  // Transforms in mesh units, applied to the handle term in the normalised frame.
  void set_transforms(Transforms transforms) {
    for (Eigen::Matrix4d& T : transforms) T.topRightCorner<3, 1>() *= scale_;
    handle_term_.set_transforms(transforms);
  }

  // F(y), ∇F(y) written into `gradient`; +inf where y is beyond what the energy takes.
  double operator()(const Eigen::VectorXd& y, Eigen::VectorXd& gradient) const {
    if (!positions_in_range(y)) return std::numeric_limits<double>::infinity();
    const double value = energy_->value_and_gradient(y, gradient);
    return value + handle_term_.add_value_and_gradient(y, gradient);
  }

 private:
  double scale_;
  RowMatrixX3d rest_;
  std::unique_ptr<Energy> energy_;
  HandleTerm handle_term_;
  Eigen::VectorXd mass_diagonal_, constant_diagonal_;
  double smallest_shift_ = 0;
  RowMatrixX3i faces_;
};

// The handles' transforms a fraction t of the way from the identity: each rotation by t times its
// angle about the handle's centre c, which moves along the straight line to T(c).
class LoadPath {
 public:
  LoadPath(const VerticesRef& V, const Handles& handles, const Transforms& transforms) : transforms_(transforms) {
    const double diagonal = (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
    for (size_t h = 0; h < handles.size(); ++h) {
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (int v : handles[h]) c += V.row(v).transpose();
      c /= static_cast<double>(handles[h].size());
      centres_.push_back(c);
      const Eigen::AngleAxisd rotation(Eigen::Matrix3d(transforms[h].topLeftCorner<3, 3>()));
      const double move = (transforms[h].topLeftCorner<3, 3>() * c + transforms[h].topRightCorner<3, 1>() - c).norm();
      const double wanted = std::max(std::abs(rotation.angle()) / (kPi / 6), move / (0.1 * diagonal));
      steps_ = std::max(steps_, static_cast<int>(std::ceil(std::min<double>(wanted - 1e-9, kMaxLoadSteps))));
    }
  }

  // Steps of at most 30° and a tenth of the diagonal per handle (at most kMaxLoadSteps).
  int suggested_steps() const { return steps_; }

  Transforms at(double t) const {
    if (t >= 1) return transforms_;
    Transforms partial(transforms_.size());
    for (size_t h = 0; h < transforms_.size(); ++h) {
      const Eigen::Matrix4d& T = transforms_[h];
      const Eigen::Vector3d& c = centres_[h];
      const Eigen::AngleAxisd rotation(Eigen::Matrix3d(T.topLeftCorner<3, 3>()));
      const Eigen::Matrix3d R = Eigen::AngleAxisd(t * rotation.angle(), rotation.axis()).toRotationMatrix();
      const Eigen::Vector3d moved = T.topLeftCorner<3, 3>() * c + T.topRightCorner<3, 1>();
      partial[h].setIdentity();
      partial[h].topLeftCorner<3, 3>() = R;
      partial[h].topRightCorner<3, 1>() = c + t * (moved - c) - R * c;
    }
    return partial;
  }

 private:
  Transforms transforms_;
  std::vector<Eigen::Vector3d> centres_;
  int steps_ = 1;
};

// Newton iterations on ∇²F + τD, keeping CHOLMOD's analysis of the Hessian's pattern and τ from
// one iteration (and load step) to the next.
class ShiftedNewton {
 public:
  explicit ShiftedNewton(const PoseObjective& objective)
      : objective_(objective), llt_(3), shift_(objective.smallest_shift()) {
    const int size = static_cast<int>(objective.mass_diagonal().size());
    step_.resize(size);
    y_new_.resize(size);
    gradient_new_.resize(size);
  }

  int factorizations() const { return factorizations_; }

  // One iteration from y (F(y) = value, ∇F(y) = gradient), all three updated. Near the minimum
  // (`near_minimum`) the exact Hessian is tried first, at the current τ only: where it is not
  // definite there (a flap still bent far from rest), the projected one (Energy::projected_hessian)
  // serves instead for the next kRetryExactAfter iterations. Growing τ until the exact Hessian
  // factors would damp the whole mesh (on the 23k dragon τ rose to 3e6 and the next ten
  // iterations crept). Returns whether it made progress: F fell by more than its
  // rounding, or ‖∇F‖ by half (near the minimum, where F's decrease is below rounding).
  bool iterate(Eigen::VectorXd& y, double& value, Eigen::VectorXd& gradient, bool near_minimum) {
    const Energy& energy = objective_.energy();
    const bool try_exact = near_minimum && ++since_exact_failed_ > kRetryExactAfter;
    const bool exact = try_exact && try_factorize(energy.hessian(y));
    if (try_exact && !exact) since_exact_failed_ = 0;
    if (!exact) factorize_shifted(energy.projected_hessian(y));
    llt_.solve(gradient, step_);
    step_ = -step_;
    const double slope = gradient.dot(step_);
    // The decrease the model F + ∇Fᵀp + ½pᵀ∇²F p promises: pᵀ(∇²F + τD)p = −∇Fᵀp gives it.
    const double predicted = -0.5 * slope + 0.5 * shift_ * step_.dot(objective_.mass_diagonal().cwiseProduct(step_));
    const double noise = 1e-12 * (1 + std::abs(value));
    double value_new = value;
    // A trial point that turns a triangle over counts as too far.
    const Objective within_smooth_part = [&](const Eigen::VectorXd& trial, Eigen::VectorXd& trial_gradient) {
      if (objective_.turns_a_triangle_over(y, trial)) return std::numeric_limits<double>::infinity();
      return objective_(trial, trial_gradient);
    };
    const BacktrackingResult search = backtracking_line_search(within_smooth_part, y, value, gradient, step_, y_new_,
                                                               value_new, gradient_new_, noise);
    failed_shift_ /= 3;  // the Hessian changes: a shift too small a while ago may do now
    if (search.step == 1) {
      const double ratio = (value - value_new) / predicted;
      shift_ = std::max({objective_.smallest_shift(), failed_shift_,
                         shift_ * std::max(0.1, 1 - std::pow(2 * ratio - 1, 3))});
      growth_ = 2;
    } else {
      // Too long a step: lean towards steepest descent. Where τD dominates the Hessian (the floppy
      // parts that made the step too long) the step shrinks as 1/τ, so τ grows at least by the
      // factor the line search cut the step by (from a poor start, τ must rise by ten orders of
      // magnitude, which doubling alone took ten iterations to reach).
      shift_ *= std::max(growth_, std::min(1 / search.step, kMaxCutGrowth));
      growth_ = std::min(2 * growth_, kMaxGrowth);
    }
    if (search.step == 0) return false;
    const bool progress = value - value_new > noise || gradient_new_.norm() < 0.5 * gradient.norm();
    y.swap(y_new_);
    gradient.swap(gradient_new_);
    value = value_new;
    return progress;
  }

 private:
  static constexpr double kMaxGrowth = 16;
  static constexpr double kMaxCutGrowth = 1e4;
  // Iterations on the projected Hessian after the exact one failed to factor before it is tried
  // again: the projected one converges only linearly (clamping the negative curvature of a bent
  // flap overestimates it), so the exact one is retried soon, at one factorisation's cost.
  static constexpr int kRetryExactAfter = 3;

  // Factors ∇²F + τD at the current τ; false (the matrix not definite) leaves τ as it is.
  bool try_factorize(const SparseMatrix& hessian) {
    ++factorizations_;
    try {
      llt_.factorize(hessian, objective_.constant_diagonal() + shift_ * objective_.mass_diagonal());
      return true;
    } catch (const NumericalError&) {
      return false;
    }
  }

  // Factors ∇²F + τD, τ grown tenfold until it factors.
  void factorize_shifted(const SparseMatrix& hessian) {
    for (int attempt = 0; !try_factorize(hessian); ++attempt) {
      if (attempt == 60) throw NumericalError("solve_full: no shift of the Hessian could be factored");
      failed_shift_ = std::max(failed_shift_, shift_);
      shift_ *= 10;
    }
  }

  const PoseObjective& objective_;
  CholmodLLT llt_;
  double shift_;       // τ
  double growth_ = 2;  // τ's factor after the next poor step (Nielsen's ν)
  // The largest τ that failed to factor lately (decaying): τ is not lowered below it, which would
  // only cost another failed factorisation.
  double failed_shift_ = 0;
  int factorizations_ = 0;
  // Iterations since the exact Hessian was last found not definite at τ.
  int since_exact_failed_ = kRetryExactAfter;
  Eigen::VectorXd step_, y_new_, gradient_new_;
};

// The predictor of a load step: y moved on along the path the last load step took, by `ratio`
// times that step, y_previous → y. Kept when F is lower there (value and gradient updated).
void extrapolate(const PoseObjective& objective, double ratio, const Eigen::VectorXd& y_previous, Eigen::VectorXd& y,
                 double& value, Eigen::VectorXd& gradient) {
  Eigen::VectorXd guess = y + ratio * (y - y_previous), guess_gradient(y.size());
  const double guess_value = objective(guess, guess_gradient);
  if (!(guess_value < value)) return;
  y.swap(guess);
  gradient.swap(guess_gradient);
  value = guess_value;
}

// Fraction of the work done for the progress bar: the load path first (when there is one), then
// the final load's gradient decrease on a log scale.
double fraction_done(double load, bool stepping, double gradient_norm, double scale, double tolerance) {
  const double path = stepping ? 0.5 * load : 0;
  if (load < 1) return path;
  const double decrease = std::log(std::max(gradient_norm / scale, tolerance)) / std::log(tolerance);
  return path + (stepping ? 0.5 : 1.0) * std::clamp(decrease, 0.0, 1.0);
}

}  // namespace

FullSolveResult solve_full(const VerticesRef& V, const FacesRef& F, const Handles& handles, const VectorRef& weights,
                           const Transforms& transforms, double stiffness, const FullSolveOptions& options,
                           const RowMatrixX3d* initial) {
  validate_mesh(V, F);  // before the handles, which index into it
  const int n = static_cast<int>(V.rows());
  const Eigen::VectorXd handle_weights = checked_handle_weights(handles, weights, n);
  check_transforms(transforms, static_cast<int>(handles.size()));
  require_stiffness(stiffness);
  const double tolerance = options.tolerance;
  if (!(tolerance > 0 && tolerance < 1))
    throw InputError(message("tolerance: expected a value in (0, 1), got ", tolerance));
  if (options.max_iterations < 0)
    throw InputError(message("max_iterations: expected at least 0, got ", options.max_iterations));
  if (initial) require_positions(flatten(*initial), 3 * n, "initial");
  const auto start = std::chrono::steady_clock::now();
  Progress progress(options.progress);
  progress.report("solve", 0);

  PoseObjective objective(V, F, handles, handle_weights, stiffness, options);
  const LoadPath path(V, handles, transforms);
  ShiftedNewton newton(objective);

  FullSolveResult result;
  Eigen::VectorXd y = objective.rest_positions(), gradient(3 * n);
  objective.set_transforms(transforms);
  double value = objective(y, gradient);
  result.gradient_scale = gradient.norm();
  if (initial) {
    y = objective.scale() * flatten(*initial);
    value = objective(y, gradient);
    result.gradient_scale = std::max(result.gradient_scale, gradient.norm());
  }
  result.initial_energy = value;
  // From rest, the first load step is a sixth of the suggested one: longer, its first Newton step
  // (nearly the linear elastic answer) tangles fins and flaps (on the 5k dragon turned by 30° at
  // once, triangles collapsed and the solve stalled at 4 times the minimum's objective). Each
  // next increment doubles after an easy step, up to the suggested one, and halves after a hard
  // one.
  const bool stepping = !initial;
  const double largest_increment = 1.0 / path.suggested_steps();
  double increment = stepping ? largest_increment / kFirstStepDivisor : 1.0;
  double load = 0, previous_increment = 0, done = 0;
  Eigen::VectorXd y_previous;  // the answer at the load before, for the predictor
  while (load < 1) {
    // A last sliver of the path is taken with the step before it; with no iterations left, the
    // full load is evaluated as it stands.
    const bool spent = result.iterations >= options.max_iterations;
    const double next = spent || load + 1.25 * increment >= 1 ? 1.0 : load + increment;
    const bool final = next == 1;
    objective.set_transforms(path.at(next));
    value = objective(y, gradient);
    if (previous_increment > 0) {
      Eigen::VectorXd y_load = y;
      extrapolate(objective, (next - load) / previous_increment, y_previous, y, value, gradient);
      y_previous.swap(y_load);
    } else if (stepping) {
      y_previous = y;
    }
    const double target = (final ? tolerance : std::max(tolerance, kIntermediateTolerance)) * result.gradient_scale;
    const int budget = final ? options.max_iterations - result.iterations
                             : std::min(kIterationsPerIntermediateStep, options.max_iterations - result.iterations);
    int iterations = 0, stalled = 0;
    while (iterations < budget && stalled < kMaxStalledIterations && gradient.norm() > target) {
      const bool near_minimum = gradient.norm() <= kExactHessianBelow * result.gradient_scale;
      stalled = newton.iterate(y, value, gradient, near_minimum) ? 0 : stalled + 1;
      ++iterations;
      // The gradient norm may rise for a step: the bar never goes back.
      done = std::max(done, fraction_done(next, stepping, gradient.norm(), result.gradient_scale, tolerance));
      progress.report("solve", done);
    }
    result.iterations += iterations;
    ++result.steps;
    previous_increment = next - load;
    load = next;
    if (gradient.norm() <= target && iterations <= kFewIterations)
      increment = std::min(2 * increment, largest_increment);
    else if (gradient.norm() > target || iterations > kManyIterations)
      increment = std::max(increment / 2, largest_increment / (4 * kFirstStepDivisor));
  }
  progress.report("solve", 1);
  result.factorizations = newton.factorizations();
  result.energy = value;
  result.gradient_norm = gradient.norm();
  result.converged = result.gradient_norm <= tolerance * result.gradient_scale;
  result.positions = Eigen::Map<const RowMatrixX3d>(y.data(), n, 3) / objective.scale();
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace modal_deform
