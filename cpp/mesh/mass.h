// Lumped vertex masses.
#pragma once

#include "util/types.h"

namespace modal_deform {

// Area of each triangle of (V, F): #F vector, in units of length squared.
Eigen::VectorXd face_areas(const VerticesRef& V, const FacesRef& F);

// Lumped mass of each vertex: a third of the area of its incident triangles (#V vector, length
// squared). Unreferenced vertices get zero.
Eigen::VectorXd lumped_mass(const VerticesRef& V, const FacesRef& F);

}  // namespace modal_deform
