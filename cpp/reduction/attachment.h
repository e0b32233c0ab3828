// Which vertices the bake simulates, and how the others follow them.
//
// Every connected component adds 6 zero modes, every mechanism more, and real scans come with
// debris: tiny components, unreferenced vertices, vertices whose faces have no area, doubled
// triangles (folded fins), blobs hanging from the surface by one vertex. The bake spends its modes only on
// the simulated vertices; the others are attached and ride along.
//
// The rule. Sound faces are neither degenerate nor slivers (face_shape_ratio above
// kMinSimulatedShape) nor copies (laid again on an earlier face's three vertices: a scan's
// doubled triangles count once). Sound faces sharing an edge form pieces; a piece is simulated
// when its area is at least kSimulatedAreaFraction (10%) of the largest piece's, and so are its
// vertices. Every other vertex
// is attached: unreferenced vertices, vertices on degenerate or sliver faces only, and the
// vertices of smaller pieces (scan debris; Suzanne's eyes, about 7% of her vertices each; a small
// closed blob or flap joined to the surface at one vertex, which would turn about it at no cost).
// Simulated pieces that share a vertex are one component: they share rigid motions, and turning
// about the shared vertex is a zero mode of the bake. The energy, the mass and the eigenproblem
// use only the simulated submesh: the sound faces of the simulated pieces.
//
// How attached vertices follow. Attached vertices joined by faces (a small piece, less any vertex
// it shares with a simulated one) or a single attached vertex
// move as one affine body with the surface around them: their displacement is the affine
// field t + A (p − m) fitted by mass-weighted least squares to the displacements of the simulated
// vertices nearby, m their mean. The region: the simulated vertices within 1.5 times the
// group's radius from its centre, grown until it holds at least 16 vertices and is not flat
// (thinner than a tenth of its extent). Every affine motion of that region, rigid motions
// included, carries over exactly; a region that deforms is followed on average, so an eye stays
// in its socket rather than following four far-apart vertices. A flat region could not tell how
// its normal turns under a large rotation, hence the growing. Only when the whole simulated mesh
// is flat (a sheet) is the fit affine in its plane, the normal turning as the plane does (the
// skew completion of A): every linearised rigid motion, which is what the rigid columns of the
// basis are, is still reproduced exactly. The fit is linear in the displacements, so it applies
// to each basis vector (x = x̄ + U q stays linear).
#pragma once

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
Eigen::MatrixXd extend_to_attached(const Attachment& attachment, const Eigen::Ref<const Eigen::MatrixXd>& U);

}  // namespace modal_deform
