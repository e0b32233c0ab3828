#include "reduction/region.h"

#include <algorithm>

#include "util/errors.h"

namespace modal_deform {

RegionMesh region_mesh(const FacesRef& F, const VectorRef& mass,
                       const Eigen::Ref<const Eigen::VectorXi>& region) {
  const Eigen::Index n = mass.size();
  // 1: in the region, 2: free (in the region, with mass), 3 and 4: clamped (below).
  std::vector<char> kind(static_cast<size_t>(n), 0);
  for (Eigen::Index i = 0; i < region.size(); ++i) {
    const int v = region[i];
    if (v < 0 || v >= n)
      throw InputError(message("region[", i, "] = ", v, " is not a vertex (0 to ", n - 1, ")"));
    if (kind[v]) throw InputError(message("region[", i, "] = ", v, " is there twice"));
    kind[v] = mass[v] > 0 ? 2 : 1;
  }
  if (region.size() == n)
    throw InputError(
        "region: it holds every vertex, so nothing is clamped; bake without a region instead");
  RegionMesh mesh;
  // The first ring (3): vertices on a face with a free vertex. The faces on them hold every term
  // that moves: a bending term spans the two faces of an edge, and a face with a free vertex
  // shares its edges with faces that may have none.
  // The second ring (4): the other vertices of those faces. Both rings are clamped.
  const auto touches = [&](Eigen::Index f, char low, char high) {
    for (int k = 0; k < 3; ++k)
      if (kind[F(f, k)] >= low && kind[F(f, k)] <= high) return true;
    return false;
  };
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    if (touches(f, 2, 2))
      for (int k = 0; k < 3; ++k)
        if (kind[F(f, k)] != 2) kind[F(f, k)] = 3;
  std::vector<int> faces;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    if (touches(f, 2, 3)) faces.push_back(static_cast<int>(f));
  for (int f : faces)
    for (int k = 0; k < 3; ++k)
      if (kind[F(f, k)] < 2) kind[F(f, k)] = 4;
  std::vector<int> local(static_cast<size_t>(n), -1);
  for (const bool free : {true, false})
    for (int v = 0; v < n; ++v)
      if (free ? kind[v] == 2 : kind[v] >= 3) {
        local[v] = static_cast<int>(mesh.vertices.size());
        mesh.vertices.push_back(v);
        if (free) ++mesh.num_free;
      }
  if (mesh.num_free == 0)
    throw InputError(
        "region: no vertex of it is left free (each lies on no face with area); paint the region "
        "on "
        "the surface");
  mesh.faces.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t i = 0; i < faces.size(); ++i)
    for (int k = 0; k < 3; ++k) mesh.faces(static_cast<Eigen::Index>(i), k) = local[F(faces[i], k)];
  return mesh;
}

void require_handles_in_region(const std::vector<std::vector<int>>& handles,
                               const Eigen::VectorXi& region) {
  if (region.size() == 0) return;
  for (size_t h = 0; h < handles.size(); ++h)
    for (int v : handles[h])
      if (!std::binary_search(region.data(), region.data() + region.size(), v))
        throw InputError(
            message("handles[", h, "]: vertex ", v,
                    " lies outside the basis's region, which alone "
                    "moves; keep handles inside the region, or bake a region that holds them"));
}

}  // namespace modal_deform
