// Modal derivatives, the paper's eq. 13: K ψᵢⱼ = ∇³E(x̄)(φᵢ, φⱼ), solved generically in (K, M) for
// a block of right-hand sides, and the order in which the pairs (i, j) enter the basis.
//
// Which modes pair (paper §4): all but the translations, whose derivatives vanish. A linearised
// rotation r = W x̄ pairs too: ∇³E(x̄)(r, φ) = (W K − K W) φ, so its derivative with a mode is, up to
// a part ∝ λ, −W φ, that mode rotated (what the far end of a bent bar needs), and with another
// rotation −W_a W_b x̄, the second-order term of the rotation.
#pragma once

#include <array>
#include <functional>
#include <vector>

#include "util/progress.h"
#include "util/types.h"

namespace modal_deform {

// The first `count` pairs (i, j), i ≤ j, of modes ordered by eigenvalue (lowest first), in the
// paper's order (two loops, so that pairs of low eigenvalues come first): (0,0), (0,1), (1,1),
// (0,2), (1,2), (2,2), (0,3), ... Pairs of modes that move no component in common (the rotations of
// two components) are left out: the energy couples the vertices of one component only, so their
// derivative is zero. components[i]: the components mode i moves, ascending (components_moved).
// Throws InputError naming "derivatives" when count is negative or exceeds the pairs there are.
std::vector<std::array<int, 2>> derivative_pairs(const std::vector<std::vector<int>>& components,
                                                 int count);

// The components each column of Phi (3n by k, interleaved) moves: those holding more than 1e-12
// of its squared norm. component: n labels in [0, c). Throws InputError for mismatched sizes or a
// label outside [0, c).
std::vector<std::vector<int>> components_moved(const Eigen::Ref<const Eigen::MatrixXd>& Phi,
                                               const Eigen::Ref<const Eigen::VectorXi>& component);

// Ψ (3n by p) with K Ψ = P B and Zᵀ M Ψ = 0, where P projects onto the range of K (Euclidean-
// orthogonal to its kernel): at rest, the right-hand sides ∇³E(x̄)(φᵢ, φⱼ) have components in the
// kernel proportional to λᵢ and λⱼ, which eq. 13 cannot match.
// K: 3n by 3n symmetric positive semidefinite; mass: n vertex masses; Z: 3n by z, M-orthonormal,
// spanning the kernel of K (rigid_motions for a rigid-invariant energy); B: 3n by p.
// K plus a stiffness at pinned DOFs is factored once and solved for blocks of columns, reporting
// ("derivative solves", fraction) to `progress`. The pins: in each connected component of K's
// graph as many DOFs as Z has rank there, chosen by column-pivoted QR of Z's rows (for rigid
// motions a well-conditioned "3-2-1" set). DOFs without mass and stiffness (stiffness_and_mass.h)
// get zero rows. Throws InputError for inconsistent input (Z not M-orthonormal, not in the kernel
// or not split over the components of K) and NumericalError when the pinned matrix is singular
// (Z misses part of the kernel) or a solution fails its residual check.
Eigen::MatrixXd solve_in_range(const SparseMatrix& K, const VectorRef& mass,
                               const Eigen::Ref<const Eigen::MatrixXd>& Z,
                               const Eigen::Ref<const Eigen::MatrixXd>& B,
                               Progress* progress = nullptr);

// What the solves in the range above share, for a caller with a solver of its own (ShiftedPencil):
// Ψ written over B, block by block of at most 64 columns, each block's P B handed to
// solve(P B, X, report), which writes a solution of K X = P B into X (its kernel part is removed
// here) and may tell the bar what part of the block is done; then the residuals P B − K X are
// checked. A solve that knows that residual from its own recurrence leaves it in PB and returns
// true, sparing the product with K (as costly as a step of the solve); one that returns
// false leaves PB as it was, and the residual is computed here.
// m: the diagonal of M (3n); Z: a checked kernel basis (checked_kernel_basis); decoupled:
// decoupled_dofs. Throws InputError for a B of the wrong size or not finite, NumericalError when
// a column fails the residual check.
using BlockSolve = std::function<bool(Eigen::MatrixXd& PB, Eigen::Ref<Eigen::MatrixXd> X,
                                      const std::function<void(double part)>& report)>;
Eigen::MatrixXd solve_in_range_by_blocks(const SparseMatrix& K, const Eigen::VectorXd& m,
                                         const Eigen::MatrixXd& Z,
                                         const std::vector<bool>& decoupled, Eigen::MatrixXd B,
                                         const BlockSolve& solve, Progress* progress);

}  // namespace modal_deform
