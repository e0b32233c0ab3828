#include "mesh/mesh_topology.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

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

void collect_edges(const FacesRef& F, MeshTopology& topology) {
  const int num_faces = static_cast<int>(F.rows());
  std::unordered_map<long long, int> edge_index;
  edge_index.reserve(static_cast<size_t>(num_faces) * 2);
  topology.face_edges.setConstant(num_faces, 3, -1);
  std::vector<int> face_count;
  for (int f = 0; f < num_faces; ++f) {
    if (has_repeated_index(F, f)) continue;
    for (int k = 0; k < 3; ++k) {
      int a = F(f, k), b = F(f, (k + 1) % 3);
      if (a > b) std::swap(a, b);
      const long long key = static_cast<long long>(a) * topology.num_vertices + b;
      auto [it, inserted] = edge_index.emplace(key, static_cast<int>(topology.edges.size()));
      if (inserted) {
        topology.edges.push_back({a, b});
        face_count.push_back(0);
      }
      topology.face_edges(f, k) = it->second;
      ++face_count[it->second];
    }
  }
  const int num_edges = static_cast<int>(topology.edges.size());
  topology.edge_face_offsets.assign(num_edges + 1, 0);
  std::partial_sum(face_count.begin(), face_count.end(), topology.edge_face_offsets.begin() + 1);
  topology.edge_faces.resize(topology.edge_face_offsets.back());
  std::vector<int> fill(topology.edge_face_offsets.begin(), topology.edge_face_offsets.end() - 1);
  for (int f = 0; f < num_faces; ++f)
    for (int k = 0; k < 3; ++k)
      if (topology.face_edges(f, k) >= 0) topology.edge_faces[fill[topology.face_edges(f, k)]++] = f;
}

// Faces around a non-manifold edge, sorted by the angle of their opposite vertex about the edge.
std::vector<int> faces_in_angular_order(const VerticesRef& V, const FacesRef& F, const MeshTopology& topology,
                                        int edge) {
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
  return Hinge{edge, {a, b, opposite_vertex(F, face0, a, b), opposite_vertex(F, face1, a, b)}, {face0, face1}};
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
  std::vector<std::vector<int>> vertex_faces(n);
  for (int f = 0; f < F.rows(); ++f)
    if (topology.face_edges(f, 0) >= 0)
      for (int k = 0; k < 3; ++k) vertex_faces[F(f, k)].push_back(f);
  std::unordered_map<int, int> local;
  for (int v = 0; v < n; ++v) {
    const auto& faces = vertex_faces[v];
    if (faces.size() < 2) continue;
    local.clear();
    for (size_t i = 0; i < faces.size(); ++i) local[faces[i]] = static_cast<int>(i);
    UnionFind fans(static_cast<int>(faces.size()));
    for (size_t i = 0; i < faces.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        const int e = topology.face_edges(faces[i], k);
        const auto [a, b] = topology.edges[e];
        if (a != v && b != v) continue;
        for (int j = topology.edge_face_offsets[e]; j < topology.edge_face_offsets[e + 1]; ++j)
          fans.unite(static_cast<int>(i), local.at(topology.edge_faces[j]));
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
