// The lowest vibration modes: eigenpairs of K φ = λ M φ (the paper's V1, section 4).
#pragma once

#include "util/progress.h"
#include "util/types.h"

namespace modal_deform {

class CholmodLLT;

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

// The `count` eigenpairs of K φ = λ M φ with the smallest λ, rigid motions (λ = 0) included.
// K: 3n by 3n symmetric positive semidefinite; mass: n vertex masses (M = diag(mass) ⊗ I₃); see
// stiffness_and_mass.h for the checks and for DOFs without mass, which stay zero.
// Block Lanczos on (K − σM)⁻¹M with σ < 0 from the scale of the problem, the inverse applied
// through one CHOLMOD factorisation in blocks of right-hand sides, then one step of inverse
// iteration and Rayleigh–Ritz on K. Reports ("modes", fraction) to `progress`, which may cancel.
// Throws InputError for bad input, NumericalError when the eigensolver does not converge or a
// mode's residual is too large.
VibrationModes vibration_modes(const SparseMatrix& K, const VectorRef& mass, int count, Progress* progress = nullptr);

// The `count` lowest eigenpairs with modes M-orthogonal to the columns of Z (3n by z, M-orthonormal,
// in the kernel of K: rigid_motions for a rigid-invariant energy). Deflating the known kernel
// spares Lanczos the eigenvalue 0 of multiplicity 6 per component, slow to resolve and useless to
// deform with, and lets the shift sit closer to the flexible modes.
// `factor`, when given, is the CholmodLLT (3 DOFs per node) that K − σM is factored in, and holds
// that factor afterwards (σ = VibrationModes::shift): the bake's derivative solves reuse it
// (solve_in_range_shifted). zero_modes_below > 0 is for a caller that deflates the zero modes
// returned (λ below it) and solves again (the bake): a mode above its tolerance is then returned
// rather than thrown, and Lanczos returns as soon as the zero modes have converged when they keep
// the others from converging (undeflated, they swamp them by up to 1e6; see BlockLanczos).
VibrationModes vibration_modes(const SparseMatrix& K, const VectorRef& mass, int count,
                               const Eigen::Ref<const Eigen::MatrixXd>& Z, Progress* progress = nullptr,
                               CholmodLLT* factor = nullptr, double zero_modes_below = 0);

// Throws NumericalError, naming the mode, when a mode in [first, last) has a residual above its
// tolerance.
void require_accurate(const VibrationModes& modes, int first, int last);

}  // namespace modal_deform
