// Which vertices the bake simulates, and how the others follow them.
//
// Every connected component adds 6 zero modes, and real scans come with debris: tiny components,
// unreferenced vertices, vertices whose faces have no area. The bake spends its modes only on
// the simulated vertices; the others are attached and ride along.
//
// The rule. Components are taken over the sound faces: neither degenerate nor slivers
// (face_shape_ratio above kMinSimulatedShape). A vertex is simulated when it lies on a sound face
// of a component whose area is at least kSimulatedAreaFraction (10%) of the largest component's
// area. Every other vertex is attached: unreferenced vertices, vertices on degenerate faces or
// slivers only, and all vertices of smaller components (scan debris; Suzanne's eyes, about 7% of
// her vertices each). The energy, the mass and the eigenproblem use only the simulated submesh:
// the sound faces of the simulated components.
//
// How attached vertices follow. An attached vertex moves with the affine motion of a tetrahedron
// of four well-spread simulated vertices near it: its basis rows are Σ_k w_k (rows of anchor k),
// with w its affine (barycentric) coordinates in the tetrahedron, so every affine motion of the
// anchors, rigid motions included, carries over exactly: handles can still move the whole mesh
// rigidly, and the eyes follow the head. All vertices of one attached component share one
// tetrahedron, chosen around the component's centroid among the simulated vertices within about
// twice its radius plus its distance to them, so the component moves as one affine body with the
// part of the mesh beside it. Where those simulated vertices are nearly coplanar (a flat sheet),
// the tetrahedron flattens to a triangle: in-plane motion is interpolated affinely and the offset
// along the normal turns with the triangle as a linearised rotation, so every linearised rigid
// motion (what the rigid columns of the basis are) is still reproduced exactly.
#pragma once

#include <array>
#include <vector>

#include "util/types.h"

namespace modal_deform {

// Components with less area than this fraction of the largest one are attached.
constexpr double kSimulatedAreaFraction = 0.1;
// Faces thinner than this (face_shape_ratio: an angle below about 0.06°) are not simulated. The
// bending stiffness of a sliver's hinges grows as the inverse square of its thinness (the inverse
// cube when the sliver alone carries a vertex); measured on small grids, a sliver of 6e-5 threw
// the eigensolver's shift, and one of 6e-6 made the lowest modes rounding noise (scan debris; the
// shared dragons have one face below 1e-3 in 202k).
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
  // An attached vertex's displacement is Σ_k weights[k] · (displacement of submesh vertex
  // anchors[k]), weights 3 by 3 (a multiple of the identity for a tetrahedron).
  struct Follower {
    int vertex;
    std::array<int, 4> anchors;
    std::array<Eigen::Matrix3d, 4> weights;
  };
  std::vector<Follower> followers;  // one per attached vertex, in vertex order
  int num_attached_components = 0;  // components attached as a whole
};

// The simulated submesh of (V #V by 3, F #F by 3) and how the other vertices follow it (rule
// above). Any length unit: the weights are dimensionless. Throws InputError for a mesh
// validate_mesh refuses or one whose faces are all degenerate (nothing to simulate).
Attachment attach(const VerticesRef& V, const FacesRef& F);

// Fine vectors from submesh vectors: U (3#S by r, interleaved) to 3#V by r, simulated rows
// copied, attached rows blended from their anchors.
Eigen::MatrixXd extend_to_attached(const Attachment& attachment, const Eigen::Ref<const Eigen::MatrixXd>& U);

}  // namespace modal_deform
