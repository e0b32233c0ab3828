#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>

#include "linalg/tall_products.h"
#include "util/errors.h"
#include "util/parallel_for.h"

namespace modal_deform {
namespace {

// Sizes around the chunk size (8192 rows): one partial chunk, exactly one, several and a remainder.
class TallProducts : public ::testing::TestWithParam<Eigen::Index> {};

TEST_P(TallProducts, WeightedInnerIsAtDiagB) {
  const Eigen::Index rows = GetParam();
  const Eigen::MatrixXd A = Eigen::MatrixXd::Random(rows, 5);
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(rows, 3);
  const Eigen::VectorXd w = Eigen::VectorXd::Random(rows).cwiseAbs();
  const Eigen::MatrixXd expected = A.transpose() * w.asDiagonal() * B;
  EXPECT_LE((weighted_inner(A, w, B) - expected).norm(), 1e-12 * expected.norm());
}

TEST_P(TallProducts, SubtractProductIsXMinusAC) {
  const Eigen::Index rows = GetParam();
  const Eigen::MatrixXd A = Eigen::MatrixXd::Random(rows, 4);
  const Eigen::MatrixXd C = Eigen::MatrixXd::Random(4, 6);
  Eigen::MatrixXd X = Eigen::MatrixXd::Random(rows, 6);
  const Eigen::MatrixXd expected = X - A * C;
  subtract_product(A, C, X);
  EXPECT_LE((X - expected).norm(), 1e-12 * expected.norm());
}

INSTANTIATE_TEST_SUITE_P(RowCounts, TallProducts, ::testing::Values(1, 100, 8192, 30001));

TEST(TallProducts, MismatchedShapesAreInputErrors) {
  const Eigen::MatrixXd A = Eigen::MatrixXd::Zero(10, 2);
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(9, 3);
  EXPECT_THROW(weighted_inner(A, Eigen::VectorXd::Ones(9), A), InputError);
  EXPECT_THROW(subtract_product(A, Eigen::MatrixXd::Zero(2, 3), X), InputError);
}

TEST(ParallelFor, RunsEveryIndexOnceAndRethrowsTheFirstFailure) {
  std::vector<std::atomic<int>> runs(1000);
  parallel_for(1000, [&](int i) { ++runs[static_cast<size_t>(i)]; });
  for (const auto& count : runs) EXPECT_EQ(count.load(), 1);
  EXPECT_THROW(parallel_for(1000,
                            [](int i) {
                              if (i % 100 == 7) throw std::runtime_error("index " + std::to_string(i));
                            }),
               std::runtime_error);
}

}  // namespace
}  // namespace modal_deform
