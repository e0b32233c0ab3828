#include "mesh/mesh_check.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>

#include "mesh/normalization.h"
#include "util/errors.h"
#include "util/require_positions.h"

namespace modal_deform {

void require_vertices(const VerticesRef& V, const char* name) {
  require_positions(flatten(V), 3 * V.rows(), name);
  const double extent = bounding_box_extent(V);
  if (!(extent >= kMinExtent))
    throw InputError(message(name, ": the mesh's extent (the longest side of its bounding box) is ",
                             extent, "; the core needs at least ", kMinExtent,
                             ": scale the mesh up"));
}

void validate_mesh(const VerticesRef& V, const FacesRef& F) {
  if (V.rows() == 0) throw InputError("V: the mesh has no vertices");
  if (F.rows() == 0) throw InputError("F: the mesh has no faces");
  require_vertices(V, "V");
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (F(f, k) < 0 || F(f, k) >= V.rows())
        throw InputError(message("F[", f, "]: face ", f, " refers to vertex ", F(f, k),
                                 ", outside [0, ", V.rows(), ")"));
}

double face_shape_ratio(const VerticesRef& V, const FacesRef& F, int f) {
  const int a = F(f, 0), b = F(f, 1), c = F(f, 2);
  if (a == b || b == c || c == a) return 0;
  const Eigen::Vector3d ab = (V.row(b) - V.row(a)).transpose();
  const Eigen::Vector3d bc = (V.row(c) - V.row(b)).transpose();
  const Eigen::Vector3d ca = (V.row(a) - V.row(c)).transpose();
  const double longest = std::max({ab.norm(), bc.norm(), ca.norm()});
  if (!(longest > 0)) return 0;
  return (ab / longest).cross(-ca / longest).norm();
}

bool is_degenerate_face(const VerticesRef& V, const FacesRef& F, int f) {
  return face_shape_ratio(V, F, f) <= kDegenerateAreaRatio;
}

std::vector<int> duplicate_faces(const FacesRef& F) {
  const auto m = static_cast<int>(F.rows());
  std::vector<std::array<int, 4>> keys(static_cast<size_t>(m));  // sorted vertices, then the face
  for (int f = 0; f < m; ++f) {
    keys[static_cast<size_t>(f)] = {F(f, 0), F(f, 1), F(f, 2), f};
    std::sort(keys[static_cast<size_t>(f)].begin(), keys[static_cast<size_t>(f)].begin() + 3);
  }
  std::sort(keys.begin(), keys.end());
  std::vector<int> copies;
  for (size_t i = 1; i < keys.size(); ++i)
    if (std::equal(keys[i].begin(), keys[i].begin() + 3, keys[i - 1].begin()))
      copies.push_back(keys[i][3]);
  std::sort(copies.begin(), copies.end());
  return copies;
}

MeshReport check_mesh(const VerticesRef& V, const FacesRef& F) {
  validate_mesh(V, F);
  const MeshTopology topology = build_topology(V, F);
  MeshReport report;
  report.num_vertices = static_cast<int>(V.rows());
  report.num_faces = static_cast<int>(F.rows());
  report.num_edges = static_cast<int>(topology.edges.size());
  report.num_components = topology.num_components;
  report.vertex_component = topology.vertex_component;
  report.component_sizes.assign(topology.num_components, 0);
  for (int c : topology.vertex_component)
    if (c >= 0) ++report.component_sizes[c];
  std::sort(report.component_sizes.rbegin(), report.component_sizes.rend());

  auto add = [&report](const std::string& name, const std::vector<int>& indices) {
    MeshReport::Finding finding{name, static_cast<int>(indices.size()), {}};
    finding.examples.assign(
        indices.begin(), indices.begin() + std::min<size_t>(indices.size(), MeshReport::kExamples));
    report.findings.push_back(std::move(finding));
  };

  std::vector<int> degenerate;
  for (int f = 0; f < F.rows(); ++f)
    if (is_degenerate_face(V, F, f)) degenerate.push_back(f);
  add("boundary_edges", topology.boundary_edges);
  add("nonmanifold_edges", topology.nonmanifold_edges);
  add("nonmanifold_vertices", topology.nonmanifold_vertices);
  add("unreferenced_vertices", topology.unreferenced_vertices);
  add("degenerate_faces", degenerate);
  add("duplicate_faces", duplicate_faces(F));
  return report;
}

}  // namespace modal_deform
