// Newton's method on the full solve's objective F (pose_objective.h) with the Hessian shifted,
// ∇²F + τD (D the normalised lumped mass per coordinate). CHOLMOD's analysis of the Hessian's
// pattern is kept for the whole solve, and τ from one iteration (and load step) to the next.
//
// τ follows how well the quadratic model predicted the decrease (Levenberg–Marquardt with
// Nielsen's update), never below PoseObjective::smallest_shift; the step is then backtracked
// (Armijo, line_search.h) when F does not decrease enough or a triangle turns over. The Hessian is
// the projected one far from the minimum and the exact one near it wherever it factors. An
// iteration first solves by conjugate gradients preconditioned by the last factor, to an inexact
// Newton tolerance (Eisenstat & Walker 1996), and factors only when that would not converge.
// Why each of these: docs/design.md, "Newton's iterations".
#pragma once

#include <functional>
#include <vector>

#include "linalg/cholmod_llt.h"
#include "solve/line_search.h"
#include "solve/pose_objective.h"

namespace modal_deform {

// A point of the solve: y (3#V, normalised frame), F(y) and ∇F(y).
struct NewtonPoint {
  Eigen::VectorXd y;
  double value = 0;
  Eigen::VectorXd gradient;
};

// What one iteration did, for the solve's statistics.
// The Hessian a Newton step solves with: each element's made semidefinite, or the exact one.
enum class HessianModel { kProjected, kExact };
// "projected" or "exact".
inline const char* hessian_model_name(HessianModel model) {
  return model == HessianModel::kExact ? "exact" : "projected";
}

struct NewtonIteration {
  HessianModel model = HessianModel::kProjected;
  double shift = 0;  // τ it was factored with
  double step =
      0;  // α taken (above 1: extended); 0: the line search found no decrease (the iterate stays)
  bool guarded = false;   // α < 1 only because longer steps turned a triangle over
  double ratio = 0;       // F's decrease over the model's at α
  int cg_iterations = 0;  // conjugate gradient iterations of the step; 0: solved with a new factor
  bool progress = false;  // as iterate() returns
  double energy = 0;      // F and ‖∇F‖ after the iteration
  double gradient_norm = 0;
};

// The fields of a NewtonIteration by name (the Python API's stats, one dict per iteration):
// visit(name, field) with `field` an accessor it -> it.member.
template <typename Visit>
void for_each_newton_iteration_field(Visit&& visit) {
  visit("model", [](auto& it) -> auto& { return it.model; });
  visit("shift", [](auto& it) -> auto& { return it.shift; });
  visit("step", [](auto& it) -> auto& { return it.step; });
  visit("guarded", [](auto& it) -> auto& { return it.guarded; });
  visit("ratio", [](auto& it) -> auto& { return it.ratio; });
  visit("cg_iterations", [](auto& it) -> auto& { return it.cg_iterations; });
  visit("progress", [](auto& it) -> auto& { return it.progress; });
  visit("energy", [](auto& it) -> auto& { return it.energy; });
  visit("gradient_norm", [](auto& it) -> auto& { return it.gradient_norm; });
}

class ShiftedNewton {
 public:
  // Keeps a reference to `objective`, which must outlive it.
  explicit ShiftedNewton(const PoseObjective& objective);

  int factorizations() const { return factorizations_; }
  // Every iteration made so far, in order.
  const std::vector<NewtonIteration>& history() const { return history_; }
  // Whether the last minimize() stopped because F stopped decreasing.
  bool stalled() const { return stalled_; }

  // Iterates from `point` (updated) until ‖∇F‖ ≤ target, `budget` iterations are spent, or F
  // stops decreasing (kMaxStalledIterations iterations without progress: at a kink of F, a triangle
  // collapsed, its bending terms' angles undefined, F stops decreasing while ‖∇F‖ does not fall).
  // The exact Hessian is tried once ‖∇F‖ ≤ exact_below. after_iteration(point) is called after
  // each iteration. Returns the iterations made.
  int minimize(NewtonPoint& point, double target, int budget, double exact_below,
               const std::function<void(const NewtonPoint&)>& after_iteration);

  // One iteration from `point` (updated). Near the minimum (`near_minimum`) the exact Hessian is
  // tried first, at the current τ only: where it is not definite there (a flap still bent far from
  // rest), the projected one (Energy::projected_hessian) serves instead for the next
  // kRetryExactAfter iterations. Growing τ until the exact Hessian factors would damp the whole
  // mesh (docs/measurements.md, "Choices in the core"). Returns whether it
  // made progress: F fell by more than its rounding, or ‖∇F‖ by half (near the minimum, where F's
  // decrease is below rounding).
  // By conjugate gradients the Newton system is solved to the relative residual `forcing` (> 0).
  bool iterate(NewtonPoint& point, bool near_minimum, double forcing);

 private:
  static constexpr int kMaxStalledIterations = 3;
  static constexpr double kMaxGrowth = 16;
  static constexpr double kMaxCutGrowth = 1e4;
  // Iterations on the projected Hessian after the exact one failed to factor before it is tried
  // again: the projected one converges only linearly (clamping the negative curvature of a bent
  // flap overestimates it), so the exact one is retried soon, at one factorisation's cost.
  static constexpr int kRetryExactAfter = 3;
  // Conjugate gradient iterations (a solve with the factor and a product with the Hessian each)
  // before the matrix is factored instead.
  static constexpr int kMaxCgIterations = 12;
  // The forcing terms' bound (Eisenstat & Walker's η_max): far from the minimum a loose step
  // serves.
  static constexpr double kMaxForcing = 0.1;
  // A full step that decreased F by more than this times the model's promise is extended
  // (extend()).
  static constexpr double kExtendAbove = 1.5;
  static constexpr double kMaxExtension = 8;
  // The fraction of the way to the first triangle's turning point the line search starts at when
  // that point is nearer than a full step: the fewest Refine iterations on the 23k dragon's strong
  // turns (docs/measurements.md, "Choices in the core").
  static constexpr double kToTurning = 0.9;

  // trial_ (the full step's point, F lower there than the model promised: the projected Hessian
  // clamps the negative curvature of a flap bent away from a saddle, and such steps creep, ‖∇F‖
  // rising, for many iterations) moved on to α = 2, 4, ... kMaxExtension
  // while F keeps falling and no triangle turns over; returns the α kept.
  double extend(const NewtonPoint& point, const Objective& objective);

  // Conjugate gradients on (H + C + τD) step_ = −∇F (C the constant diagonal), preconditioned by
  // the last factor, from step_ = 0 until the residual is below `forcing` times ‖∇F‖. Returns the
  // iterations made, or 0 when they met a direction of nonpositive curvature or would not converge
  // within kMaxCgIterations, judged from the first iteration on by the mean decrease so far (step_
  // is then not a step).
  int solve_by_cg(const SparseMatrix& hessian, const Eigen::VectorXd& gradient, double forcing);
  // The relative residual the next Newton system is solved to by conjugate gradients.
  double forcing(double gradient_norm, double target, double exact_below) const;
  // shifted_diagonal_ = C + τD at the current τ: the shift of both the factor and the system CG
  // solves.
  void set_shifted_diagonal();
  // Factors ∇²F + τD at the current τ; false (the matrix not definite) leaves τ as it is.
  bool try_factorize(const SparseMatrix& hessian);
  // Factors ∇²F + τD, τ grown tenfold until it factors.
  void factorize_shifted(const SparseMatrix& hessian);
  // τ after a step the line search cut to `cut` for want of decrease (1: not cut; 0: no step
  // taken), its decrease `ratio` times the model's.
  void update_shift(double cut, double ratio);
  // The decrease the model F + ∇Fᵀp + ½pᵀ∇²F p promises at αp, with p = step_, slope = ∇Fᵀp and
  // curvature = pᵀ∇²F p.
  static double predicted_decrease(double alpha, double slope, double curvature);

  const PoseObjective& objective_;
  CholmodLLT llt_;
  double shift_;       // τ
  double growth_ = 2;  // τ's factor after the next poor step (Nielsen's ν)
  // The largest τ that failed to factor lately (decaying): τ is not lowered below it, which would
  // only cost another failed factorisation.
  double failed_shift_ = 0;
  int factorizations_ = 0;
  bool stalled_ = false;
  // Iterations since the exact Hessian was last found not definite at τ.
  int since_exact_failed_ = kRetryExactAfter;
  bool factored_ = false;  // llt_ holds the factor of the last factorisation (it succeeded)
  double previous_gradient_norm_ = 0;        // ‖∇F‖ before the last iteration, for the forcing term
  Eigen::VectorXd step_, shifted_diagonal_;  // shifted_diagonal_: C + τD
  Eigen::VectorXd residual_, preconditioned_, direction_, product_;  // conjugate gradients' vectors
  NewtonPoint trial_, extended_;
  SparseMatrix hessian_;  // the last iteration's, its storage reused
  std::vector<NewtonIteration> history_;
};

}  // namespace modal_deform
