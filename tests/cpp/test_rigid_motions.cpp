#include <gtest/gtest.h>

#include "mesh/mass.h"
#include "mesh/mesh_topology.h"
#include "modes/rigid_motions.h"
#include "modes/stiffness_and_mass.h"
#include "stand_in_stiffness.h"
#include "test_support.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

using testing::jittered_bar;
using testing::shared_mesh;
using testing::side_by_side;
using testing::spring_network_hessian;

Eigen::VectorXi labels_of(const TriangleMesh& mesh) {
  const std::vector<int> component = build_topology(mesh.V, mesh.F).vertex_component;
  return Eigen::Map<const Eigen::VectorXi>(component.data(),
                                           static_cast<Eigen::Index>(component.size()));
}

TEST(RigidMotions, SpanTheKernelOfEachComponentMOrthonormally) {
  const TriangleMesh mesh = side_by_side(shared_mesh("bunny.obj.gz"), jittered_bar(2, 2, 3, 0.05),
                                         Eigen::RowVector3d(1, 0, 0));
  const Eigen::VectorXi labels = labels_of(mesh);
  ASSERT_EQ(labels.maxCoeff(), 1);
  const Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
  const Eigen::MatrixXd Z = rigid_motions(mesh.V, labels, mass);
  ASSERT_EQ(Z.rows(), 3 * mesh.V.rows());
  ASSERT_EQ(Z.cols(), 12);
  const Eigen::MatrixXd gram = Z.transpose() * dof_masses(mass).asDiagonal() * Z;
  EXPECT_LT((gram - Eigen::MatrixXd::Identity(12, 12)).cwiseAbs().maxCoeff(), 1e-12);
  const SparseMatrix K = spring_network_hessian(mesh.V, mesh.F);
  for (Eigen::Index k = 0; k < Z.cols(); ++k) {
    EXPECT_LT((K * Z.col(k)).norm(), 1e-12 * K.cwiseAbs().sum() / K.rows() * Z.col(k).norm())
        << "column " << k;
    // Each column moves one component only.
    for (Eigen::Index i = 0; i < mesh.V.rows(); ++i) {
      if (labels[i] != k / 6) {
        EXPECT_EQ(Z.block(3 * i, k, 3, 1).norm(), 0.0) << "vertex " << i << ", column " << k;
      }
    }
  }
}

TEST(RigidMotions, AreTranslationsAndRotationsAboutTheCentroid) {
  const TriangleMesh mesh = jittered_bar(2, 1, 3, 0.1);
  const Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
  const Eigen::MatrixXd Z = rigid_motions(mesh.V, Eigen::VectorXi::Zero(mesh.V.rows()), mass);
  const Eigen::RowVector3d centroid = (mass.transpose() * mesh.V) / mass.sum();
  // Translations: the same displacement at every vertex, along x, y and z.
  for (int a = 0; a < 3; ++a)
    for (Eigen::Index i = 0; i < mesh.V.rows(); ++i)
      EXPECT_NEAR(
          (Z.block(3 * i, a, 3, 1) - Eigen::Vector3d::Unit(a) / std::sqrt(mass.sum())).norm(), 0.0,
          1e-14);
  // The rotation about each coordinate axis through the centroid lies in the span of the last
  // three columns.
  const Eigen::MatrixXd rotations = Z.rightCols(3);
  for (int a = 0; a < 3; ++a) {
    Eigen::VectorXd rotation(Z.rows());
    for (Eigen::Index i = 0; i < mesh.V.rows(); ++i)
      rotation.segment<3>(3 * i) =
          Eigen::Vector3d::Unit(a).cross((mesh.V.row(i) - centroid).transpose());
    const Eigen::VectorXd coefficients = rotations.colPivHouseholderQr().solve(rotation);
    EXPECT_LT((rotations * coefficients - rotation).norm(), 1e-12 * rotation.norm())
        << "axis " << a;
  }
}

TEST(RigidMotions, ExcludedVerticesGetZeroRows) {
  const TriangleMesh mesh = jittered_bar(1, 1, 2, 0.05);
  Eigen::VectorXi labels = Eigen::VectorXi::Zero(mesh.V.rows());
  labels[4] = -1;
  const Eigen::MatrixXd Z = rigid_motions(mesh.V, labels, lumped_mass(mesh.V, mesh.F));
  EXPECT_EQ(Z.middleRows(12, 3).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_GT(Z.middleRows(15, 3).cwiseAbs().maxCoeff(), 0.0);
}

TEST(RigidMotions, RejectsBadLabelsAndDegenerateComponents) {
  const TriangleMesh mesh = jittered_bar(1, 1, 1, 0.05);
  const Eigen::Index n = mesh.V.rows();
  const Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
  Eigen::VectorXi labels = Eigen::VectorXi::Zero(n);
  labels[2] = -2;
  EXPECT_THROW(rigid_motions(mesh.V, labels, mass), InputError);
  labels[2] = 2;  // component 1 has no vertices
  EXPECT_THROW(rigid_motions(mesh.V, labels, mass), InputError);
  EXPECT_THROW(rigid_motions(mesh.V, Eigen::VectorXi::Zero(n - 1), mass), InputError);
  EXPECT_THROW(rigid_motions(mesh.V, Eigen::VectorXi::Zero(n), Eigen::VectorXd::Zero(n)),
               InputError);
  // Only two vertices with mass: no rotation about the line through them.
  Eigen::VectorXd two = Eigen::VectorXd::Zero(n);
  two[0] = two[5] = 1;
  try {
    rigid_motions(mesh.V, Eigen::VectorXi::Zero(n), two);
    ADD_FAILURE() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("line"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace modal_deform
