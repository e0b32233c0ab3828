// The prolongation of a multiresolution bake: from a proxy mesh, on which the modes
// and derivatives are computed, to every vertex of the dense fine mesh.
//
// Each fine vertex i is tied to the proxy triangle nearest to it (among those around the proxy
// vertex it collapsed onto) by the barycentric weights w_i of its closest point there. A proxy
// displacement field d (3p) reaches the fine mesh as
//
//   x_i = x̄_i + Σ_k w_ik d_{v_ik}                    (k = 0, 1, 2)
//
// so the fine detail, x̄_i minus its closest point on the proxy, stays fixed in the rest frame
// and rides along with the interpolated displacement. The fine basis is thus P U_proxy, stored
// as the proxy basis plus P: 24 bytes per fine vertex instead of 12 r. Turning the detail with its
// triangle's frame gains nothing measurable (docs/design.md, "Prolongation").
#pragma once

#include "util/types.h"

namespace modal_deform {

using RowMatrixX3f = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;

struct Prolongation {
  RowMatrixX3i vertices;  // #V by 3 proxy vertices of each fine vertex's triangle
  // #V by 3 barycentric weights, each in [0, 1], summing to 1; all 0 for a vertex held at rest
  // (outside a region bake's region).
  RowMatrixX3f weights;

  bool empty() const { return vertices.rows() == 0; }
  Eigen::Index size() const { return vertices.rows(); }
};

// The prolongation from the proxy (proxy_V #P by 3, proxy_F #PF by 3) to the fine vertices
// (V #V by 3); `cluster` (#V, in [0, #P)) is the proxy vertex each fine vertex collapsed onto.
// A fine vertex whose proxy vertex has no triangle takes that vertex alone (weights 1, 0, 0).
// Runs in parallel over the fine vertices; throws InputError for a cluster index out of range.
Prolongation prolongation_to_proxy(const VerticesRef& V, const VerticesRef& proxy_V,
                                   const FacesRef& proxy_F,
                                   const Eigen::Ref<const Eigen::VectorXi>& cluster);

// #V rows that hold every fine vertex at rest (zero weights on proxy vertex 0).
Prolongation held_at_rest(Eigen::Index num_vertices);

// out_i = x̄_i + Σ_k w_ik d_{v_ik} for every fine vertex: `rest` (3#V, x̄; null: the displacement
// Σ_k w_ik d_{v_ik} alone), `proxy_displacement` (3#P, d) and `out` (3#V), interleaved, in single
// precision. In parallel over blocks of fine vertices.
void prolongate_positions(const Prolongation& prolongation, const float* rest,
                          const float* proxy_displacement, float* out);

}  // namespace modal_deform
