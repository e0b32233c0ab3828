// Meshes and checks the bake tests share.
#pragma once

#include <Eigen/QR>

#include "mesh/primitives.h"
#include "mesh/triangle_mesh.h"
#include "test_support.h"

namespace modal_deform::testing {

// A head with two small disjoint eyes in front of it, like Suzanne: a closed box of side 2 and two
// closed boxes of side 0.3 (2% of its area each) just off its +x face.
inline TriangleMesh head_with_eyes() {
  const TriangleMesh head = bar(6, 6, 6, 2.0, 2.0, 2.0);
  const TriangleMesh eye = bar(2, 2, 2, 0.3, 0.3, 0.3);
  return side_by_side(side_by_side(head, eye, Eigen::RowVector3d(2.1, 0.3, 1.2)), eye,
                      Eigen::RowVector3d(2.1, 1.4, 1.2));
}

// The relative misfit of the best linearised rigid motion u_i = ω × x_i + t to the displacements
// u (3k, interleaved) of the points X (k by 3): 0 for a rigid motion.
inline double rigid_misfit(const RowMatrixX3d& X, const Eigen::VectorXd& u) {
  const Eigen::Index k = X.rows();
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(3 * k, 6);
  for (Eigen::Index i = 0; i < k; ++i) {
    const Eigen::Vector3d x = X.row(i);
    Eigen::Matrix3d cross;
    cross << 0, x.z(), -x.y(), -x.z(), 0, x.x(), x.y(), -x.x(), 0;  // ω × x = cross · ω
    A.block<3, 3>(3 * i, 0) = cross;
    A.block<3, 3>(3 * i, 3) = Eigen::Matrix3d::Identity();
  }
  const Eigen::VectorXd fit = A.colPivHouseholderQr().solve(u);
  return (A * fit - u).norm() / u.norm();
}

}  // namespace modal_deform::testing
