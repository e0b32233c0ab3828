#include "bake/region_bake.h"

#include <algorithm>

namespace modal_deform {
namespace {

// A region's attachment: its free vertices are simulated, and nothing is attached.
Attachment region_attachment(const RegionMesh& region, Eigen::Index num_vertices) {
  Attachment attachment;
  attachment.simulated.assign(region.vertices.begin(), region.vertices.begin() + region.num_free);
  attachment.submesh_index = Eigen::VectorXi::Constant(num_vertices, -1);
  for (int s = 0; s < region.num_free; ++s)
    attachment.submesh_index[region.vertices[static_cast<size_t>(s)]] = s;
  attachment.faces = region.faces;
  attachment.component = Eigen::VectorXi::Zero(region.num_free);
  return attachment;
}

}  // namespace

MovingPart::MovingPart(const VerticesRef& mesh_V, const FacesRef& mesh_F,
                       const VectorRef& mesh_mass, const Eigen::VectorXi& region)
    : mesh_vertices_(mesh_V.rows()),
      region_(region.size() > 0 ? region_mesh(mesh_F, mesh_mass, region) : RegionMesh()),
      submesh_V_(mesh_V(region_.vertices, Eigen::all)),
      mass_(is_region() ? Eigen::VectorXd(mesh_mass(region_.vertices))
                        : Eigen::VectorXd(mesh_mass)),
      V(is_region() ? VerticesRef(submesh_V_) : mesh_V),
      F(is_region() ? FacesRef(region_.faces) : mesh_F),
      mass(mass_) {}

int MovingPart::num_free() const {
  return is_region() ? region_.num_free : static_cast<int>(V.rows());
}

Attachment MovingPart::attachment() const {
  return is_region() ? region_attachment(region_, mesh_vertices_) : attach(V, F);
}

std::vector<int> MovingPart::clamped() const {
  return std::vector<int>(region_.vertices.begin() + region_.num_free, region_.vertices.end());
}

std::vector<char> MovingPart::sides() const {
  std::vector<char> sides;
  if (is_region()) {
    sides.assign(region_.vertices.size(), 0);
    std::fill_n(sides.begin(), region_.num_free, 1);
  }
  return sides;
}

StiffnessPaint MovingPart::paint(const StiffnessPaint& mesh_paint) const {
  StiffnessPaint on_part{Eigen::VectorXd(), mesh_paint.max_stiffness};
  if (mesh_paint.weights.size() == 0) return on_part;
  if (is_region())
    on_part.weights = mesh_paint.weights(region_.vertices);
  else
    on_part.weights = mesh_paint.weights;
  return on_part;
}

Eigen::VectorXi MovingPart::proxy_region(const Ghost& proxy) const {
  if (region_.num_free == static_cast<int>(region_.vertices.size())) return Eigen::VectorXi();
  std::vector<char> free(static_cast<size_t>(proxy.V.rows()), 0);
  for (Eigen::Index s = 0; s < region_.num_free; ++s) free[proxy.map[s]] = 1;
  for (Eigen::Index s = region_.num_free; s < proxy.map.size(); ++s) free[proxy.map[s]] = 0;
  std::vector<int> vertices;
  for (size_t p = 0; p < free.size(); ++p)
    if (free[p]) vertices.push_back(static_cast<int>(p));
  return Eigen::Map<const Eigen::VectorXi>(vertices.data(),
                                           static_cast<Eigen::Index>(vertices.size()));
}

Eigen::MatrixXd MovingPart::ghost_vectors(const Ghost& ghost, const Eigen::MatrixXd& U) const {
  if (!is_region()) return restrict_to_ghost(ghost, mass, U);
  const std::vector<int>& sub = region_.vertices;
  Eigen::MatrixXd rows(3 * static_cast<Eigen::Index>(sub.size()), U.cols());
  for (size_t i = 0; i < sub.size(); ++i)
    rows.middleRows<3>(3 * static_cast<Eigen::Index>(i)) =
        U.middleRows<3>(3 * static_cast<Eigen::Index>(sub[i]));
  return restrict_to_ghost(ghost, mass, rows);
}

Eigen::VectorXi MovingPart::on_mesh(const Eigen::VectorXi& per_submesh_vertex) const {
  if (!is_region()) return per_submesh_vertex;
  Eigen::VectorXi on = Eigen::VectorXi::Zero(mesh_vertices_);
  on(region_.vertices) = per_submesh_vertex;
  return on;
}

Prolongation MovingPart::on_mesh(Prolongation per_submesh_vertex) const {
  if (!is_region()) return per_submesh_vertex;
  Prolongation on = held_at_rest(mesh_vertices_);
  for (int s = 0; s < region_.num_free; ++s) {
    const int v = region_.vertices[static_cast<size_t>(s)];
    on.vertices.row(v) = per_submesh_vertex.vertices.row(s);
    on.weights.row(v) = per_submesh_vertex.weights.row(s);
  }
  return on;
}

}  // namespace modal_deform
