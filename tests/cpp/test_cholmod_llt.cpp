#include <gtest/gtest.h>

#include <omp.h>

#include <Eigen/SparseCholesky>
#include <random>

#include "linalg/cholmod_llt.h"
#include "linalg/sparse_operations.h"
#include "mesh/mass.h"
#include "modes/stiffness_and_mass.h"
#include "stand_in_stiffness.h"
#include "test_support.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

using testing::laplacian_stiffness;
using testing::shared_mesh;
using testing::spring_network_hessian;

// A random sparse symmetric positive definite matrix: random off-diagonal entries, both
// triangles stored, and a diagonal that dominates each row.
SparseMatrix random_spd(int n, int per_column, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> row(0, n - 1);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::VectorXd row_sum = Eigen::VectorXd::Zero(n);
  for (int j = 0; j < n; ++j)
    for (int k = 0; k < per_column; ++k) {
      const int i = row(random);
      if (i == j) continue;
      const double v = value(random);
      triplets.emplace_back(i, j, v);
      triplets.emplace_back(j, i, v);
      row_sum[i] += std::abs(v);
      row_sum[j] += std::abs(v);
    }
  for (int i = 0; i < n; ++i) triplets.emplace_back(i, i, row_sum[i] + 0.1 + value(random) * 0.05);
  SparseMatrix A(n, n);
  A.setFromTriplets(triplets.begin(), triplets.end());
  return A;
}

// The bunny's spring network plus its mass matrix: the pattern of a shells Hessian, definite.
SparseMatrix bunny_stiffness_plus_mass() {
  const TriangleMesh& bunny = shared_mesh("bunny.obj.gz");
  SparseMatrix A = spring_network_hessian(bunny.V, bunny.F);
  const Eigen::VectorXd m = dof_masses(lumped_mass(bunny.V, bunny.F));
  for (int d = 0; d < A.rows(); ++d) A.coeffRef(d, d) += m[d] * 1e3;
  return A;
}

Eigen::MatrixXd random_block(Eigen::Index rows, Eigen::Index cols, unsigned seed) {
  std::srand(seed);
  return Eigen::MatrixXd::Random(rows, cols);
}

double relative_error(const Eigen::MatrixXd& x, const Eigen::MatrixXd& reference) {
  return (x - reference).norm() / reference.norm();
}

TEST(CholmodLLT, SolvesLikeSimplicialLDLT) {
  // 3 DOFs per node orders the node graph; 2000 rows is not a multiple of 3 and falls back to 1.
  for (const SparseMatrix& A :
       {random_spd(400, 6, 1), random_spd(2000, 3, 2), bunny_stiffness_plus_mass()})
    for (int dofs_per_node : {1, 3}) {
      const Eigen::MatrixXd B = random_block(A.rows(), 3, 3);
      CholmodLLT llt(dofs_per_node);
      llt.factorize(A);
      const Eigen::SimplicialLDLT<SparseMatrix> reference(A);
      ASSERT_EQ(reference.info(), Eigen::Success);
      EXPECT_LT(relative_error(llt.solve(B), reference.solve(B)), 1e-10) << "n = " << A.rows();
      EXPECT_GT(llt.rcond(), 0.0);
      EXPECT_GT(llt.factor_nonzeros(), 0.0);
    }
}

TEST(CholmodLLT, NodeOrderingFillsNoMoreThanRowOrdering) {
  const SparseMatrix A = bunny_stiffness_plus_mass();
  CholmodLLT rows(1), nodes(3);
  rows.analyze(A);
  nodes.analyze(A);
  EXPECT_LT(nodes.factor_nonzeros(), 1.1 * rows.factor_nonzeros());
  EXPECT_THROW(CholmodLLT(0), InputError);
}

TEST(CholmodLLT, BlockSolveEqualsColumnSolves) {
  const SparseMatrix A = bunny_stiffness_plus_mass();
  const Eigen::MatrixXd B = random_block(A.rows(), 64, 4);
  CholmodLLT llt;
  llt.factorize(A);
  const Eigen::MatrixXd X = llt.solve(B);
  for (Eigen::Index j = 0; j < B.cols(); ++j)
    EXPECT_LT(relative_error(X.col(j), llt.solve(B.col(j))), 1e-13) << "column " << j;
  // A block that is a view into a larger matrix (outer stride above its rows).
  const Eigen::MatrixXd tall = random_block(2 * A.rows(), 5, 5);
  const Eigen::MatrixXd top = tall.topRows(A.rows());
  EXPECT_LT(relative_error(llt.solve(tall.topRows(A.rows())), llt.solve(top)), 1e-15);
  // Into a caller's buffer, a view included: the same solution; a buffer of another size is
  // refused.
  Eigen::MatrixXd into = Eigen::MatrixXd::Zero(A.rows(), 70);
  llt.solve(B, into.middleCols(3, 64));
  EXPECT_EQ(into.middleCols(3, 64), X);
  EXPECT_EQ(into.leftCols(3).norm() + into.rightCols(3).norm(), 0.0);
  Eigen::MatrixXd wrong(A.rows(), 63);
  EXPECT_THROW(llt.solve(B, wrong), InputError);
}

TEST(SparseProducts, BlockedByThreadMatchEigens) {
  const SparseMatrix A = bunny_stiffness_plus_mass();
  const Eigen::MatrixXd X = random_block(A.rows(), 7, 6);
  const Eigen::MatrixXd expected = A * X;
  EXPECT_LT(relative_error(multiply(A, X), expected), 1e-15);
  Eigen::MatrixXd out = X;
  add_product(A, X, -2.0, out);
  EXPECT_LT(relative_error(out, X - 2.0 * expected), 1e-15);
  EXPECT_EQ(multiply(A, Eigen::MatrixXd(A.rows(), 0)).cols(), 0);
}

TEST(CholmodLLT, ShiftedFactorizationsReuseOrRedoTheAnalysis) {
  const SparseMatrix A = random_spd(500, 5, 6);
  CholmodLLT llt;
  llt.analyze(A);
  const Eigen::MatrixXd B = random_block(A.rows(), 2, 7);
  for (double scale : {0.0, 0.5, 30.0}) {
    const Eigen::VectorXd shift = scale * Eigen::VectorXd::LinSpaced(A.rows(), 1.0, 2.0);
    llt.factorize(A, shift);
    SparseMatrix shifted = A;
    shifted.diagonal() += shift;
    const Eigen::SimplicialLDLT<SparseMatrix> reference(shifted);
    EXPECT_LT(relative_error(llt.solve(B), reference.solve(B)), 1e-10) << "shift scale " << scale;
  }
  // Another pattern of the same size: analysed anew.
  const SparseMatrix other = random_spd(500, 7, 8);
  llt.factorize(other);
  const Eigen::SimplicialLDLT<SparseMatrix> reference(other);
  EXPECT_LT(relative_error(llt.solve(B), reference.solve(B)), 1e-10);
}

TEST(CholmodLLT, IndefiniteMatrixThrowsWithoutPrinting) {
  SparseMatrix A = random_spd(300, 4, 9);
  A.coeffRef(123, 123) = -5.0;
  CholmodLLT llt;
  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  try {
    llt.factorize(A);
    ADD_FAILURE() << "no exception";
  } catch (const NumericalError& e) {
    EXPECT_NE(std::string(e.what()).find("not positive definite"), std::string::npos) << e.what();
  }
  EXPECT_EQ(llt.failed_row(), 123);  // the bake names the vertex of that row
  EXPECT_EQ(::testing::internal::GetCapturedStdout(), "");
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
  // The failed factorisation is not used.
  EXPECT_THROW(llt.solve(Eigen::VectorXd::Ones(A.rows())), std::logic_error);
  A.coeffRef(123, 123) = 100.0;
  llt.factorize(A);
  EXPECT_EQ(llt.failed_row(), -1);
}

// CHOLMOD's own OpenMP loops run on the calling thread during a factorisation (cholmod_llt.cpp);
// the caller's setting is back afterwards, also when the factorisation throws.
TEST(CholmodLLT, FactorizationLeavesTheCallersOpenMPAsItWas) {
  const int levels = omp_get_max_active_levels();
  omp_set_max_active_levels(2);
  SparseMatrix A = random_spd(300, 4, 9);
  CholmodLLT llt;
  llt.factorize(A);
  EXPECT_EQ(omp_get_max_active_levels(), 2);
  A.coeffRef(123, 123) = -5.0;
  EXPECT_THROW(llt.factorize(A), NumericalError);
  EXPECT_EQ(omp_get_max_active_levels(), 2);
  omp_set_max_active_levels(levels);
}

TEST(CholmodLLT, SingularMatricesThrow) {
  const TriangleMesh& bunny = shared_mesh("bunny.obj.gz");
  // Positive semidefinite with 3 and 6 zero eigenvalues: the last pivots are rounding noise.
  for (const SparseMatrix& K :
       {laplacian_stiffness(bunny.V, bunny.F), spring_network_hessian(bunny.V, bunny.F)}) {
    CholmodLLT llt;
    EXPECT_THROW(llt.factorize(K), NumericalError);
  }
}

TEST(CholmodLLT, EmptyColumnIsAZeroPivotNamedByRow) {
  SparseMatrix A = random_spd(50, 4, 10);
  for (int j = 0; j < A.outerSize(); ++j)
    for (SparseMatrix::InnerIterator it(A, j); it; ++it)
      if (it.row() == 17 || it.col() == 17) it.valueRef() = 0;
  A.prune(0.0);
  CholmodLLT llt;
  try {
    llt.factorize(A);
    ADD_FAILURE() << "no exception";
  } catch (const NumericalError& e) {
    EXPECT_NE(std::string(e.what()).find("row 17 "), std::string::npos) << e.what();
  }
}

TEST(CholmodLLT, RejectsMalformedInput) {
  CholmodLLT llt;
  EXPECT_THROW(llt.factorize(SparseMatrix(3, 4)), InputError);
  SparseMatrix A = random_spd(20, 3, 11);
  EXPECT_THROW(llt.factorize(A, Eigen::VectorXd::Zero(19)), InputError);
  Eigen::VectorXd shift = Eigen::VectorXd::Zero(20);
  shift[4] = std::nan("");
  EXPECT_THROW(llt.factorize(A, shift), InputError);
  A.coeffRef(2, 2) = std::numeric_limits<double>::infinity();
  try {
    llt.factorize(A);
    ADD_FAILURE() << "no exception";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "A(2, 2) is not finite");
  }
  EXPECT_THROW(llt.solve(Eigen::VectorXd::Ones(20)), std::logic_error);
  llt.factorize(random_spd(20, 3, 12));
  EXPECT_THROW(llt.solve(Eigen::VectorXd::Ones(21)), InputError);
}

}  // namespace
}  // namespace modal_deform
