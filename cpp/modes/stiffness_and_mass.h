// The pencil (K, M) that the vibration modes and the modal-derivative solves share.
//
// K: 3n by 3n, symmetric positive semidefinite (an energy's Hessian at rest), DOFs interleaved
// x0 y0 z0 x1 ...; M = diag(m) ⊗ I₃, the lumped mass matrix given as the n vertex masses m.
#pragma once

#include <vector>

#include "util/types.h"

namespace modal_deform {

// Throws InputError, naming the first offending entry, unless mass holds n finite non-negative
// values and K is 3n by 3n, finite, and symmetric up to rounding.
void validate_stiffness_and_mass(const SparseMatrix& K, const VectorRef& mass);

// The diagonal of M (3n): each vertex mass repeated for x, y and z.
Eigen::VectorXd dof_masses(const VectorRef& mass);

// The DOFs that take no part in the problem (3n flags): zero mass and no nonzero entry in their
// column of K, such as those of unreferenced vertices. Modes and derivatives are zero there.
std::vector<bool> decoupled_dofs(const SparseMatrix& K, const VectorRef& mass);

// Z (3n by z) as a basis of (part of) the kernel of K, with zero rows on the decoupled DOFs, after
// validate_stiffness_and_mass. Throws InputError unless Z is finite, M-orthonormal and, column by
// column, in the kernel of K up to rounding (‖K z‖ ≤ 1e-8 ‖K‖₁ ‖z‖).
Eigen::MatrixXd checked_kernel_basis(const SparseMatrix& K, const VectorRef& mass,
                                     const Eigen::Ref<const Eigen::MatrixXd>& Z);

}  // namespace modal_deform
