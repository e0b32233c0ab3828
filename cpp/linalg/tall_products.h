// Products of tall dense blocks (3n rows by tens of columns, hundreds of MB at 100k vertices) on
// the OpenMP threads: Eigen's own products run on one thread here (EIGEN_DONT_PARALLELIZE), and
// these are memory bound, so the row chunks are what both cores can share. The chunks have a
// fixed size and are summed in a fixed order, so a result does not depend on the thread count.
#pragma once

#include "util/types.h"

namespace modal_deform {

// Aᵀ diag(w) B; A and B with the rows of w.
Eigen::MatrixXd weighted_inner(const Eigen::Ref<const Eigen::MatrixXd>& A, const Eigen::VectorXd& w,
                               const Eigen::Ref<const Eigen::MatrixXd>& B);

// X −= A C.
void subtract_product(const Eigen::Ref<const Eigen::MatrixXd>& A, const Eigen::Ref<const Eigen::MatrixXd>& C,
                      Eigen::Ref<Eigen::MatrixXd> X);

}  // namespace modal_deform
