// The point of a triangle closest to a given point.
#pragma once

#include "util/types.h"

namespace modal_deform {

// Barycentric weights (of a, b, c; non-negative, summing to 1) of the point of triangle abc
// closest to p. A degenerate triangle (a segment or a point) gives the closest point of its edges.
Eigen::Vector3d closest_point_barycentric(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c);

}  // namespace modal_deform
