// M-orthonormalisation of a basis whose columns come in order of priority (the bake's rigid
// motions, vibration modes, modal derivatives), dropping the numerically dependent ones.
#pragma once

#include <vector>

#include "util/progress.h"
#include "util/types.h"

namespace modal_deform {

// Relative M-norm below which a column counts as dependent on the columns before it: float32
// storage of the basis (about 6e-8 relative) could not tell the rest apart anyway.
constexpr double kDependentTolerance = 1e-6;

// Replaces U (3n by r) by Q (3n by r', r' ≤ r) with Qᵀ M Q = I, M = diag(dof_mass) (3n masses
// ≥ 0), and returns the index in U of each of Q's columns. Column j of U is dropped when what is
// left of it after removing its components along the columns before it has an M-norm below
// `tolerance` times its own; otherwise it becomes the next column of Q, which spans the kept
// columns up to it (Q = U_kept R⁻¹, R upper triangular). So a leading block that is already
// M-orthonormal (rigid motions) stays what it was up to rounding.
// Blocks of columns are projected against the columns before them and orthonormalised by
// Cholesky-QR, twice (block classical Gram–Schmidt with re-orthogonalisation: the second pass
// removes what the first lost to rounding). About 4 n r² flops for r columns of n rows (22 GFlop
// for 136 columns of the 100k dragon); the dense products run over row blocks in parallel.
// Reports ("orthonormalisation", fraction) per block.
// Throws InputError for a non-finite entry or a wrong dof_mass size.
std::vector<int> orthonormalize(Eigen::MatrixXd& U, const VectorRef& dof_mass,
                                double tolerance = kDependentTolerance,
                                Progress* progress = nullptr);

}  // namespace modal_deform
