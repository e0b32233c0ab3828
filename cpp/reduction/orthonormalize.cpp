#include "reduction/orthonormalize.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "linalg/row_blocks.h"
#include "util/bake_stages.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

// Columns orthonormalised together, at most: the wider the block, the fewer passes over the basis
// and the faster its products (docs/measurements.md, "Choices in the core").
constexpr Eigen::Index kBlockColumns = 80;
// The squared M-norms of X's columns: the diagonal of Xᵀ M X without the rest of it.
Eigen::VectorXd squared_m_norms(const Eigen::Ref<const Eigen::MatrixXd>& X,
                                const VectorRef& dof_mass) {
  return sum_over_row_blocks(X.rows(), 1, X.cols(),
                             [&](Eigen::Index first, Eigen::Index count) {
                               return dof_mass.segment(first, count).transpose() *
                                      X.middleRows(first, count).cwiseAbs2();
                             })
      .transpose();
}

// X ← X R⁻¹ for upper triangular R.
void solve_upper_on_the_right(Eigen::Ref<Eigen::MatrixXd> X, const Eigen::MatrixXd& R) {
  for_row_blocks(X.rows(), [&](Eigen::Index first, Eigen::Index count) {
    auto part = X.middleRows(first, count);
    R.triangularView<Eigen::Upper>().solveInPlace<Eigen::OnTheRight>(part);
  });
}

// Removes from X its components along the M-orthonormal columns Q (classical Gram–Schmidt; each
// of the two passes does it once, which makes it twice, "twice is enough").
void project_out(Eigen::Ref<Eigen::MatrixXd> X, const Eigen::Ref<const Eigen::MatrixXd>& Q,
                 const VectorRef& dof_mass) {
  if (Q.cols()) add_dense_product(X, Q, -inner_product(Q, dof_mass, X));
}

// Cholesky factor R (upper) of the Gram matrix G over the columns it keeps: column j is dropped
// when its squared residual norm, G_jj less its components along the kept columns before it, is
// at most floor[j]. Writes the kept indices into `kept`.
Eigen::MatrixXd dropping_cholesky(const Eigen::MatrixXd& G, const Eigen::VectorXd& floor,
                                  std::vector<int>& kept) {
  const Eigen::Index w = G.rows();
  Eigen::MatrixXd R = Eigen::MatrixXd::Zero(w, w);  // rows and columns of kept indices only
  kept.clear();
  for (Eigen::Index j = 0; j < w; ++j) {
    double residual = G(j, j);
    // Rows of R are indexed by position among the kept columns; the entries of the candidate
    // column j go into column kept.size().
    const auto c = static_cast<Eigen::Index>(kept.size());
    for (Eigen::Index a = 0; a < c; ++a) {
      double r = G(kept[static_cast<size_t>(a)], j);
      for (Eigen::Index b = 0; b < a; ++b) r -= R(b, a) * R(b, c);
      R(a, c) = r / R(a, a);
      residual -= R(a, c) * R(a, c);
    }
    if (residual > floor[j]) {
      R(c, c) = std::sqrt(residual);
      kept.push_back(static_cast<int>(j));
    } else {
      R.col(c).setZero();
    }
  }
  const auto r = static_cast<Eigen::Index>(kept.size());
  return R.topLeftCorner(r, r);
}

}  // namespace

std::vector<int> orthonormalize(Eigen::MatrixXd& U, const VectorRef& dof_mass, double tolerance,
                                Progress* progress) {
  if (dof_mass.size() != U.rows())
    throw InputError(message("dof_mass: expected ", U.rows(), " values (one per row of U), got ",
                             dof_mass.size()));
  if (!U.allFinite()) throw InputError("U: has an entry that is not finite");
  if (!(tolerance >= 0 && tolerance < 1))
    throw InputError(message("tolerance: expected [0, 1), got ", tolerance));
  std::vector<int> kept_columns;
  Eigen::Index done = 0;  // columns of Q so far: U's leading columns
  if (progress) progress->report(stages::kOrthonormalisation, 0.0);
  // Blocks of equal width, at most kBlockColumns (the bake's 73 columns in one, its 142 in two).
  const Eigen::Index blocks = (U.cols() + kBlockColumns - 1) / kBlockColumns;
  const Eigen::Index block_columns = blocks > 0 ? (U.cols() + blocks - 1) / blocks : 1;
  for (Eigen::Index first = 0; first < U.cols(); first += block_columns) {
    const Eigen::Index width = std::min(block_columns, U.cols() - first);
    // In place: the block's kept columns move left to follow Q (done ≤ first), each to a column
    // at or before its own, so none is overwritten before it is read.
    auto X = U.middleCols(first, width);
    const auto Q = U.leftCols(done);
    const Eigen::VectorXd floor =
        (tolerance * tolerance) * squared_m_norms(X, dof_mass);  // before projection
    project_out(X, Q, dof_mass);
    std::vector<int> kept;
    const Eigen::MatrixXd R = dropping_cholesky(inner_product(X, dof_mass, X), floor, kept);
    for (size_t a = 0; a < kept.size(); ++a)
      if (done + static_cast<Eigen::Index>(a) != first + kept[a])
        U.col(done + static_cast<Eigen::Index>(a)) = U.col(first + kept[a]);
    auto Y = U.middleCols(done, static_cast<Eigen::Index>(kept.size()));
    solve_upper_on_the_right(Y, R);
    // Second pass: Y is orthonormal up to rounding amplified by R's condition; once more makes it
    // orthonormal to working precision.
    project_out(Y, Q, dof_mass);
    const Eigen::LLT<Eigen::MatrixXd> second(inner_product(Y, dof_mass, Y));
    if (second.info() != Eigen::Success)
      throw NumericalError(
          "orthonormalize: the second Cholesky-QR pass failed; the columns are too dependent");
    solve_upper_on_the_right(Y, Eigen::MatrixXd(second.matrixU()));
    done += Y.cols();
    for (int k : kept) kept_columns.push_back(static_cast<int>(first) + k);
    if (progress)
      progress->report(stages::kOrthonormalisation, static_cast<double>(first + width) / U.cols());
  }
  U.conservativeResize(Eigen::NoChange, done);
  return kept_columns;
}

}  // namespace modal_deform
