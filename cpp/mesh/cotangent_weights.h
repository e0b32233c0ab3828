// Cotangent weights of the edges of a triangle mesh: the stiffness of piecewise-linear functions
// (the cotangent Laplacian), used by the as-rigid-as-possible energy.
#pragma once

#include "mesh/mesh_topology.h"
#include "util/types.h"

namespace modal_deform {

// Cotangents are clamped to [-kMaxCotangent, kMaxCotangent] (angles closer than about 0.06 degrees
// to 0 or 180): scanned slivers would otherwise give weights without bound and a Hessian whose
// condition number grows with them.
constexpr double kMaxCotangent = 1e3;

// w_e = ½ Σ cot θ over the faces around edge e, θ the angle opposite e in that face: one term on
// a boundary edge, two on an interior edge, k on a non-manifold edge with k faces. Degenerate faces
// (is_degenerate_face: repeated indices or zero area) have no angles and add nothing.
//
// V: #V by 3 rest positions; F: #F by 3 faces; topology: build_topology(V, F).
// Returns the #edges weights in the order of topology.edges, dimensionless; negative where the
// opposite angles sum to more than 180 degrees (non-Delaunay edges).
Eigen::VectorXd cotangent_weights(const VerticesRef& V, const FacesRef& F,
                                  const MeshTopology& topology);

}  // namespace modal_deform
