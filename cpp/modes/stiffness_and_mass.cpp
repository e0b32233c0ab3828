#include "modes/stiffness_and_mass.h"

#include <algorithm>
#include <cmath>

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

// K(row, col), zero when not stored; columns hold sorted row indices.
double entry(const SparseMatrix& K, int row, int col) {
  const int* begin = K.innerIndexPtr() + K.outerIndexPtr()[col];
  const int* end = K.isCompressed() ? K.innerIndexPtr() + K.outerIndexPtr()[col + 1] : begin + K.innerNonZeroPtr()[col];
  const int* it = std::lower_bound(begin, end, row);
  return it != end && *it == row ? K.valuePtr()[it - K.innerIndexPtr()] : 0.0;
}

}  // namespace

void validate_stiffness_and_mass(const SparseMatrix& K, const VectorRef& mass) {
  const Eigen::Index n = mass.size();
  if (n == 0) throw InputError("mass: no vertices");
  for (Eigen::Index i = 0; i < n; ++i)
    if (!(std::isfinite(mass[i]) && mass[i] >= 0))
      throw InputError(message("mass[", i, "] = ", mass[i], ": expected a finite non-negative mass"));
  if (K.rows() != 3 * n || K.cols() != 3 * n)
    throw InputError(
        message("K: expected ", 3 * n, " by ", 3 * n, " (3 per vertex), got ", K.rows(), " by ", K.cols()));
  double largest = 0;
  for (int j = 0; j < K.outerSize(); ++j) {
    int previous = -1;
    for (SparseMatrix::InnerIterator it(K, j); it; ++it) {
      if (!std::isfinite(it.value())) throw InputError(message("K(", it.row(), ", ", j, ") is not finite"));
      if (it.row() <= previous) throw InputError(message("K: row indices of column ", j, " are not sorted or repeat"));
      previous = static_cast<int>(it.row());
      largest = std::max(largest, std::abs(it.value()));
    }
  }
  for (int j = 0; j < K.outerSize(); ++j)
    for (SparseMatrix::InnerIterator it(K, j); it; ++it) {
      const int i = static_cast<int>(it.row());
      if (i != j && std::abs(it.value() - entry(K, j, i)) > kSymmetryTolerance * largest)
        throw InputError(message("K is not symmetric: K(", i, ", ", j, ") = ", it.value(), " but K(", j, ", ", i,
                                 ") = ", entry(K, j, i)));
    }
}

Eigen::VectorXd dof_masses(const VectorRef& mass) { return mass.replicate(1, 3).transpose().reshaped(); }

std::vector<bool> decoupled_dofs(const SparseMatrix& K, const VectorRef& mass) {
  std::vector<bool> decoupled(static_cast<size_t>(K.cols()));
  for (int j = 0; j < K.outerSize(); ++j) {
    bool empty = mass[j / 3] == 0;
    for (SparseMatrix::InnerIterator it(K, j); it && empty; ++it) empty = it.value() == 0;
    decoupled[static_cast<size_t>(j)] = empty;
  }
  return decoupled;
}

double norm_1(const SparseMatrix& K) {
  double largest = 0;
  for (int j = 0; j < K.outerSize(); ++j) {
    double sum = 0;
    for (SparseMatrix::InnerIterator it(K, j); it; ++it) sum += std::abs(it.value());
    largest = std::max(largest, sum);
  }
  return largest;
}

Eigen::MatrixXd checked_kernel_basis(const SparseMatrix& K, const VectorRef& mass,
                                     const Eigen::Ref<const Eigen::MatrixXd>& Z) {
  validate_stiffness_and_mass(K, mass);
  if (Z.rows() != K.rows()) throw InputError(message("Z: expected ", K.rows(), " rows, got ", Z.rows()));
  if (!Z.allFinite()) throw InputError("Z: has an entry that is not finite");
  Eigen::MatrixXd basis = Z;
  const std::vector<bool> decoupled = decoupled_dofs(K, mass);
  for (Eigen::Index d = 0; d < Z.rows(); ++d)
    if (decoupled[static_cast<size_t>(d)]) basis.row(d).setZero();
  const Eigen::MatrixXd gram = basis.transpose() * (dof_masses(mass).asDiagonal() * basis);
  Eigen::Index i = 0, j = 0;
  if (Z.cols() &&
      (gram - Eigen::MatrixXd::Identity(Z.cols(), Z.cols())).cwiseAbs().maxCoeff(&i, &j) > kOrthonormalTolerance)
    throw InputError(message("Z: expected M-orthonormal columns, but (Z^T M Z)(", i, ", ", j, ") = ", gram(i, j)));
  const Eigen::MatrixXd KZ = K * basis;
  const double norm_K = norm_1(K);
  for (Eigen::Index k = 0; k < Z.cols(); ++k) {
    const double relative = KZ.col(k).norm() / (norm_K * basis.col(k).norm());
    if (relative > kKernelTolerance)
      throw InputError(message("Z: column ", k, " is not in the kernel of K (|K z| / (|K| |z|) = ", relative, ")"));
  }
  return basis;
}

}  // namespace modal_deform
