// A region bake: only the region's vertices move, every other vertex stays exactly where
// it is, and the whole basis is spent inside the region.
//
// The energy is that of the faces around the region (those with a vertex in it or next to it: every
// term that moves, a bending term spanning two faces), with their vertices outside the region
// clamped at rest: a fixed boundary. The eigenproblem (and the modal
// derivatives' systems) are the block of K and M of the free vertices, so the modes have no rigid
// motions, but for a part of the region that touches no clamped vertex (a free component: its
// rigid motions come as zero modes). The basis rows of every vertex outside are zero, so
// x = x̄ + U q leaves it exactly at rest.
#pragma once

#include <vector>

#include "util/types.h"

namespace modal_deform {

struct RegionMesh {
  // Fine indices of the submesh's vertices: the free ones (the region's vertices with mass, on a
  // face), ascending, then the clamped ones (the others on the submesh's faces), ascending.
  std::vector<int> vertices;
  int num_free = 0;
  RowMatrixX3i faces;  // the faces with a vertex free or next to a free one, in submesh indices
};

// The submesh of the region (fine vertex indices, any order) of the mesh (#V vertices, F #F by 3,
// lumped `mass` #V), the region not empty. Throws InputError naming "region" for an index out of
// range or repeated, a region holding every vertex (bake without one), or one with no vertex left
// free (none with mass on a face).
RegionMesh region_mesh(const FacesRef& F, const VectorRef& mass,
                       const Eigen::Ref<const Eigen::VectorXi>& region);

// Throws InputError naming the handle and vertex when a handle vertex lies outside the region
// (`region`: sorted fine indices; empty: the whole mesh).
void require_handles_in_region(const std::vector<std::vector<int>>& handles,
                               const Eigen::VectorXi& region);

}  // namespace modal_deform
