#include "modes/stiffness_and_mass.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "linalg/sparse_operations.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

// K(i, j) and K(j, i) may differ by this much relative to K's largest entry (rounding in the
// assembly of element Hessians).
constexpr double kSymmetryTolerance = 1e-10;
// Zᵀ M Z may differ from I by this much.
constexpr double kOrthonormalTolerance = 1e-8;
// ‖K z‖ ≤ kKernelTolerance ‖K‖₁ ‖z‖ for each column z of a kernel basis.
constexpr double kKernelTolerance = 1e-8;

// Entries [begin, end) of column `col` in K's index and value arrays; rows come sorted.
std::pair<int, int> column_range(const SparseMatrix& K, int col) {
  const int begin = K.outerIndexPtr()[col];
  return {begin, K.isCompressed() ? K.outerIndexPtr()[col + 1] : begin + K.innerNonZeroPtr()[col]};
}

}  // namespace

void validate_stiffness_and_mass(const SparseMatrix& K, const VectorRef& mass) {
  const Eigen::Index n = mass.size();
  if (n == 0) throw InputError("mass: no vertices");
  for (Eigen::Index i = 0; i < n; ++i)
    if (!(std::isfinite(mass[i]) && mass[i] >= 0))
      throw InputError(
          message("mass[", i, "] = ", mass[i], ": expected a finite non-negative mass"));
  if (K.rows() != 3 * n || K.cols() != 3 * n)
    throw InputError(message("K: expected ", 3 * n, " by ", 3 * n, " (3 per vertex), got ",
                             K.rows(), " by ", K.cols()));
  double largest = 0;
  for (int j = 0; j < K.outerSize(); ++j) {
    int previous = -1;
    for (SparseMatrix::InnerIterator it(K, j); it; ++it) {
      if (!std::isfinite(it.value()))
        throw InputError(message("K(", it.row(), ", ", j, ") is not finite"));
      if (it.row() <= previous)
        throw InputError(message("K: row indices of column ", j, " are not sorted or repeat"));
      previous = static_cast<int>(it.row());
      largest = std::max(largest, std::abs(it.value()));
    }
  }
  // Each pair once, in one pass over K (not a lookup per entry: the bake checks K twice): the
  // partner K(j, i) of an entry K(i, j) below the diagonal is the
  // next entry above the diagonal of column i not yet paired, as columns j come in ascending
  // order and so do the rows of column i. An entry above the diagonal that no entry below pairs
  // with is compared with the 0 its missing partner holds.
  const double tolerance = kSymmetryTolerance * largest;
  const int* rows = K.innerIndexPtr();
  const double* values = K.valuePtr();
  const auto asymmetric = [&](int i, int j, double value, double partner) {
    return InputError(message("K is not symmetric: K(", i, ", ", j, ") = ", value, " but K(", j,
                              ", ", i, ") = ", partner));
  };
  std::vector<int> unpaired(
      static_cast<size_t>(K.outerSize()));  // per column, its first entry not yet paired
  for (int c = 0; c < K.outerSize(); ++c)
    unpaired[static_cast<size_t>(c)] = column_range(K, c).first;
  // Checks the entries of column c above the diagonal with rows below `row` and moves past them.
  const auto check_unpaired = [&](int c, int row) {
    int& p = unpaired[static_cast<size_t>(c)];
    for (const int end = column_range(K, c).second; p < end && rows[p] < std::min(row, c); ++p)
      if (std::abs(values[p]) > tolerance) throw asymmetric(rows[p], c, values[p], 0.0);
  };
  for (int j = 0; j < K.outerSize(); ++j) {
    const auto [begin, end] = column_range(K, j);
    for (int p = begin; p < end; ++p) {
      const int i = rows[p];
      if (i <= j) continue;
      check_unpaired(i, j);
      int& q = unpaired[static_cast<size_t>(i)];
      double partner = 0;
      if (q < column_range(K, i).second && rows[q] == j) partner = values[q++];
      if (std::abs(values[p] - partner) > tolerance) throw asymmetric(i, j, values[p], partner);
    }
  }
  for (int c = 0; c < K.outerSize(); ++c) check_unpaired(c, c);
}

Eigen::VectorXd dof_masses(const VectorRef& mass) {
  return mass.replicate(1, 3).transpose().reshaped();
}

std::vector<bool> decoupled_dofs(const SparseMatrix& K, const VectorRef& mass) {
  std::vector<bool> decoupled(static_cast<size_t>(K.cols()));
  for (int j = 0; j < K.outerSize(); ++j) {
    bool empty = mass[j / 3] == 0;
    for (SparseMatrix::InnerIterator it(K, j); it && empty; ++it) empty = it.value() == 0;
    decoupled[static_cast<size_t>(j)] = empty;
  }
  return decoupled;
}

Eigen::MatrixXd checked_kernel_basis(const SparseMatrix& K, const VectorRef& mass,
                                     const Eigen::Ref<const Eigen::MatrixXd>& Z) {
  validate_stiffness_and_mass(K, mass);
  if (Z.rows() != K.rows())
    throw InputError(message("Z: expected ", K.rows(), " rows, got ", Z.rows()));
  if (!Z.allFinite()) throw InputError("Z: has an entry that is not finite");
  Eigen::MatrixXd basis = Z;
  const std::vector<bool> decoupled = decoupled_dofs(K, mass);
  for (Eigen::Index d = 0; d < Z.rows(); ++d)
    if (decoupled[static_cast<size_t>(d)]) basis.row(d).setZero();
  const Eigen::MatrixXd gram = basis.transpose() * (dof_masses(mass).asDiagonal() * basis);
  Eigen::Index i = 0, j = 0;
  if (Z.cols() &&
      (gram - Eigen::MatrixXd::Identity(Z.cols(), Z.cols())).cwiseAbs().maxCoeff(&i, &j) >
          kOrthonormalTolerance)
    throw InputError(message("Z: expected M-orthonormal columns, but (Z^T M Z)(", i, ", ", j,
                             ") = ", gram(i, j)));
  const Eigen::MatrixXd KZ = multiply(K, basis);
  const double norm_K = norm_1(K);
  for (Eigen::Index k = 0; k < Z.cols(); ++k) {
    const double relative = KZ.col(k).norm() / (norm_K * basis.col(k).norm());
    if (relative > kKernelTolerance)
      throw InputError(message("Z: column ", k,
                               " is not in the kernel of K (|K z| / (|K| |z|) = ", relative, ")"));
  }
  return basis;
}

}  // namespace modal_deform
