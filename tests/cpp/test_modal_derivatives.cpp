#include <gtest/gtest.h>

#include <algorithm>

#include "mesh/mass.h"
#include "mesh/mesh_topology.h"
#include "modes/modal_derivatives.h"
#include "modes/rigid_motions.h"
#include "modes/stiffness_and_mass.h"
#include "stand_in_stiffness.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

using testing::jittered_bar;
using testing::side_by_side;
using testing::spring_network_hessian;

// Two rigid spring networks with their stiffness, masses and rigid motions, plus an unreferenced
// vertex (no mass, no stiffness) at the end.
struct Problem {
  TriangleMesh mesh;
  SparseMatrix K;
  Eigen::VectorXd mass;
  Eigen::VectorXi labels;
  Eigen::MatrixXd Z;
};

Problem two_boxes() {
  Problem p;
  p.mesh = side_by_side(jittered_bar(2, 2, 3, 0.05, 1), jittered_bar(1, 2, 2, 0.05, 2),
                        Eigen::RowVector3d(3, 0, 0));
  p.mesh.V.conservativeResize(p.mesh.V.rows() + 1, 3);
  p.mesh.V.bottomRows(1) << 9, 9, 9;
  p.K = spring_network_hessian(p.mesh.V, p.mesh.F);
  p.mass = lumped_mass(p.mesh.V, p.mesh.F);
  const std::vector<int> component = build_topology(p.mesh.V, p.mesh.F).vertex_component;
  p.labels = Eigen::Map<const Eigen::VectorXi>(component.data(),
                                               static_cast<Eigen::Index>(component.size()));
  p.Z = rigid_motions(p.mesh.V, p.labels, p.mass);
  return p;
}

Eigen::MatrixXd random_block(Eigen::Index rows, Eigen::Index cols, unsigned seed) {
  std::srand(seed);
  return Eigen::MatrixXd::Random(rows, cols);
}

// B projected Euclidean-orthogonally to the columns of Z.
Eigen::MatrixXd project_to_range(const Eigen::MatrixXd& Z, const Eigen::MatrixXd& B) {
  return B - Z * (Z.transpose() * Z).ldlt().solve(Z.transpose() * B);
}

TEST(DerivativePairs, FollowThePapersOrder) {
  const auto one_component = [](int k) {
    return std::vector<std::vector<int>>(static_cast<size_t>(k), {0});
  };
  const std::vector<std::array<int, 2>> expected{{0, 0}, {0, 1}, {1, 1}, {0, 2}, {1, 2}, {2, 2}};
  EXPECT_EQ(derivative_pairs(one_component(3), 6), expected);
  EXPECT_EQ(derivative_pairs(one_component(5), 4),
            (std::vector<std::array<int, 2>>(expected.begin(), expected.begin() + 4)));
  EXPECT_EQ(derivative_pairs(one_component(15), 120).size(), 120u);
  EXPECT_TRUE(derivative_pairs(one_component(4), 0).empty());
  EXPECT_THROW(derivative_pairs(one_component(3), 7), InputError);
  EXPECT_THROW(derivative_pairs(one_component(3), -1), InputError);
}

TEST(DerivativePairs, LeaveOutModesOfDifferentComponents) {
  // A rotation of component 0, one of component 1, a mode moving both, a mode of component 1.
  const std::vector<std::vector<int>> components{{0}, {1}, {0, 1}, {1}};
  const std::vector<std::array<int, 2>> expected{{0, 0}, {1, 1}, {0, 2}, {1, 2},
                                                 {2, 2}, {1, 3}, {2, 3}, {3, 3}};
  EXPECT_EQ(derivative_pairs(components, 8), expected);
  try {
    derivative_pairs(components, 9);
    ADD_FAILURE() << "9 pairs accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("derivatives: 9 asked for, but the 4 modes"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("only 8 pairs"), std::string::npos) << e.what();
  }
}

TEST(DerivativePairs, ComponentsMovedAreThoseCarryingTheMode) {
  const Problem p = two_boxes();
  const Eigen::VectorXi labels =
      p.labels.head(p.labels.size() - 1);  // without the unreferenced vertex
  const Eigen::MatrixXd Z = p.Z.topRows(3 * labels.size());
  Eigen::MatrixXd Phi(Z.rows(), 3);
  Phi << Z.col(3), Z.col(9), Z.col(4) + Z.col(10);
  Phi(0, 1) += 1e-9;  // rounding on component 0 does not count for a mode of component 1
  const std::vector<std::vector<int>> expected{{0}, {1}, {0, 1}};
  EXPECT_EQ(components_moved(Phi, labels), expected);
  EXPECT_THROW(components_moved(Phi.topRows(3), labels), InputError);
  EXPECT_THROW(components_moved(Phi, -labels), InputError);
}

TEST(SolveInRange, SolvesTheProjectedSystemOrthogonalToTheKernel) {
  const Problem p = two_boxes();
  // 70 columns: two blocks. Random columns have kernel components, which P removes.
  const Eigen::MatrixXd B = random_block(p.K.rows(), 70, 1);
  const Eigen::MatrixXd Psi = solve_in_range(p.K, p.mass, p.Z, B);
  const Eigen::MatrixXd PB = project_to_range(p.Z, B).topRows(p.K.rows() - 3);
  const Eigen::MatrixXd residual = (p.K * Psi).topRows(p.K.rows() - 3) - PB;
  EXPECT_LT(residual.norm(), 1e-10 * PB.norm());
  EXPECT_LT((p.Z.transpose() * dof_masses(p.mass).asDiagonal() * Psi).cwiseAbs().maxCoeff(),
            1e-10 * Psi.cwiseAbs().maxCoeff());
  // The unreferenced vertex stays still.
  EXPECT_EQ(Psi.bottomRows(3).cwiseAbs().maxCoeff(), 0.0);
}

TEST(SolveInRange, ReportsProgressPerBlock) {
  const Problem p = two_boxes();
  std::vector<double> fractions;
  Progress progress(
      [&](const std::string& stage, double fraction) {
        EXPECT_EQ(stage, "derivative solves");
        fractions.push_back(fraction);
        return true;
      },
      0.0);
  solve_in_range(p.K, p.mass, p.Z, random_block(p.K.rows(), 130, 5), &progress);
  // Three blocks of equal width (at most 64): 44 + 44 + 42.
  EXPECT_EQ(fractions, (std::vector<double>{0.0, 44.0 / 130, 88.0 / 130, 1.0}));
  Progress cancel([](const std::string&, double) { return false; }, 0.0);
  EXPECT_THROW(solve_in_range(p.K, p.mass, p.Z, random_block(p.K.rows(), 3, 6), &cancel),
               Cancelled);
}

TEST(SolveInRange, RejectsAKernelBasisThatIsWrong) {
  const Problem p = two_boxes();
  const Eigen::MatrixXd B = random_block(p.K.rows(), 2, 7);
  // Not M-orthonormal.
  EXPECT_THROW(solve_in_range(p.K, p.mass, 2 * p.Z, B), InputError);
  // M-orthonormal but not in the kernel.
  const Eigen::MatrixXd sheared = p.Z + 0.01 * random_block(p.Z.rows(), p.Z.cols(), 8);
  const Eigen::MatrixXd m = dof_masses(p.mass).asDiagonal();
  const Eigen::MatrixXd orthonormal =
      sheared * (sheared.transpose() * m * sheared)
                    .llt()
                    .matrixU()
                    .solve(Eigen::MatrixXd::Identity(p.Z.cols(), p.Z.cols()));
  try {
    solve_in_range(p.K, p.mass, orthonormal, B);
    ADD_FAILURE() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not in the kernel"), std::string::npos) << e.what();
  }
  // Only the translations: the rotations stay unpinned and the matrix singular.
  Eigen::MatrixXd translations(p.Z.rows(), 6);
  translations << p.Z.leftCols(3), p.Z.middleCols(6, 3);
  EXPECT_THROW(solve_in_range(p.K, p.mass, translations, B), NumericalError);
  EXPECT_THROW(solve_in_range(p.K, p.mass, p.Z, B.topRows(6)), InputError);
}

}  // namespace
}  // namespace modal_deform
