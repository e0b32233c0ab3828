// Modal derivatives, the paper's eq. 13: K ψᵢⱼ = ∇³E(x̄)(φᵢ, φⱼ), solved generically in (K, M) for
// a block of right-hand sides, and the order in which the pairs (i, j) enter the basis.
#pragma once

#include <array>
#include <vector>

#include "util/progress.h"
#include "util/types.h"

namespace modal_deform {

class CholmodLLT;

// The first `count` pairs (i, j), i ≤ j < num_modes, of non-rigid modes in the paper's order
// (two loops, so that pairs of low eigenvalues come first): (0,0), (0,1), (1,1), (0,2), (1,2),
// (2,2), (0,3), ... Throws InputError when count exceeds num_modes (num_modes + 1) / 2.
std::vector<std::array<int, 2>> derivative_pairs(int num_modes, int count);

// The DOFs to pin so that K plus a stiffness at them is definite: in each connected component of
// K's graph, as many DOFs as Z has rank there, chosen by column-pivoted QR of Z's rows (for rigid
// motions a well-conditioned "3-2-1" set). K: 3n by 3n; mass: n; Z: 3n by z, M-orthonormal,
// spanning the kernel of K. Returns z DOF indices. Throws InputError when Z does not split over
// the components of K, as a basis of its kernel does.
std::vector<int> kernel_pins(const SparseMatrix& K, const VectorRef& mass, const Eigen::Ref<const Eigen::MatrixXd>& Z);

// Ψ (3n by p) with K Ψ = P B and Zᵀ M Ψ = 0, where P projects onto the range of K (Euclidean-
// orthogonal to its kernel): at rest, the right-hand sides ∇³E(x̄)(φᵢ, φⱼ) have components in the
// kernel proportional to λᵢ and λⱼ, which eq. 13 cannot match.
// K: 3n by 3n symmetric positive semidefinite; mass: n vertex masses; Z: 3n by z, M-orthonormal,
// spanning the kernel of K (rigid_motions for a rigid-invariant energy); B: 3n by p.
// K plus a stiffness at the pinned DOFs (kernel_pins unless given) is factored once and solved
// for blocks of columns, reporting ("derivative solves", fraction) to `progress`. DOFs without
// mass and stiffness (stiffness_and_mass.h) get zero rows. Throws InputError for inconsistent
// input (Z not M-orthonormal or not in the kernel, bad pins) and NumericalError when the pinned
// matrix is singular (Z misses part of the kernel) or a solution fails its residual check.
// `factor`, when given, is the CholmodLLT (3 DOFs per node) to factor in: one that already holds
// the analysis of K's pattern (from vibration_modes) skips it.
Eigen::MatrixXd solve_in_range(const SparseMatrix& K, const VectorRef& mass, const Eigen::Ref<const Eigen::MatrixXd>& Z,
                               const Eigen::Ref<const Eigen::MatrixXd>& B, Progress* progress = nullptr,
                               CholmodLLT* factor = nullptr);
Eigen::MatrixXd solve_in_range(const SparseMatrix& K, const VectorRef& mass, const Eigen::Ref<const Eigen::MatrixXd>& Z,
                               const Eigen::Ref<const Eigen::MatrixXd>& B, const std::vector<int>& pins,
                               Progress* progress = nullptr);

}  // namespace modal_deform
