#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "solve/quantized_vectors.h"
#include "test_support.h"

namespace modal_deform {
namespace {

// Rows of very different sizes from block to block and column to column (as a basis has: flaps that
// move far, a still region of zero rows), more than one thread's worth, a short last block.
RowMatrixXf uneven_vectors(Eigen::Index rows, Eigen::Index cols) {
  const Eigen::Index block = QuantizedVectors::kRowsPerBlock;
  RowMatrixXf U =
      testing::random_vector(rows * cols, 7).cast<float>().reshaped<Eigen::RowMajor>(rows, cols);
  for (Eigen::Index k = 0; k < rows; ++k)
    U.row(k) *= std::pow(10.0f, static_cast<float>((k / block) % 5) - 2.0f);
  for (Eigen::Index j = 0; j < cols; ++j)
    U.col(j) *= std::pow(10.0f, static_cast<float>(j % 3) - 1.0f);
  U.middleRows(2 * block, block).setZero();
  return U;
}

// rest + U q in double from the float32 entries: what the float32 map rounds.
Eigen::VectorXd exact_map(const RowMatrixXf& U, const Eigen::VectorXf& q,
                          const Eigen::VectorXd& rest) {
  return rest + U.cast<double>() * q.cast<double>();
}

TEST(QuantizedVectors, EveryCoordinateIsWithinTheToleranceAndTheBoundChoosesFloat32Blocks) {
  const Eigen::Index rows = 70 * QuantizedVectors::kRowsPerBlock + 77, cols = 67;
  const RowMatrixXf U = uneven_vectors(rows, cols);
  const QuantizedVectors quantized(U);
  ASSERT_EQ(quantized.blocks(), 71);
  const Eigen::VectorXf q = (10.0 * testing::random_vector(cols, 3)).cast<float>();
  const Eigen::VectorXf rest32 = testing::random_vector(rows, 5).cast<float>();
  const Eigen::VectorXd rest = rest32.cast<double>();
  const Eigen::VectorXd expected = exact_map(U, q, rest);
  const double largest = (expected - rest).cwiseAbs().maxCoeff();
  const double rounding = 1e-6 * (largest + rest.cwiseAbs().maxCoeff());  // float32's own
  Eigen::VectorXf out(rows);
  std::vector<Eigen::Index> from_float32;
  for (double tolerance : {1e3 * largest, 3e-5 * largest, 0.0}) {
    from_float32.push_back(quantized.map(U, q, rest32.data(), tolerance, out.data()));
    EXPECT_LE((out.cast<double>() - expected).cwiseAbs().maxCoeff(), tolerance + rounding)
        << tolerance;
    for (Eigen::Index k = 2 * QuantizedVectors::kRowsPerBlock;
         k < 3 * QuantizedVectors::kRowsPerBlock; ++k)
      ASSERT_EQ(out(k), rest32(k)) << "a zero row moves";
  }
  EXPECT_EQ(from_float32[0], 0);
  EXPECT_GT(from_float32[1], 0) << "the largest rows' bound exceeds 3e-5 of the largest coordinate";
  EXPECT_LT(from_float32[1], quantized.blocks() / 2) << "the smaller rows' does not";
  EXPECT_EQ(from_float32[2], quantized.blocks() - 1)
      << "no tolerance: every block but the zero one from float32";
  // The 16 bits alone are far better than the largest tolerance, and U q alone without a rest.
  EXPECT_EQ(quantized.map(U, q, nullptr, 1e3 * largest, out.data()), 0);
  EXPECT_LE((out.cast<double>() - (expected - rest)).cwiseAbs().maxCoeff(), 1e-4 * largest);
}

}  // namespace
}  // namespace modal_deform
