// Products and norms of a sparse matrix (CSC, as Eigen stores it) that Eigen leaves to one thread
// or lacks.
#pragma once

#include "util/types.h"

namespace modal_deform {

// out += scale A X, and A X, in blocks of a few columns on the OpenMP threads (Eigen's sparse
// products run on one thread). A: r by c; X: c by k; out: r by k.
void add_product(const SparseMatrix& A, const Eigen::Ref<const Eigen::MatrixXd>& X, double scale,
                 Eigen::Ref<Eigen::MatrixXd> out);
Eigen::MatrixXd multiply(const SparseMatrix& A, const Eigen::Ref<const Eigen::MatrixXd>& X);

// ‖A‖₁, the largest column sum of |A|.
double norm_1(const SparseMatrix& A);

}  // namespace modal_deform
