// The lowest vibration modes: eigenpairs of K φ = λ M φ (the paper's V1, section 4), in one call.
// ShiftedPencil (shifted_pencil.h) is the same solver keeping its factorisation, for the bake.
#pragma once

#include "modes/shifted_pencil.h"
#include "util/progress.h"
#include "util/types.h"

namespace modal_deform {

// The `count` eigenpairs of K φ = λ M φ with the smallest λ, rigid motions (λ = 0) included.
// K: 3n by 3n symmetric positive semidefinite; mass: n vertex masses (M = diag(mass) ⊗ I₃); see
// stiffness_and_mass.h for the checks and for DOFs without mass, which stay zero.
// ShiftedPencil::lowest_modes with σ < 0 from the scale of the problem, then require_accurate.
// Reports ("modes", fraction) to `progress`, which may cancel. Throws InputError for bad input,
// NumericalError when the eigensolver does not converge or a mode's residual is too large.
VibrationModes vibration_modes(const SparseMatrix& K, const VectorRef& mass, int count,
                               Progress* progress = nullptr);

// The `count` lowest eigenpairs with modes M-orthogonal to the columns of Z (3n by z,
// M-orthonormal, in the kernel of K: rigid_motions for a rigid-invariant energy), deflated.
VibrationModes vibration_modes(const SparseMatrix& K, const VectorRef& mass, int count,
                               const Eigen::Ref<const Eigen::MatrixXd>& Z,
                               Progress* progress = nullptr);

}  // namespace modal_deform
