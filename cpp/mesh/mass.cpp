#include "mesh/mass.h"

namespace modal_deform {

Eigen::VectorXd face_areas(const VerticesRef& V, const FacesRef& F) {
  Eigen::VectorXd areas(F.rows());
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    areas[f] = 0.5 * (b - a).cross(c - a).norm();
  }
  return areas;
}

Eigen::VectorXd lumped_mass(const VerticesRef& V, const FacesRef& F) {
  const Eigen::VectorXd areas = face_areas(V, F);
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(V.rows());
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) mass[F(f, k)] += areas[f] / 3.0;
  return mass;
}

}  // namespace modal_deform
