// The reduced shape space a bake produces and the solver consumes; stored with the asset.
//
// Everything is in the mesh's own units: the fine positions are x = x̄ + U q, or, for a dense mesh
// baked on a proxy, x = x̄ + P U q with U the proxy's basis (prolongation.h). The energy is
// evaluated in the paper's normalised frame (longest bounding-box edge 10), reached by
// multiplying positions by `scale`; eigenvalues are those of that frame.
#pragma once

#include <map>
#include <string>

#include "energy/material.h"
#include "reduction/prolongation.h"
#include "util/types.h"

namespace modal_deform {

struct Basis {
  // Fine mesh: #V by 3 rest positions and #V lumped masses (mesh units).
  RowMatrixX3d rest;
  Eigen::VectorXd mass;
  // 3n by r, x = x̄ + U q (3p by r over the proxy's vertices when `prolongation` is not empty).
  // Columns: rigid motions, vibration modes, then modal derivatives;
  // M-orthonormal in the normalised frame over the simulated vertices (the bake's attached
  // vertices, bake.h, ride along without mass). float32 rows: mapping q to the mesh is memory
  // bound.
  RowMatrixXf vectors;
  int num_rigid = 0;  // leading columns that are rigid motions
  int num_modes = 0;  // leading columns that are vibration modes (rigid ones included)
  // Modes after the rigid ones with eigenvalue numerically zero (mechanisms of a floppy mesh):
  // columns num_rigid .. num_rigid + num_floppy − 1. They have no modal derivatives.
  int num_floppy = 0;
  Eigen::VectorXd eigenvalues;  // num_modes, ascending (normalised frame)
  // Empty, or for a basis baked on a proxy the map from the proxy's vertices to the fine ones.
  Prolongation prolongation;
  // Ghost: #G by 3 rest positions, #H by 3 triangles, #V fine vertex -> ghost vertex (a region
  // bake's: its submesh's; every vertex outside maps to 0), and
  // 3g by r restricted basis (mass-weighted means over each ghost vertex's preimage).
  RowMatrixX3d ghost_vertices;
  RowMatrixX3i ghost_faces;
  Eigen::VectorXi ghost_map;
  Eigen::MatrixXd ghost_vectors;
  // #G: the painted stiffness of the ghost (mass-weighted means of the fine weights over each
  // ghost vertex's preimage, restrict_to_ghost), empty when stiffness_weights is.
  Eigen::VectorXd ghost_stiffness_weights;
  // The scale of the normalised frame and the material the basis was baked with (a basis stored
  // before stiffness was painted has none: max_stiffness 1).
  double scale = 1.0;
  Material material = {1.0, 1.0, StiffnessPaint{}};
  // A region bake's region (region.h): its fine vertices, ascending; empty for the whole mesh.
  // The rows of vectors of every other vertex are zero.
  Eigen::VectorXi region;
  // Derivative vectors dropped by the orthonormalisation as numerically dependent.
  int num_dropped = 0;
  // Seconds spent in each stage of the bake, by stage name.
  std::map<std::string, double> timings;

  int num_vertices() const { return static_cast<int>(rest.rows()); }
  int dimension() const { return static_cast<int>(vectors.cols()); }
  // Vertices the rows of `vectors` belong to: the proxy's, or the fine mesh's own.
  int num_basis_vertices() const { return static_cast<int>(vectors.rows() / 3); }
  bool on_proxy() const { return !prolongation.empty(); }
  // The 3 by r rows of the fine basis at fine vertex v (in double): P U's rows on a proxy.
  Eigen::Matrix<double, 3, Eigen::Dynamic> vertex_rows(int v) const;
};

// The stored fields of a Basis, in storage order: the one table the bindings (keyword
// constructor, read-only views) and the Python storage (modal_deform.core.bake: dtypes, shapes,
// format versions) follow. Calls visit(name, since, field) with `since` the storage format version
// that introduced the field (a basis stored before it has the field's default) and `field` an
// accessor b -> b.member, const when b is.
template <typename Visit>
void for_each_stored_field(Visit&& visit) {
  visit("rest", 1, [](auto& b) -> auto& { return b.rest; });
  visit("mass", 1, [](auto& b) -> auto& { return b.mass; });
  visit("vectors", 1, [](auto& b) -> auto& { return b.vectors; });
  visit("num_rigid", 1, [](auto& b) -> auto& { return b.num_rigid; });
  visit("num_modes", 1, [](auto& b) -> auto& { return b.num_modes; });
  visit("num_floppy", 1, [](auto& b) -> auto& { return b.num_floppy; });
  visit("eigenvalues", 1, [](auto& b) -> auto& { return b.eigenvalues; });
  visit("ghost_vertices", 1, [](auto& b) -> auto& { return b.ghost_vertices; });
  visit("ghost_faces", 1, [](auto& b) -> auto& { return b.ghost_faces; });
  visit("ghost_map", 1, [](auto& b) -> auto& { return b.ghost_map; });
  visit("ghost_vectors", 1, [](auto& b) -> auto& { return b.ghost_vectors; });
  visit("scale", 1, [](auto& b) -> auto& { return b.scale; });
  visit("bending", 1, [](auto& b) -> auto& { return b.material.bending; });
  visit("membrane", 1, [](auto& b) -> auto& { return b.material.membrane; });
  visit("num_dropped", 1, [](auto& b) -> auto& { return b.num_dropped; });
  visit("prolongation_vertices", 2, [](auto& b) -> auto& { return b.prolongation.vertices; });
  visit("prolongation_weights", 2, [](auto& b) -> auto& { return b.prolongation.weights; });
  visit("stiffness_weights", 3, [](auto& b) -> auto& { return b.material.paint.weights; });
  visit("max_stiffness", 3, [](auto& b) -> auto& { return b.material.paint.max_stiffness; });
  visit("region", 3, [](auto& b) -> auto& { return b.region; });
  visit("ghost_stiffness_weights", 3, [](auto& b) -> auto& { return b.ghost_stiffness_weights; });
}

// Throws InputError naming the first array that is missing, of the wrong shape, non-finite or
// out of range, or inconsistent with the others. Stored bases are untrusted: a .blend may be
// old, edited or hostile, and nothing may be read out of bounds after this passes. Besides shapes,
// counts and index ranges, what the bake guarantees is checked where it is cheap (O(#V r)):
// coordinates within require_positions's range, scale = normalizing_scale(rest), ghost vertices
// inside the bounding box of rest forming a usable mesh, and ghost vector entries no larger than
// the largest entry of their column of vectors (they are weighted means of them); a prolongation's
// proxy vertices in range and its weights barycentric; the painted stiffness as the bake takes it;
// a region's vertices ascending and in range, not on a proxy, with zero rows outside it.
void validate_basis(const Basis& basis);

// The material of the basis's ghost: the basis's, with the ghost's painted weights.
inline Material ghost_material(const Basis& basis) {
  Material ghost = basis.material;
  ghost.paint.weights = basis.ghost_stiffness_weights;
  return ghost;
}

}  // namespace modal_deform
