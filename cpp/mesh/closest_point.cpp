#include "mesh/closest_point.h"

#include <algorithm>

namespace modal_deform {

// Projecting p onto the triangle's plane (normal equations of p − a ≈ s (b − a) + t (c − a))
// answers when the projection falls inside; otherwise the closest point lies on an edge.
Eigen::Vector3d closest_point_barycentric(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d e1 = b - a, e2 = c - a, d = p - a;
  const double g11 = e1.squaredNorm(), g12 = e1.dot(e2), g22 = e2.squaredNorm();
  const double determinant = g11 * g22 - g12 * g12;  // g11 g22 sin²θ
  if (determinant > 1e-14 * g11 * g22) {
    const double s = (g22 * e1.dot(d) - g12 * e2.dot(d)) / determinant;
    const double t = (g11 * e2.dot(d) - g12 * e1.dot(d)) / determinant;
    const double u = 1 - s - t;  // tested itself, so no weight is below 0 by rounding
    if (s >= 0 && t >= 0 && u >= 0) return {u, s, t};
  }
  const Eigen::Vector3d corners[3] = {a, b, c};
  Eigen::Vector3d weights(1, 0, 0);
  double nearest = (p - a).squaredNorm();
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d& x = corners[k];
    const Eigen::Vector3d edge = corners[(k + 1) % 3] - x;
    const double length = edge.squaredNorm();
    const double t = length > 0 ? std::clamp((p - x).dot(edge) / length, 0.0, 1.0) : 0.0;
    const double distance = (x + t * edge - p).squaredNorm();
    if (distance < nearest) {
      nearest = distance;
      weights.setZero();
      weights[k] = 1 - t;
      weights[(k + 1) % 3] = t;
    }
  }
  return weights;
}

}  // namespace modal_deform
