#include "mesh/cotangent_weights.h"

#include <algorithm>

#include "mesh/mesh_check.h"

namespace modal_deform {

Eigen::VectorXd cotangent_weights(const VerticesRef& V, const FacesRef& F,
                                  const MeshTopology& topology) {
  Eigen::VectorXd weights = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(topology.edges.size()));
  for (int f = 0; f < F.rows(); ++f) {
    if (is_degenerate_face(V, F, f)) continue;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d corner = V.row(F(f, k));
      const Eigen::Vector3d u = V.row(F(f, (k + 1) % 3)).transpose() - corner;
      const Eigen::Vector3d v = V.row(F(f, (k + 2) % 3)).transpose() - corner;
      const double cotangent = u.dot(v) / u.cross(v).norm();
      // The edge opposite corner k runs from F(f, k + 1) to F(f, k + 2).
      weights[topology.face_edges(f, (k + 1) % 3)] +=
          0.5 * std::clamp(cotangent, -kMaxCotangent, kMaxCotangent);
    }
  }
  return weights;
}

}  // namespace modal_deform
