#include "linalg/sparse_operations.h"

#include <algorithm>
#include <cmath>

#include <omp.h>

namespace modal_deform {
namespace {

// Columns of X per task of add_product, copied to row-major storage: Eigen then streams A once per
// task and adds each entry's multiple of a contiguous row, where column-major columns make it
// stream A once per column. 8 columns are about as fast as wider tasks, for two 8-column buffers
// per thread.
constexpr Eigen::Index kProductColumns = 8;

}  // namespace

void add_product(const SparseMatrix& A, const Eigen::Ref<const Eigen::MatrixXd>& X, double scale,
                 Eigen::Ref<Eigen::MatrixXd> out) {
  using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const Eigen::Index tasks = (X.cols() + kProductColumns - 1) / kProductColumns;
#pragma omp parallel if (tasks > 1)
  {
    RowMajorMatrix rows, product;  // reused from task to task
#pragma omp for schedule(dynamic)
    for (Eigen::Index task = 0; task < tasks; ++task) {
      const Eigen::Index first = task * kProductColumns,
                         width = std::min(kProductColumns, X.cols() - first);
      rows = X.middleCols(first, width);
      product.noalias() = A * rows;
      out.middleCols(first, width) += scale * product;
    }
  }
}

Eigen::MatrixXd multiply(const SparseMatrix& A, const Eigen::Ref<const Eigen::MatrixXd>& X) {
  Eigen::MatrixXd AX = Eigen::MatrixXd::Zero(A.rows(), X.cols());
  add_product(A, X, 1.0, AX);
  return AX;
}

double norm_1(const SparseMatrix& A) {
  double largest = 0;
  for (int j = 0; j < A.outerSize(); ++j) {
    double sum = 0;
    for (SparseMatrix::InnerIterator it(A, j); it; ++it) sum += std::abs(it.value());
    largest = std::max(largest, sum);
  }
  return largest;
}

}  // namespace modal_deform
