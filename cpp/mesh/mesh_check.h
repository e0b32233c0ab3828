// Input validation and a report of what is awkward about a mesh.
#pragma once

#include <string>
#include <vector>

#include "mesh/mesh_topology.h"
#include "util/types.h"

namespace modal_deform {

// The smallest extent (longest side of the bounding box) of a usable mesh: the third derivatives
// of the shells energy grow as the inverse cube of its elements' size, which must stay far from
// overflow. A mesh whose vertices coincide has extent 0.
constexpr double kMinExtent = 1e-12;

// Throws InputError, naming the array `name`, when a coordinate of V is not finite or beyond
// kMaxCoordinate (name[i], require_positions) or its extent is below kMinExtent.
void require_vertices(const VerticesRef& V, const char* name);

// Throws InputError naming the first problem that makes (V, F) unusable: no vertices, no faces,
// V failing require_vertices, or an index outside [0, #V) (F[f]).
void validate_mesh(const VerticesRef& V, const FacesRef& F);

// Twice the area below which a face counts as degenerate, relative to its longest edge squared.
constexpr double kDegenerateAreaRatio = 1e-12;

// Twice the area of face f over its longest edge squared: √3/2 for an equilateral triangle, about
// the smallest angle (radians) for a thin one, 0 for repeated indices or coincident vertices.
// Independent of the scale (no underflow for tiny faces).
double face_shape_ratio(const VerticesRef& V, const FacesRef& F, int f);

// True when face f has repeated indices or (numerically) zero area: face_shape_ratio at most
// kDegenerateAreaRatio.
bool is_degenerate_face(const VerticesRef& V, const FacesRef& F, int f);

// The faces laid again on the three vertices of an earlier face, in either orientation (a scan's
// doubled triangles), ascending: every copy but the first.
std::vector<int> duplicate_faces(const FacesRef& F);

// Counts of each awkward feature with the first few offending indices (at most kExamples).
struct MeshReport {
  static constexpr int kExamples = 10;
  struct Finding {
    std::string name;  // e.g. "nonmanifold_edges"
    int count = 0;
    std::vector<int> examples;  // first offending indices (vertices, faces or edges as named)
  };
  int num_vertices = 0, num_faces = 0, num_edges = 0, num_components = 0;
  std::vector<int> component_sizes;   // vertices per component, largest first
  std::vector<int> vertex_component;  // per vertex: its component, -1 when in no face
  std::vector<Finding> findings;      // boundary_edges, nonmanifold_edges, ... in a fixed order
};

// Validates (V, F) and reports its boundary edges, non-manifold edges and vertices, unreferenced
// vertices, degenerate faces and duplicate faces, and its connected components.
MeshReport check_mesh(const VerticesRef& V, const FacesRef& F);

}  // namespace modal_deform
