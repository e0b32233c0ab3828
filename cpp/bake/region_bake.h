// The part of a mesh that a bake moves: the whole mesh, or a region bake's submesh (region.h).
//
// A region's submesh is its free vertices, then the clamped ones on the faces around them. The
// pipeline (bake.cpp) takes the part's vertices, faces and masses where it simplifies (the ghost, a
// proxy: all their vertices spent where the mesh moves), and asks the part the region's questions:
// which vertices are simulated and which clamped, and how values on the submesh go back to the
// mesh's vertices (zero, or held at rest, outside it).
#pragma once

#include <vector>

#include "energy/stiffness_paint.h"
#include "reduction/attachment.h"
#include "reduction/ghost.h"
#include "reduction/prolongation.h"
#include "reduction/region.h"
#include "util/types.h"

namespace modal_deform {

class MovingPart {
 public:
  // The mesh (V, F) with its lumped `mass`; `region` its vertex indices that may move (any order;
  // empty: the whole mesh), with region_mesh's errors. V and F must outlive the part.
  MovingPart(const VerticesRef& V, const FacesRef& F, const VectorRef& mass,
             const Eigen::VectorXi& region);
  MovingPart(const MovingPart&) = delete;
  MovingPart& operator=(const MovingPart&) = delete;

  bool is_region() const { return !region_.vertices.empty(); }
  // The vertices that may move: the mesh's, or the region's free ones.
  int num_free() const;
  // Submesh vertex s as a vertex of the mesh.
  int mesh_vertex(int s) const {
    return is_region() ? region_.vertices[static_cast<size_t>(s)] : s;
  }

  // Step 2: which vertices are simulated (the region's free ones, none attached) and which follow
  // them (attach).
  Attachment attachment() const;
  // The mesh's vertices held at rest on the faces the energy sees (ascending; none for the mesh).
  std::vector<int> clamped() const;
  // Per submesh vertex, for a proxy's edge collapse: 1 free, 0 clamped (empty for the mesh), so
  // that the line between them stays.
  std::vector<char> sides() const;
  // The painted stiffness of the mesh's vertices on the submesh's.
  StiffnessPaint paint(const StiffnessPaint& mesh_paint) const;
  // The region of a proxy made of the part by edge collapse (`proxy.map`: proxy vertex of each
  // submesh vertex): the proxy vertices that only free vertices collapsed onto; empty for the mesh
  // and for a region with nothing clamped (a free component: it is the whole proxy).
  Eigen::VectorXi proxy_region(const Ghost& proxy) const;

  // The ghost's vectors restricted from the mesh's rows U (3#V by r) of the part's vertices.
  Eigen::MatrixXd ghost_vectors(const Ghost& ghost, const Eigen::MatrixXd& U) const;
  // Per mesh vertex, the values per submesh vertex; 0 outside the submesh.
  Eigen::VectorXi on_mesh(const Eigen::VectorXi& per_submesh_vertex) const;
  // The prolongation of the mesh's vertices from the rows of the submesh's (its free vertices'
  // rows; every other vertex held at rest).
  Prolongation on_mesh(Prolongation per_submesh_vertex) const;

 private:
  Eigen::Index mesh_vertices_;
  RegionMesh region_;  // empty for the whole mesh
  RowMatrixX3d submesh_V_;
  Eigen::VectorXd mass_;

 public:
  const VerticesRef V;  // the part's vertices (mesh units), faces over them and masses
  const FacesRef F;
  const VectorRef mass;
};

}  // namespace modal_deform
