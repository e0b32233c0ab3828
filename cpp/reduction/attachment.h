// Which vertices the bake simulates, and how the others follow them.
//
// Every connected component adds 6 zero modes, every mechanism more, and scans come with debris.
// So sound faces (neither degenerate, slivers nor copies of an earlier face) sharing an edge form
// pieces, and a piece is simulated when its area is at least kSimulatedAreaFraction of the largest
// piece's. Every other vertex is attached (unreferenced vertices, vertices on unsound faces only,
// the vertices of smaller pieces) and takes no part in the energy, the mass or the eigenproblem.
// Attached vertices joined by faces, or a single one, move as one affine body fitted by
// mass-weighted least squares to the simulated vertices around them, a region grown until it is
// not flat: every affine motion, rigid motions included, carries over exactly, and the fit is
// linear in the displacements, so it applies to each basis vector (x = x̄ + U q stays linear).
// The rule, the fit and their reasons: docs/design.md, "Attachment".
#pragma once

#include <vector>

#include "util/types.h"

namespace modal_deform {

// Components with less area than this fraction of the largest one are attached.
constexpr double kSimulatedAreaFraction = 0.1;
// Faces thinner than this (face_shape_ratio: an angle below about 0.06°) are not simulated. The
// bending stiffness of a sliver's hinges grows as the inverse square of its thinness (the inverse
// cube when the sliver alone carries a vertex), and much thinner slivers throw the eigensolver's
// shift or leave the lowest modes to rounding (docs/measurements.md, "Meshes as they come").
constexpr double kMinSimulatedShape = 1e-3;

struct Attachment {
  // Sorted indices of the simulated vertices (#S); submesh vertex s is fine vertex simulated[s].
  std::vector<int> simulated;
  // #V: the submesh index of each fine vertex, -1 for attached vertices.
  Eigen::VectorXi submesh_index;
  // The simulated submesh: its non-degenerate faces (in submesh indices, #SF by 3) and the
  // component of each of its vertices (#S labels in [0, num_components)).
  RowMatrixX3i faces;
  Eigen::VectorXi component;
  int num_components = 0;
  // A group of attached vertices and the region it follows: the displacement of vertex p is
  // Σ_k [(alpha[k] + beta[k]·y) I − (normal·y) beta[k] normalᵀ] u_k, y = p − m, u_k the
  // displacement of submesh vertex anchors[k] (the least-squares affine fit, flat or not).
  struct Follower {
    std::vector<int> vertices;  // fine vertex indices, ascending
    RowMatrixX3d offsets;       // y of each vertex: its rest position minus the region's mean m
    std::vector<int> anchors;   // submesh indices of the region
    Eigen::VectorXd alpha;      // #anchors
    RowMatrixX3d beta;          // #anchors by 3
    Eigen::Vector3d normal;     // the flat region's normal, zero when the region is not flat
  };
  std::vector<Follower> followers;  // one per group, in the order of their first vertex
  // Groups of attached vertices joined by faces (small pieces, less any vertex shared with the
  // simulated surface; a lone vertex on slivers), each following one region.
  int num_attached_components = 0;
};

// The simulated submesh of (V #V by 3, F #F by 3) and how the other vertices follow it (rule
// above). Any length unit (the fit scales with the mesh). Throws InputError for a mesh
// validate_mesh refuses or one whose faces are all degenerate (nothing to simulate).
Attachment attach(const VerticesRef& V, const FacesRef& F);

// Fine vectors from submesh vectors: U (3#S by r, interleaved) to 3#V by r, simulated rows
// copied, attached rows blended from their anchors, the rows of vertices neither simulated nor
// attached (outside a region, region.h) zero.
Eigen::MatrixXd extend_to_attached(const Attachment& attachment,
                                   const Eigen::Ref<const Eigen::MatrixXd>& U);

}  // namespace modal_deform
