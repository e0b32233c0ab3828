// The paper's normalisation: every model is scaled so its longest bounding-box edge is 10 before
// the energy weights apply, so material weights mean the same on a 0.2-unit scan and a
// 2-metre character. The bake and both solvers work in this frame.
#pragma once

#include "util/errors.h"
#include "util/types.h"

namespace modal_deform {

constexpr double kNormalizedExtent = 10.0;

// The longest side of the bounding box of V (#V by 3), in V's units; 0 when V has no rows.
inline double bounding_box_extent(const VerticesRef& V) {
  if (V.rows() == 0) return 0;  // Eigen's reductions read the first entry even of an empty matrix
  return (V.colwise().maxCoeff() - V.colwise().minCoeff()).maxCoeff();
}

// The length of the bounding box's diagonal of V (#V by 3), in V's units; 0 when V has no rows.
inline double bounding_box_diagonal(const VerticesRef& V) {
  if (V.rows() == 0) return 0;
  return (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
}

// The factor that scales V (#V by 3) to a longest bounding-box edge of 10.
inline double normalizing_scale(const VerticesRef& V) {
  const double extent = bounding_box_extent(V);
  if (!(extent > 0)) throw InputError("V: all vertices coincide; the mesh has no extent to scale");
  return kNormalizedExtent / extent;
}

}  // namespace modal_deform
