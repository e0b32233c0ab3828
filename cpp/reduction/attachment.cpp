#include "reduction/attachment.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "mesh/mass.h"
#include "mesh/mesh_check.h"
#include "mesh/union_find.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

// The neighbourhood of an attached group holds at least this many simulated vertices.
constexpr int kMinNeighbours = 16;
// A fourth anchor less than this fraction of the first edge's length off the plane of the other
// three makes a flat tetrahedron: its weights would amplify noise, so the triangle rule applies.
constexpr double kMinThickness = 0.1;
// A third anchor this close to the line of the first two (relative to their distance) means the
// neighbourhood is collinear: it grows.
constexpr double kCollinear = 1e-6;

// Vertices that follow one set of anchors: an attached component, or a single attached vertex.
struct Group {
  std::vector<int> vertices;
};

// Anchors (submesh indices) and the 3 by 3 weights of each follower of `group`, appended to
// `followers`. P: #S by 3 simulated positions.
void follow(const VerticesRef& V, const RowMatrixX3d& P, const Group& group,
            std::vector<Attachment::Follower>& followers) {
  const auto S = static_cast<int>(P.rows());
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (int v : group.vertices) centre += V.row(v).transpose();
  centre /= static_cast<double>(group.vertices.size());
  double radius = 0;
  for (int v : group.vertices) radius = std::max(radius, (V.row(v).transpose() - centre).norm());

  const Eigen::VectorXd distance = (P.rowwise() - centre.transpose()).rowwise().norm();
  int nearest = 0;
  distance.minCoeff(&nearest);
  std::vector<double> sorted(distance.data(), distance.data() + S);
  const int k = std::min(kMinNeighbours, S) - 1;
  std::nth_element(sorted.begin(), sorted.begin() + k, sorted.end());
  double reach = std::max(2 * (distance[nearest] + radius), sorted[static_cast<size_t>(k)]);

  std::array<int, 4> anchor{nearest, nearest, nearest, nearest};
  double length = 0, height = 0;
  for (;;) {
    std::vector<int> near;
    for (int s = 0; s < S; ++s)
      if (distance[s] <= reach) near.push_back(s);
    const Eigen::Vector3d a1 = P.row(nearest).transpose();
    // The farthest from the first, the farthest from their line, the farthest from their plane.
    length = 0;
    for (int s : near)
      if ((P.row(s).transpose() - a1).norm() > length) length = (P.row(s).transpose() - a1).norm(), anchor[1] = s;
    const Eigen::Vector3d e = (P.row(anchor[1]).transpose() - a1).normalized();
    double off_line = 0;
    for (int s : near) {
      const Eigen::Vector3d d = P.row(s).transpose() - a1;
      const double h = (d - d.dot(e) * e).norm();
      if (h > off_line) off_line = h, anchor[2] = s;
    }
    if (length > 0 && off_line > kCollinear * length) {
      const Eigen::Vector3d normal = e.cross(P.row(anchor[2]).transpose() - a1).normalized();
      height = 0;
      for (int s : near) {
        const double h = std::abs(normal.dot(P.row(s).transpose() - a1));
        if (h > height) height = h, anchor[3] = s;
      }
      break;
    }
    if (static_cast<int>(near.size()) == S)
      throw NumericalError(message("attachment: the simulated vertices around attached vertex ", group.vertices[0],
                                   " are collinear; no tetrahedron or triangle can carry it"));
    reach *= 2;
  }

  const Eigen::Vector3d a1 = P.row(anchor[0]).transpose();
  const Eigen::Vector3d d2 = P.row(anchor[1]).transpose() - a1, d3 = P.row(anchor[2]).transpose() - a1;
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  if (height >= kMinThickness * length) {
    // Affine coordinates in the tetrahedron: p − a1 = β2 d2 + β3 d3 + β4 d4.
    Eigen::Matrix3d edges;
    edges << d2, d3, P.row(anchor[3]).transpose() - a1;
    const Eigen::PartialPivLU<Eigen::Matrix3d> lu(edges);
    for (int v : group.vertices) {
      const Eigen::Vector3d beta = lu.solve(V.row(v).transpose() - a1);
      followers.push_back({v, anchor, {(1 - beta.sum()) * I, beta[0] * I, beta[1] * I, beta[2] * I}});
    }
    return;
  }
  // Flat: p − a1 = a d2 + b d3 + h n. In-plane motion is affine; the normal turns as under the
  // linearised rotation A with A d2 = u2 − u1, A d3 = u3 − u1: for a skew A, (A n)·v = −n·(A v)
  // for every in-plane v, so A n = −d2* nᵀ(u2 − u1) − d3* nᵀ(u3 − u1) with the dual basis
  // d2*, d3* of (d2, d3) in the plane.
  const Eigen::Vector3d normal = d2.cross(d3).normalized();
  Eigen::Matrix<double, 3, 2> D;
  D << d2, d3;
  const Eigen::Matrix2d gram_inverse = (D.transpose() * D).inverse();
  const Eigen::Matrix<double, 3, 2> dual = D * gram_inverse;
  const Eigen::Matrix3d turn2 = dual.col(0) * normal.transpose(), turn3 = dual.col(1) * normal.transpose();
  anchor[3] = anchor[0];
  for (int v : group.vertices) {
    const Eigen::Vector3d p = V.row(v).transpose() - a1;
    const double h = normal.dot(p);
    const Eigen::Vector2d ab = gram_inverse * (D.transpose() * p);
    followers.push_back({v,
                         anchor,
                         {(1 - ab.sum()) * I + h * (turn2 + turn3), ab[0] * I - h * turn2, ab[1] * I - h * turn3,
                          Eigen::Matrix3d::Zero()}});
  }
}

}  // namespace

Attachment attach(const VerticesRef& V, const FacesRef& F) {
  validate_mesh(V, F);
  const auto n = static_cast<int>(V.rows());
  const auto m = static_cast<int>(F.rows());
  const Eigen::VectorXd area = face_areas(V, F);

  // Components over the non-degenerate faces, and the area of each (at its root).
  UnionFind sets(n);
  std::vector<bool> sound(static_cast<size_t>(m)), on_sound_face(static_cast<size_t>(n), false);
  for (int f = 0; f < m; ++f) {
    sound[static_cast<size_t>(f)] = face_shape_ratio(V, F, f) > kMinSimulatedShape;
    if (!sound[static_cast<size_t>(f)]) continue;
    sets.unite(F(f, 0), F(f, 1));
    sets.unite(F(f, 0), F(f, 2));
    for (int k = 0; k < 3; ++k) on_sound_face[static_cast<size_t>(F(f, k))] = true;
  }
  std::vector<double> root_area(static_cast<size_t>(n), 0.0);
  for (int f = 0; f < m; ++f)
    if (sound[static_cast<size_t>(f)]) root_area[static_cast<size_t>(sets.find(F(f, 0)))] += area[f];
  const double largest = *std::max_element(root_area.begin(), root_area.end());
  if (!(largest > 0))
    throw InputError(message("F: every face is degenerate or a sliver (twice its area below ", kMinSimulatedShape,
                             " of its longest edge squared); the mesh has nothing to simulate"));
  const double threshold = kSimulatedAreaFraction * largest;

  Attachment result;
  result.submesh_index = Eigen::VectorXi::Constant(n, -1);
  std::vector<int> label_of_root(static_cast<size_t>(n), -1);
  std::vector<int> group_of_root(static_cast<size_t>(n), -1);
  std::vector<Group> groups;
  std::vector<int> labels;
  for (int v = 0; v < n; ++v) {
    if (!on_sound_face[static_cast<size_t>(v)]) {
      groups.push_back({{v}});
      continue;
    }
    const auto root = static_cast<size_t>(sets.find(v));
    if (root_area[root] >= threshold) {
      if (label_of_root[root] < 0) label_of_root[root] = result.num_components++;
      result.submesh_index[v] = static_cast<int>(result.simulated.size());
      result.simulated.push_back(v);
      labels.push_back(label_of_root[root]);
    } else {
      if (group_of_root[root] < 0) {
        group_of_root[root] = static_cast<int>(groups.size());
        groups.emplace_back();
        ++result.num_attached_components;
      }
      groups[static_cast<size_t>(group_of_root[root])].vertices.push_back(v);
    }
  }
  result.component = Eigen::Map<const Eigen::VectorXi>(labels.data(), static_cast<Eigen::Index>(labels.size()));

  std::vector<int> faces;
  for (int f = 0; f < m; ++f)
    if (sound[static_cast<size_t>(f)] && result.submesh_index[F(f, 0)] >= 0)
      for (int k = 0; k < 3; ++k) faces.push_back(result.submesh_index[F(f, k)]);
  result.faces = Eigen::Map<const RowMatrixX3i>(faces.data(), static_cast<Eigen::Index>(faces.size() / 3), 3);

  RowMatrixX3d P(static_cast<Eigen::Index>(result.simulated.size()), 3);
  for (size_t s = 0; s < result.simulated.size(); ++s) P.row(static_cast<Eigen::Index>(s)) = V.row(result.simulated[s]);
  for (const Group& group : groups) follow(V, P, group, result.followers);
  std::sort(result.followers.begin(), result.followers.end(),
            [](const Attachment::Follower& a, const Attachment::Follower& b) { return a.vertex < b.vertex; });
  return result;
}

Eigen::MatrixXd extend_to_attached(const Attachment& attachment, const Eigen::Ref<const Eigen::MatrixXd>& U) {
  const auto S = static_cast<Eigen::Index>(attachment.simulated.size());
  if (U.rows() != 3 * S)
    throw InputError(message("U: expected ", 3 * S, " rows (3 per simulated vertex), got ", U.rows()));
  const Eigen::Index n = attachment.submesh_index.size();
  Eigen::MatrixXd out(3 * n, U.cols());
#pragma omp parallel for schedule(static)
  for (Eigen::Index j = 0; j < U.cols(); ++j) {
    for (Eigen::Index s = 0; s < S; ++s)
      out.col(j).segment<3>(3 * attachment.simulated[static_cast<size_t>(s)]) = U.col(j).segment<3>(3 * s);
    for (const Attachment::Follower& follower : attachment.followers) {
      Eigen::Vector3d row = Eigen::Vector3d::Zero();
      for (int k = 0; k < 4; ++k)
        row += follower.weights[static_cast<size_t>(k)] *
               U.col(j).segment<3>(3 * follower.anchors[static_cast<size_t>(k)]);
      out.col(j).segment<3>(3 * follower.vertex) = row;
    }
  }
  return out;
}

}  // namespace modal_deform
