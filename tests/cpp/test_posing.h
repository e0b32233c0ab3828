// What the solver tests share: rigid transforms, handles picked by position, and a reduced basis
// small enough to build with a dense eigensolver (the ghost is the mesh itself), which can span
// the whole shape space (the bake's Lanczos cannot).
#pragma once

#include <Eigen/Eigenvalues>
#include <functional>
#include <vector>

#include "basis/basis.h"
#include "energy/discrete_shells.h"
#include "mesh/mass.h"
#include "mesh/normalization.h"
#include "mesh/primitives.h"
#include "mesh/triangle_mesh.h"
#include "solve/handle_term.h"

namespace modal_deform::testing {

// The 4 by 4 transform x ↦ R (x − centre) + centre + t, R a rotation by `angle` about `axis`.
inline Eigen::Matrix4d rigid_transform(const Eigen::Vector3d& axis, double angle,
                                       const Eigen::Vector3d& centre, const Eigen::Vector3d& t) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = R;
  T.topRightCorner<3, 1>() = centre + t - R * centre;
  return T;
}

// The vertices of V whose rest position satisfies `inside`.
inline std::vector<int> vertices_where(const RowMatrixX3d& V,
                                       const std::function<bool(const Eigen::Vector3d&)>& inside) {
  std::vector<int> selected;
  for (int v = 0; v < V.rows(); ++v)
    if (inside(V.row(v).transpose())) selected.push_back(v);
  return selected;
}

// A tube of length 3 held at both ends (6 around and 5 along unless told), the far end moved.
struct SmallTube {
  TriangleMesh mesh;
  Handles handles;
  Transforms transforms;
  explicit SmallTube(int around = 6, int along = 5) : mesh(cylinder(around, along, 1.0, 3.0)) {
    handles = {vertices_where(mesh.V, [](const Eigen::Vector3d& x) { return x.z() < 1e-9; }),
               vertices_where(mesh.V, [](const Eigen::Vector3d& x) { return x.z() > 3 - 1e-9; })};
    transforms = {Eigen::Matrix4d::Identity(),
                  rigid_transform({1, 1, 1}, 1.0, {0, 0, 3}, {0.8, 0.2, -0.5})};
  }
};

// A basis of the r lowest vibration modes of the shells energy at rest, from a dense generalised
// eigensolver (r = 3#V spans everything); the ghost is the mesh with the identity map. Modes are
// M-orthonormal in the normalised frame; U holds them in mesh units.
inline Basis dense_modal_basis(const TriangleMesh& mesh, int r) {
  const int n = static_cast<int>(mesh.V.rows());
  const double s = normalizing_scale(mesh.V);
  const RowMatrixX3d scaled = s * mesh.V;
  const DiscreteShells shells(scaled, mesh.F);
  const Eigen::MatrixXd K = Eigen::MatrixXd(shells.hessian(flatten(scaled)));
  const Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
  Eigen::VectorXd dof_mass(3 * n);
  for (int v = 0; v < n; ++v) dof_mass.segment<3>(3 * v).setConstant(s * s * mass[v]);
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eigen(
      K, Eigen::MatrixXd(dof_mass.asDiagonal()));
  Basis basis;
  basis.rest = mesh.V;
  basis.mass = mass;
  const Eigen::MatrixXd U = eigen.eigenvectors().leftCols(r) / s;
  basis.vectors = U.cast<float>();
  basis.num_rigid = 6;
  basis.num_modes = r;
  basis.eigenvalues = eigen.eigenvalues().head(r);
  basis.ghost_vertices = mesh.V;
  basis.ghost_faces = mesh.F;
  basis.ghost_map = Eigen::VectorXi::LinSpaced(n, 0, n - 1);
  basis.ghost_vectors = basis.vectors.cast<double>();  // exactly the fine rows: ghost = mesh
  basis.scale = s;
  return basis;
}

}  // namespace modal_deform::testing
