#include <gtest/gtest.h>
#include <omp.h>

#include <atomic>
#include <stdexcept>
#include <string>
#include <vector>

#include "linalg/row_blocks.h"
#include "test_support.h"
#include "util/parallel_for.h"

namespace modal_deform {
namespace {

Eigen::MatrixXd random_matrix(Eigen::Index rows, Eigen::Index cols, unsigned seed) {
  return testing::random_vector(rows * cols, seed).reshaped(rows, cols);
}

// The sum over blocks, written out serially in block order: the parallel one must give the same
// bits.
Eigen::MatrixXd inner_in_block_order(const Eigen::MatrixXd& A, const Eigen::VectorXd& d,
                                     const Eigen::MatrixXd& B) {
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(A.cols(), B.cols());
  for (Eigen::Index first = 0; first < A.rows(); first += kRowBlock) {
    const Eigen::Index count = std::min(kRowBlock, A.rows() - first);
    const Eigen::MatrixXd part =
        A.middleRows(first, count).transpose() *
        (d.segment(first, count).asDiagonal() * B.middleRows(first, count));
    sum += part;
  }
  return sum;
}

TEST(RowBlocks, ProductsMatchTheirDefinitionForAnyNumberOfThreads) {
  const Eigen::Index n = 5 * kRowBlock + 123;  // a short last block
  const Eigen::MatrixXd A = random_matrix(n, 7, 1), B = random_matrix(n, 5, 2),
                        C = random_matrix(7, 5, 3);
  const Eigen::VectorXd d = testing::random_vector(n, 4).cwiseAbs();
  const Eigen::MatrixXd expected = inner_in_block_order(A, d, B);
  const int threads = omp_get_max_threads();
  for (int t : {1, 2, 3}) {
    omp_set_num_threads(t);
    EXPECT_EQ(inner_product(A, d, B), expected) << t << " threads";
    EXPECT_EQ(inner_product(A, B), inner_in_block_order(A, Eigen::VectorXd::Ones(n), B))
        << t << " threads";
    Eigen::MatrixXd X = B;
    add_dense_product(X, A, C);
    EXPECT_LT((X - (B + A * C)).cwiseAbs().maxCoeff(), 1e-12) << t << " threads";
    const Eigen::MatrixXd AC = dense_product(A, C);
    ASSERT_EQ(AC.rows(), n);
    ASSERT_EQ(AC.cols(), C.cols());
    EXPECT_LT((AC - A * C).cwiseAbs().maxCoeff(), 1e-12) << t << " threads";
  }
  omp_set_num_threads(threads);
  EXPECT_LT((inner_product(A, d, B) - A.transpose() * d.asDiagonal() * B).cwiseAbs().maxCoeff(),
            1e-9);
}

TEST(RowBlocks, VisitsEachRowOnceAndHandlesFewOrNoRows) {
  for (const Eigen::Index n : {Eigen::Index{0}, Eigen::Index{1}, kRowBlock, 2 * kRowBlock + 1}) {
    std::vector<int> visits(static_cast<size_t>(n), 0);
    for_row_blocks(n, [&](Eigen::Index first, Eigen::Index count) {
      for (Eigen::Index i = first; i < first + count; ++i) ++visits[static_cast<size_t>(i)];
    });
    EXPECT_EQ(std::count(visits.begin(), visits.end(), 1), n);
    EXPECT_EQ(inner_product(Eigen::MatrixXd::Ones(n, 2), Eigen::MatrixXd::Ones(n, 3)),
              Eigen::MatrixXd::Constant(2, 3, static_cast<double>(n)));
  }
}

TEST(ParallelFor, RunsEveryIndexOnceAndRethrowsTheFirstFailure) {
  std::vector<std::atomic<int>> runs(1000);
  parallel_for(1000, [&](int i) { ++runs[static_cast<size_t>(i)]; });
  for (const auto& count : runs) EXPECT_EQ(count.load(), 1);
  EXPECT_THROW(parallel_for(1000,
                            [](int i) {
                              if (i % 100 == 7)
                                throw std::runtime_error("index " + std::to_string(i));
                            }),
               std::runtime_error);
}

}  // namespace
}  // namespace modal_deform
