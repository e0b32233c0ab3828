// Connectivity of a triangle mesh: edges, hinges, boundary and non-manifold edges, components.
//
// The core takes triangles only (the add-on triangulates quads and n-gons). Faces whose three
// indices are not distinct have no edges and no hinges; check_mesh reports them.
#pragma once

#include <array>
#include <vector>

#include "util/types.h"

namespace modal_deform {

// An edge with a face on each side: the flexural element of the shells energy.
// vertices = {v0, v1, v2, v3}: the edge v0 -> v1 as it runs in faces[0], v2 the vertex of
// faces[0] opposite the edge, v3 the vertex of faces[1] opposite the edge.
struct Hinge {
  int edge;
  std::array<int, 4> vertices;
  std::array<int, 2> faces;
};

struct MeshTopology {
  int num_vertices = 0;
  // Unique undirected edges {a, b} with a < b, in order of first appearance.
  std::vector<std::array<int, 2>> edges;
  // Faces around edge e: edge_faces[edge_face_offsets[e] .. edge_face_offsets[e + 1]).
  std::vector<int> edge_face_offsets;
  std::vector<int> edge_faces;
  // face_edges(f, k): the edge from F(f, k) to F(f, (k + 1) % 3); -1 for faces with repeated
  // indices.
  RowMatrixX3i face_edges;
  // Interior edges with their two faces. A non-manifold edge (k > 2 faces) gets one hinge per
  // pair of faces that are neighbours around it at rest (k hinges): the sheets meeting there bend
  // as if welded, so no zero-energy folding appears along such edges.
  std::vector<Hinge> hinges;
  std::vector<int> boundary_edges;     // exactly one face
  std::vector<int> nonmanifold_edges;  // more than two faces
  // Vertices whose faces form more than one fan (joined through the vertex only).
  std::vector<int> nonmanifold_vertices;
  std::vector<int> unreferenced_vertices;
  // Connected components over shared vertices; -1 for unreferenced vertices.
  std::vector<int> vertex_component;
  int num_components = 0;

  int num_edge_faces(int edge) const {
    return edge_face_offsets[edge + 1] - edge_face_offsets[edge];
  }
};

// Builds the topology of the triangle mesh (V, F). V (#V by 3) orders the faces around
// non-manifold edges; F (#F by 3) must index into V (see validate_mesh).
MeshTopology build_topology(const VerticesRef& V, const FacesRef& F);

}  // namespace modal_deform
