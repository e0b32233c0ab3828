// The pencil (K, M) shifted by σ < 0 and factored once, K − σM = LLᵀ (CHOLMOD), for everything the
// bake solves with it: the vibration modes (the paper's V1, section 4) by block shift-invert
// Lanczos, and the modal derivatives (eq. 13) by solves in the range of K. In the manner of
// geometry-central's solvers that keep their factorisation: the object holds K, M, the kernel
// deflated so far, the factor, σ and the eigenpairs last found, and times its own work.
//
// K: 3n by 3n symmetric positive semidefinite (an energy's Hessian at rest), mass: the n vertex
// masses (M = diag(mass) ⊗ I₃); see stiffness_and_mass.h for the checks and for DOFs without mass,
// which stay zero.
#pragma once

#include <vector>

#include "linalg/cholmod_llt.h"
#include "util/progress.h"
#include "util/types.h"

namespace modal_deform {

// Eigenpairs of K φ = λ M φ, as ShiftedPencil::lowest_modes and vibration_modes find them.
struct VibrationModes {
  Eigen::VectorXd eigenvalues;  // count, ascending; units of K per unit of mass
  Eigen::MatrixXd modes;        // 3n by count, M-orthonormal (Φᵀ M Φ = I)
  // ‖K φ − λ M φ‖ in the M⁻¹-norm per mode (count, units of λ): some eigenvalue of the pencil
  // lies within it of the reported one.
  Eigen::VectorXd residuals;
  // The residual each mode must stay within: 1e-6 of (|λ| + the largest λ computed), plus a
  // rounding floor for λ = 0 and the rounding error of computing K φ (count, units of λ).
  Eigen::VectorXd tolerances;
  double shift = 0;  // σ of the shift-invert transform
  int solves = 0;    // solves with the factor of K − σM
};

// Throws NumericalError, naming the mode, when a mode in [first, last) has a residual above its
// tolerance.
void require_accurate(const VibrationModes& modes, int first, int last);

// Vibration modes past a pencil's kernel (ShiftedPencil::flexible_modes): the zero modes of a
// floppy mesh, deflated into the kernel, then the flexible modes, ascending.
struct FlexibleModes {
  Eigen::VectorXd eigenvalues;  // num_zero + flexible
  Eigen::MatrixXd flexible;     // 3n by flexible, M-orthonormal
  int num_zero = 0;
};

class ShiftedPencil {
 public:
  // kernel: 3n by z, M-orthonormal, in the kernel of K (rigid_motions for a rigid-invariant
  // energy; may be empty). Deflating it spares Lanczos the eigenvalue 0 of multiplicity 6 per
  // component, slow to resolve and useless to deform with, and lets the shift sit closer to the
  // flexible modes. shift: σ < 0, or 0 to take it from the scale of the problem (tr K / tr M) and
  // whether a kernel is deflated. K is kept by reference: it must outlive the pencil. Throws
  // InputError for bad K, mass, kernel or shift.
  ShiftedPencil(const SparseMatrix& K, const VectorRef& mass,
                const Eigen::Ref<const Eigen::MatrixXd>& kernel, double shift = 0);

  // CHOLMOD's ordering of K now rather than at the first factorisation, so that factor_bytes()
  // is known before memory is spent on the factor. Throws OutOfMemory.
  void analyze();
  // Bytes the numeric factor takes (after analyze).
  double factor_bytes() const { return factor_.factor_bytes(); }

  // The `count` eigenpairs of K φ = λ M φ with the smallest λ, M-orthogonal to the kernel, by
  // block Lanczos on (K − σM)⁻¹M with the inverse applied in blocks of right-hand sides, then one
  // step of inverse iteration and Rayleigh–Ritz on K; K − σM is factored when σ is new. Residuals
  // are reported, not checked (require_accurate). zero_modes_below > 0 is for a caller that
  // deflates the zero modes returned (λ below it) and asks again: Lanczos then returns as soon as
  // they have converged when they keep the others from converging (left in K, they swamp them by
  // up to 1e6). Reports ("modes", fraction) to `progress`, which may cancel. Throws InputError
  // for a bad count, NumericalError when K − σM cannot be factored (failed_row() says where) or
  // the eigensolver does not converge, OutOfMemory.
  VibrationModes lowest_modes(int count, Progress* progress = nullptr, double zero_modes_below = 0);

  // The zero modes (λ below `zero`) of a floppy mesh, deflated into the kernel, and `flexible`
  // modes above them. Lanczos is asked for `flexible` modes; when zero modes come among them, it is
  // asked again with those deflated, until the flexible modes are complete (asking for spare modes
  // up front would cost every bake Lanczos iterations on modes it does not keep). So is a mesh
  // whose flexible modes miss their residual tolerance next to zero modes (two cones joined at
  // their apex: with the zero modes in K, their transformed eigenvalue 1/|σ| dwarfs the others',
  // which are left to rounding), or whose Lanczos run returned as soon as its zero modes converged
  // because the others could not beside them. Throws InputError when the pencil has too few
  // degrees of freedom, and as lowest_modes and require_accurate.
  FlexibleModes flexible_modes(int flexible, double zero, Progress* progress = nullptr);
  // The `count` lowest modes of the last lowest_modes join the kernel (a floppy mesh's zero
  // modes); the next lowest_modes is M-orthogonal to them. Throws InputError past those modes.
  void deflate(int count);

  // Ψ (3n by p) with K Ψ = P B and Ψ M-orthogonal to the kernel, P the projection onto the range
  // of K (as solve_in_range in modal_derivatives.h) through this factor of K − σM: exact on the
  // eigenpairs of the last lowest_modes within their tolerance and not deflated, each off by
  // λ/(λ − σ) on the others, so refined (ψ += (K − σM)⁻¹(P b − K ψ)) until each such component
  // is within 1e-3 (usually one step). Saves a factorisation for a solve and a product with K per
  // step. B (3n by p) is taken by value and Ψ is
  // written over it. Reports ("derivative solves", fraction). Throws InputError for a bad B or
  // before any eigenpair is known; NumericalError when a column fails its residual check.
  Eigen::MatrixXd solve_in_range(Eigen::MatrixXd B, Progress* progress = nullptr);

  // The kernel deflated so far: the one given, then the zero modes deflated (3n by z).
  const Eigen::MatrixXd& kernel() const { return kernel_; }
  // σ of the factor held (0 before the first lowest_modes).
  double shift() const { return factored_shift_; }
  // The row (in K's order) where the last factorisation found K − σM not positive definite; -1
  // when it did not fail that way.
  int failed_row() const { return factor_.failed_row(); }

  // Wall seconds: CHOLMOD's analysis and factorisations; lowest_modes without them; solve_in_range.
  struct Timings {
    double factorisation = 0;
    double modes = 0;
    double solves = 0;
  };
  Timings timings() const;

 private:
  void factor_with_shift(double sigma);

  const SparseMatrix& K_;
  Eigen::VectorXd dof_mass_;             // the diagonal of M (3n)
  std::vector<bool> decoupled_;          // DOFs outside the problem (decoupled_dofs)
  Eigen::VectorXd decoupled_stiffness_;  // added to them so that K − σM stays definite
  double scale_;                         // tr K / tr M, a mass-weighted mean of the spectrum
  double requested_shift_;               // the σ given, or 0
  Eigen::MatrixXd kernel_;
  CholmodLLT factor_{3};  // orders vertices, 3 DOFs each
  double factored_shift_ = 0;
  // The eigenpairs of the last lowest_modes within their tolerance and not deflated: solve_in_range
  // corrects them; the first deflatable_ of them are its lowest modes.
  Eigen::VectorXd known_eigenvalues_;
  Eigen::MatrixXd known_modes_;
  Eigen::Index deflatable_ = 0;
  Timings timings_;  // but the factorisation, which factor_ times
};

}  // namespace modal_deform
