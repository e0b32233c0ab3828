#include "mesh/mesh_topology.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

#include "mesh/union_find.h"

namespace modal_deform {
namespace {

bool has_repeated_index(const FacesRef& F, int f) {
  return F(f, 0) == F(f, 1) || F(f, 1) == F(f, 2) || F(f, 2) == F(f, 0);
}

// The vertex of face f that is not on edge {a, b}.
int opposite_vertex(const FacesRef& F, int f, int a, int b) {
  for (int k = 0; k < 3; ++k)
    if (F(f, k) != a && F(f, k) != b) return F(f, k);
  return F(f, 0);
}

// True when face f runs along its edge {a, b} from a to b.
bool runs_from(const FacesRef& F, int f, int a, int b) {
  for (int k = 0; k < 3; ++k)
    if (F(f, k) == a && F(f, (k + 1) % 3) == b) return true;
  return false;
}

// The ends of side k of face f (from F(f, k) to F(f, k + 1)), the smaller first.
std::array<int, 2> side_ends(const FacesRef& F, int f, int k) {
  const int a = F(f, k), b = F(f, (k + 1) % 3);
  return {std::min(a, b), std::max(a, b)};
}

// Edges by sorting the faces' sides on their end vertices (cheaper than a hash map of the sides);
// numbered in order of first appearance.
void collect_edges(const FacesRef& F, MeshTopology& topology) {
  const int num_faces = static_cast<int>(F.rows());
  topology.face_edges.setConstant(num_faces, 3, -1);
  // (a · #V + b, 3f + k) for side k of face f from a to b, a < b.
  std::vector<std::pair<long long, int>> sides;
  sides.reserve(3 * static_cast<size_t>(num_faces));
  for (int f = 0; f < num_faces; ++f) {
    if (has_repeated_index(F, f)) continue;
    for (int k = 0; k < 3; ++k) {
      const auto [a, b] = side_ends(F, f, k);
      sides.emplace_back(static_cast<long long>(a) * topology.num_vertices + b, 3 * f + k);
    }
  }
  std::sort(sides.begin(), sides.end());
  // Each run of equal keys is one edge, its sides in ascending 3f + k: the first is where the edge
  // appears first, and the faces come in ascending order, as edge_faces lists them.
  std::vector<size_t> run_begin;
  for (size_t i = 0; i < sides.size(); ++i)
    if (i == 0 || sides[i].first != sides[i - 1].first) run_begin.push_back(i);
  run_begin.push_back(sides.size());
  const size_t runs = run_begin.size() - 1;
  std::vector<int> run_starting_at(3 * static_cast<size_t>(num_faces), -1);  // per side
  for (size_t r = 0; r < runs; ++r)
    run_starting_at[static_cast<size_t>(sides[run_begin[r]].second)] = static_cast<int>(r);
  std::vector<int> edge_of_run(runs);
  for (int side = 0; side < 3 * num_faces; ++side) {
    const int run = run_starting_at[static_cast<size_t>(side)];
    if (run < 0) continue;
    edge_of_run[static_cast<size_t>(run)] = static_cast<int>(topology.edges.size());
    topology.edges.push_back(side_ends(F, side / 3, side % 3));
  }
  topology.edge_face_offsets.assign(runs + 1, 0);
  for (size_t r = 0; r < runs; ++r) {
    const auto faces = static_cast<int>(run_begin[r + 1] - run_begin[r]);
    topology.edge_face_offsets[static_cast<size_t>(edge_of_run[r]) + 1] = faces;
  }
  std::partial_sum(topology.edge_face_offsets.begin(), topology.edge_face_offsets.end(),
                   topology.edge_face_offsets.begin());
  topology.edge_faces.resize(sides.size());
  for (size_t r = 0; r < runs; ++r) {
    const int e = edge_of_run[r];
    for (size_t i = run_begin[r]; i < run_begin[r + 1]; ++i) {
      const int f = sides[i].second / 3;
      topology.face_edges(f, sides[i].second % 3) = e;
      topology.edge_faces[static_cast<size_t>(topology.edge_face_offsets[e]) + (i - run_begin[r])] =
          f;
    }
  }
}

// Faces around a non-manifold edge, sorted by the angle of their opposite vertex about the edge.
std::vector<int> faces_in_angular_order(const VerticesRef& V, const FacesRef& F,
                                        const MeshTopology& topology, int edge) {
  const auto [a, b] = topology.edges[edge];
  const Eigen::Vector3d axis = (V.row(b) - V.row(a)).transpose().normalized();
  std::vector<std::pair<double, int>> by_angle;
  Eigen::Vector3d reference = Eigen::Vector3d::Zero();
  for (int i = topology.edge_face_offsets[edge]; i < topology.edge_face_offsets[edge + 1]; ++i) {
    const int f = topology.edge_faces[i];
    Eigen::Vector3d spoke = (V.row(opposite_vertex(F, f, a, b)) - V.row(a)).transpose();
    spoke -= spoke.dot(axis) * axis;
    if (reference.squaredNorm() == 0) reference = spoke;
    const double angle = std::atan2(reference.cross(spoke).dot(axis), reference.dot(spoke));
    by_angle.emplace_back(std::isfinite(angle) ? angle : 0.0, f);
  }
  std::sort(by_angle.begin(), by_angle.end());
  std::vector<int> faces;
  for (const auto& [angle, f] : by_angle) faces.push_back(f);
  return faces;
}

Hinge make_hinge(const FacesRef& F, const MeshTopology& topology, int edge, int face0, int face1) {
  auto [a, b] = topology.edges[edge];
  if (!runs_from(F, face0, a, b)) std::swap(a, b);
  return Hinge{edge,
               {a, b, opposite_vertex(F, face0, a, b), opposite_vertex(F, face1, a, b)},
               {face0, face1}};
}

void collect_hinges(const VerticesRef& V, const FacesRef& F, MeshTopology& topology) {
  const int num_edges = static_cast<int>(topology.edges.size());
  for (int e = 0; e < num_edges; ++e) {
    const int count = topology.num_edge_faces(e);
    const int* faces = &topology.edge_faces[topology.edge_face_offsets[e]];
    if (count == 1) {
      topology.boundary_edges.push_back(e);
    } else if (count == 2) {
      topology.hinges.push_back(make_hinge(F, topology, e, faces[0], faces[1]));
    } else {
      topology.nonmanifold_edges.push_back(e);
      const std::vector<int> around = faces_in_angular_order(V, F, topology, e);
      for (int i = 0; i < count; ++i)
        topology.hinges.push_back(make_hinge(F, topology, e, around[i], around[(i + 1) % count]));
    }
  }
}

void collect_components(const FacesRef& F, MeshTopology& topology) {
  const int n = topology.num_vertices;
  UnionFind sets(n);
  std::vector<char> referenced(n, 0);
  for (int f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) referenced[F(f, k)] = 1;
    sets.unite(F(f, 0), F(f, 1));
    sets.unite(F(f, 0), F(f, 2));
  }
  std::vector<int> label_of_root(n, -1);
  topology.vertex_component.assign(n, -1);
  for (int v = 0; v < n; ++v) {
    if (!referenced[v]) {
      topology.unreferenced_vertices.push_back(v);
      continue;
    }
    int& label = label_of_root[sets.find(v)];
    if (label < 0) label = topology.num_components++;
    topology.vertex_component[v] = label;
  }
}

// A vertex is non-manifold when its faces, joined through the edges at the vertex, form more
// than one fan.
void collect_nonmanifold_vertices(const FacesRef& F, MeshTopology& topology) {
  const int n = topology.num_vertices;
  // The faces of each vertex, in one array (no per-vertex vectors or hash maps); a vertex has a
  // handful, so a face's place among them is found by scanning.
  std::vector<int> offsets(static_cast<size_t>(n) + 1, 0);
  for (int f = 0; f < F.rows(); ++f)
    if (topology.face_edges(f, 0) >= 0)
      for (int k = 0; k < 3; ++k) ++offsets[static_cast<size_t>(F(f, k)) + 1];
  std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
  std::vector<int> vertex_faces(static_cast<size_t>(offsets.back()));
  std::vector<int> fill(offsets.begin(), offsets.end() - 1);
  for (int f = 0; f < F.rows(); ++f)
    if (topology.face_edges(f, 0) >= 0)
      for (int k = 0; k < 3; ++k) vertex_faces[static_cast<size_t>(fill[F(f, k)]++)] = f;
  for (int v = 0; v < n; ++v) {
    const int* faces = vertex_faces.data() + offsets[v];
    const int count = offsets[v + 1] - offsets[v];
    if (count < 2) continue;
    const auto local = [&](int face) {
      return static_cast<int>(std::find(faces, faces + count, face) - faces);
    };
    UnionFind fans(count);
    for (int i = 0; i < count; ++i) {
      for (int k = 0; k < 3; ++k) {
        const int e = topology.face_edges(faces[i], k);
        const auto [a, b] = topology.edges[e];
        if (a != v && b != v) continue;
        for (int j = topology.edge_face_offsets[e]; j < topology.edge_face_offsets[e + 1]; ++j)
          fans.unite(i, local(topology.edge_faces[j]));
      }
    }
    if (fans.count() > 1) topology.nonmanifold_vertices.push_back(v);
  }
}

}  // namespace

MeshTopology build_topology(const VerticesRef& V, const FacesRef& F) {
  MeshTopology topology;
  topology.num_vertices = static_cast<int>(V.rows());
  collect_edges(F, topology);
  collect_hinges(V, F, topology);
  collect_components(F, topology);
  collect_nonmanifold_vertices(F, topology);
  return topology;
}

}  // namespace modal_deform
