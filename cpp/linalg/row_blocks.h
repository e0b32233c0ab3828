// Dense work on tall matrices (3n rows: bases, blocks of right-hand sides) over fixed blocks of
// rows, in parallel with OpenMP: Eigen's own threading is off (EIGEN_DONT_PARALLELIZE, see
// CMakeLists.txt). The blocks do not depend on the number of threads, and sums over them are
// added in block order, so results are the same for any number of threads and from run to run.
#pragma once

#include <algorithm>
#include <vector>

#include "util/parallel_for.h"
#include "util/types.h"

namespace modal_deform {

// Rows per block: a few MB of a 50-column block, enough to amortise a task. A matrix of at most
// this many rows stays on the calling thread (waking a team of threads on a busy machine costs
// more than such a product).
constexpr Eigen::Index kRowBlock = 8192;

inline Eigen::Index row_blocks(Eigen::Index rows) { return (rows + kRowBlock - 1) / kRowBlock; }

// Calls work(first, count) for each block of rows [first, first + count) of [0, rows).
template <typename Work>
void for_row_blocks(Eigen::Index rows, Work&& work) {
  parallel_for(row_blocks(rows), [&](Eigen::Index block) {
    const Eigen::Index first = block * kRowBlock;
    work(first, std::min(kRowBlock, rows - first));
  });
}

// Σ over the blocks of term(first, count), each an r by c matrix, added in block order.
template <typename Term>
Eigen::MatrixXd sum_over_row_blocks(Eigen::Index rows, Eigen::Index r, Eigen::Index c,
                                    Term&& term) {
  std::vector<Eigen::MatrixXd> partial(static_cast<size_t>(row_blocks(rows)));
  for_row_blocks(rows, [&](Eigen::Index first, Eigen::Index count) {
    partial[static_cast<size_t>(first / kRowBlock)].noalias() = term(first, count);
  });
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(r, c);
  for (const Eigen::MatrixXd& p : partial) sum += p;
  return sum;
}

// Aᵀ B (a by b) for A (n by a) and B (n by b).
inline Eigen::MatrixXd inner_product(const Eigen::Ref<const Eigen::MatrixXd>& A,
                                     const Eigen::Ref<const Eigen::MatrixXd>& B) {
  return sum_over_row_blocks(
      A.rows(), A.cols(), B.cols(), [&](Eigen::Index first, Eigen::Index count) {
        return A.middleRows(first, count).transpose() * B.middleRows(first, count);
      });
}

// Aᵀ diag(d) B (a by b) for A (n by a), d (n) and B (n by b).
inline Eigen::MatrixXd inner_product(const Eigen::Ref<const Eigen::MatrixXd>& A, const VectorRef& d,
                                     const Eigen::Ref<const Eigen::MatrixXd>& B) {
  return sum_over_row_blocks(
      A.rows(), A.cols(), B.cols(), [&](Eigen::Index first, Eigen::Index count) {
        return A.middleRows(first, count).transpose() *
               (d.segment(first, count).asDiagonal() * B.middleRows(first, count));
      });
}

// A C (n by c) for A (n by a) and C (a by c).
inline Eigen::MatrixXd dense_product(const Eigen::Ref<const Eigen::MatrixXd>& A,
                                     const Eigen::MatrixXd& C) {
  Eigen::MatrixXd X(A.rows(), C.cols());
  for_row_blocks(A.rows(), [&](Eigen::Index first, Eigen::Index count) {
    X.middleRows(first, count).noalias() = A.middleRows(first, count) * C;
  });
  return X;
}

// X += A C for X (n by c), A (n by a) and C (a by c).
inline void add_dense_product(Eigen::Ref<Eigen::MatrixXd> X,
                              const Eigen::Ref<const Eigen::MatrixXd>& A,
                              const Eigen::MatrixXd& C) {
  for_row_blocks(X.rows(), [&](Eigen::Index first, Eigen::Index count) {
    X.middleRows(first, count).noalias() += A.middleRows(first, count) * C;
  });
}

}  // namespace modal_deform
