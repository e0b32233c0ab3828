#include <gtest/gtest.h>

#include <random>

#include "reduction/orthonormalize.h"
#include "test_support.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

Eigen::MatrixXd random_matrix(Eigen::Index rows, Eigen::Index cols, unsigned seed) {
  return testing::random_vector(rows * cols, seed).reshaped(rows, cols);
}

Eigen::VectorXd random_masses(Eigen::Index n, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> uniform(0.01, 2.0);
  Eigen::VectorXd m(n);
  for (Eigen::Index i = 0; i < n; ++i) m[i] = uniform(random);
  return m;
}

double orthonormality_error(const Eigen::MatrixXd& Q, const Eigen::VectorXd& m) {
  return (Q.transpose() * m.asDiagonal() * Q - Eigen::MatrixXd::Identity(Q.cols(), Q.cols()))
      .cwiseAbs()
      .maxCoeff();
}

// The relative M-norm of what is left of u after M-projection onto the columns of Q.
double outside_span(const Eigen::MatrixXd& Q, const Eigen::VectorXd& m, const Eigen::VectorXd& u) {
  const Eigen::VectorXd r = u - Q * (Q.transpose() * m.asDiagonal() * u);
  return std::sqrt(r.dot(m.asDiagonal() * r) / u.dot(m.asDiagonal() * u));
}

TEST(Orthonormalize, DropsDependentColumnsAcrossBlocksAndKeepsTheSpan) {
  const Eigen::Index n = 3000;
  const Eigen::VectorXd m = random_masses(n, 1);
  Eigen::MatrixXd U = random_matrix(n, 80, 2);
  U.col(5).setZero();                                // nothing
  U.col(17) = 2 * U.col(3) - U.col(11);              // dependent within the first block
  U.col(50) = U.col(1) + 1e-9 * U.col(50);           // dependent up to 1e-9, across blocks
  U.col(70) = U.col(40) - 3 * U.col(65) + U.col(2);  // dependent on columns of three blocks
  U.col(79) = U.col(78) + 1e-3 * U.col(79);          // nearly dependent, but above the tolerance
  const Eigen::MatrixXd original = U;
  const std::vector<int> kept = orthonormalize(U, m);
  std::vector<int> expected;
  for (int j = 0; j < 80; ++j)
    if (j != 5 && j != 17 && j != 50 && j != 70) expected.push_back(j);
  EXPECT_EQ(kept, expected);
  ASSERT_EQ(U.cols(), static_cast<Eigen::Index>(kept.size()));
  EXPECT_LT(orthonormality_error(U, m), 1e-12);
  for (int j = 0; j < 80; ++j) {
    if (j == 5) continue;
    EXPECT_LT(outside_span(U, m, original.col(j)), 1e-8) << "column " << j;
  }
  // Triangular: the first k columns of Q span the first k kept columns.
  for (int k = 1; k < 10; ++k)
    EXPECT_LT(outside_span(U.leftCols(k), m, original.col(kept[static_cast<size_t>(k - 1)])),
              1e-10);
}

TEST(Orthonormalize, LeavesAnOrthonormalLeadingBlockAsItIs) {
  const Eigen::Index n = 2000;
  const Eigen::VectorXd m = random_masses(n, 3);
  Eigen::MatrixXd U = random_matrix(n, 50, 4);
  Eigen::MatrixXd leading = U.leftCols(12);
  ASSERT_TRUE(orthonormalize(leading, m).size() == 12);
  U.leftCols(12) = leading;
  orthonormalize(U, m);
  EXPECT_LT((U.leftCols(12) - leading).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT(orthonormality_error(U, m), 1e-12);
}

TEST(Orthonormalize, ZeroMassRowsAndBadInput) {
  Eigen::VectorXd m = random_masses(600, 5);
  m.head(30).setZero();
  Eigen::MatrixXd U = random_matrix(600, 10, 6);
  U.col(4).tail(570).setZero();  // lives only where there is no mass: M-norm zero
  const std::vector<int> kept = orthonormalize(U, m);
  EXPECT_EQ(kept, (std::vector<int>{0, 1, 2, 3, 5, 6, 7, 8, 9}));
  EXPECT_LT(orthonormality_error(U, m), 1e-12);

  Eigen::MatrixXd bad = random_matrix(600, 3, 7);
  bad(10, 1) = std::nan("");
  EXPECT_THROW(orthonormalize(bad, m), InputError);
  Eigen::MatrixXd short_mass = random_matrix(600, 3, 7);
  EXPECT_THROW(orthonormalize(short_mass, m.head(599)), InputError);
}

}  // namespace
}  // namespace modal_deform
