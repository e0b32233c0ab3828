#include "modes/stiffness_and_mass.h"

#include <algorithm>
#include <cmath>

#include "util/errors.h"

namespace modal_deform {
namespace {

// K(i, j) and K(j, i) may differ by this much relative to K's largest entry (rounding in the
// assembly of element Hessians).
constexpr double kSymmetryTolerance = 1e-10;

// K(row, col), zero when not stored; columns hold sorted row indices.
double entry(const SparseMatrix& K, int row, int col) {
  const int* begin = K.innerIndexPtr() + K.outerIndexPtr()[col];
  const int* end = K.isCompressed() ? K.innerIndexPtr() + K.outerIndexPtr()[col + 1]
                                    : begin + K.innerNonZeroPtr()[col];
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
    throw InputError(message("K: expected ", 3 * n, " by ", 3 * n, " (3 per vertex), got ", K.rows(), " by ", K.cols()));
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

}  // namespace modal_deform
