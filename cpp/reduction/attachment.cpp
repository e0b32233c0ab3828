#include "reduction/attachment.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>

#include "mesh/mass.h"
#include "mesh/mesh_check.h"
#include "mesh/union_find.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

// The region a group follows reaches this many times the group's radius (or its distance to the
// nearest simulated vertex, when larger) from its centre, and holds at least kMinNeighbours
// simulated vertices.
constexpr double kRegionReach = 1.5;
constexpr int kMinNeighbours = 16;
// A region thinner (its least principal extent) than this fraction of its largest extent is flat:
// the normal column of its affine fit is ill-determined, so it grows (header).
constexpr double kMinThickness = 0.1;
// A region whose second principal extent is this small relative to its largest lies on a line: it
// grows.
constexpr double kCollinear = 1e-6;

// Vertices that follow one region: an attached piece, or a single attached vertex.
struct Group {
  std::vector<int> vertices;
};

// The simulated vertices in a uniform grid of about two a cell, for the regions' queries: a scan
// has hundreds of attached groups, and a pass over every simulated vertex for each is slow
// (docs/measurements.md, "Choices in the core").
class VertexGrid {
 public:
  explicit VertexGrid(const RowMatrixX3d& P) : P_(P) {
    low_ = P.colwise().minCoeff().transpose().array();
    const double extent = (P.colwise().maxCoeff().transpose().array() - low_).maxCoeff();
    cells_ = std::max(1, static_cast<int>(std::cbrt(0.5 * static_cast<double>(P.rows()))));
    size_ = extent > 0 ? extent / cells_ : 1.0;
    sorted_.resize(static_cast<size_t>(P.rows()));
    for (int s = 0; s < static_cast<int>(P.rows()); ++s)
      sorted_[static_cast<size_t>(s)] = {key(cell(P.row(s).transpose().array())), s};
    std::sort(sorted_.begin(), sorted_.end());
  }

  // The vertices within r of c, ascending.
  std::vector<int> within(const Eigen::RowVector3d& c, double r) const {
    const Eigen::Array3i from = cell(c.transpose().array() - r),
                         to = cell(c.transpose().array() + r);
    std::vector<int> found;
    for (int i = from[0]; i <= to[0]; ++i)
      for (int j = from[1]; j <= to[1]; ++j)
        for (int k = from[2]; k <= to[2]; ++k) {
          const long here = key({i, j, k});
          const auto first =
              std::lower_bound(sorted_.begin(), sorted_.end(), std::pair<long, int>{here, -1});
          for (auto it = first; it != sorted_.end() && it->first == here; ++it)
            if ((P_.row(it->second) - c).norm() <= r) found.push_back(it->second);
        }
    std::sort(found.begin(), found.end());
    return found;
  }

 private:
  Eigen::Array3i cell(const Eigen::Array3d& p) const {
    return ((p - low_) / size_).floor().cast<int>().max(0).min(cells_ - 1);
  }
  long key(const Eigen::Array3i& c) const {
    return (static_cast<long>(c[0]) * cells_ + c[1]) * cells_ + c[2];
  }

  const RowMatrixX3d& P_;
  Eigen::Array3d low_;
  int cells_;
  double size_;
  std::vector<std::pair<long, int>> sorted_;  // (cell key, vertex), ascending
};

// The region `group` follows and the least-squares affine fit to it (header). P: #S by 3
// simulated positions, mass: their vertex masses (the fit's weights, so that it averages over the
// surface rather than over its sampling).
Attachment::Follower follow(const VerticesRef& V, const RowMatrixX3d& P, const VertexGrid& grid,
                            const Eigen::VectorXd& mass, const Group& group) {
  const auto S = static_cast<int>(P.rows());
  Attachment::Follower follower;
  follower.vertices = group.vertices;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (int v : group.vertices) centre += V.row(v).transpose();
  centre /= static_cast<double>(group.vertices.size());
  double radius = 0;
  for (int v : group.vertices) radius = std::max(radius, (V.row(v).transpose() - centre).norm());

  // The nearest simulated vertices: those within a radius doubled until it holds kMinNeighbours.
  const int k = std::min(kMinNeighbours, S) - 1;
  double r = std::max(radius, 1e-12 * (P.colwise().maxCoeff() - P.colwise().minCoeff()).norm());
  std::vector<int> near = grid.within(centre.transpose(), r);
  while (static_cast<int>(near.size()) <= k) near = grid.within(centre.transpose(), r *= 2);
  std::vector<double> sorted(near.size());
  for (size_t i = 0; i < near.size(); ++i) sorted[i] = (P.row(near[i]) - centre.transpose()).norm();
  const double nearest = *std::min_element(sorted.begin(), sorted.end());
  std::nth_element(sorted.begin(), sorted.begin() + k, sorted.end());
  double reach = std::max(kRegionReach * std::max(radius, nearest), sorted[static_cast<size_t>(k)]);

  // The region: its principal axes (ascending extent) from the mass-weighted covariance.
  // Its weights w and its vertices relative to their weighted mean, kept for the fit below.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> axes;
  Eigen::RowVector3d mean;
  Eigen::VectorXd w;
  RowMatrixX3d centred;
  bool flat = false;
  for (;;) {
    follower.anchors = grid.within(centre.transpose(), reach);
    w = mass(follower.anchors);
    const RowMatrixX3d A = P(follower.anchors, Eigen::all);
    mean = (w.transpose() * A) / w.sum();
    centred = A.rowwise() - mean;
    axes.compute(centred.transpose() * w.asDiagonal() * centred / w.sum());
    const bool collinear = axes.eigenvalues()[1] <= kCollinear * kCollinear * axes.eigenvalues()[2];
    flat = axes.eigenvalues()[0] < kMinThickness * kMinThickness * axes.eigenvalues()[2];
    const bool everything = static_cast<int>(follower.anchors.size()) == S;
    if (collinear && everything)
      throw NumericalError(message("attachment: the simulated vertices around attached vertex ",
                                   group.vertices[0],
                                   " are collinear; no affine motion can be fitted to them"));
    if (!collinear && (!flat || everything)) break;
    reach *= 2;
  }

  // About the region's mean (in the plane of a flat region, so that t is the displacement there):
  // weighted least squares u_k ≈ t + A y_k (y_k = anchor k − mean) over the fitted directions
  // (all three, or the plane's two): [t; A e] = Σ_k G⁻¹ w_k [1; y_k·e] u_k. So t = Σ alpha_k u_k
  // and A = Σ_k u_k beta_kᵀ on those directions; on a flat region A n = −Σ_i e_i (n·A e_i), the
  // skew completion (what a linearised rotation of the plane does to its normal).
  const Eigen::MatrixXd directions =
      flat ? Eigen::MatrixXd(axes.eigenvectors().rightCols(2)) : Eigen::MatrixXd::Identity(3, 3);
  follower.normal = flat ? Eigen::Vector3d(axes.eigenvectors().col(0)) : Eigen::Vector3d::Zero();
  const auto K = static_cast<Eigen::Index>(follower.anchors.size());
  Eigen::MatrixXd design(1 + directions.cols(), K);  // column k: [1; y_k·e]
  design.row(0).setOnes();
  design.bottomRows(directions.cols()) = directions.transpose() * centred.transpose();
  const Eigen::MatrixXd gram = design * w.asDiagonal() * design.transpose();
  const Eigen::MatrixXd solved =
      gram.ldlt().solve(design * w.asDiagonal());  // column k: G⁻¹ w_k [1; y_k·e]
  follower.offsets.resize(static_cast<Eigen::Index>(group.vertices.size()), 3);
  for (size_t i = 0; i < group.vertices.size(); ++i)
    follower.offsets.row(static_cast<Eigen::Index>(i)) = V.row(group.vertices[i]) - mean;
  follower.alpha = solved.row(0).transpose();
  follower.beta = (directions * solved.bottomRows(directions.cols())).transpose();
  return follower;
}

// Joins the `sound` faces that share an edge into pieces (face indices in `pieces`).
void join_across_edges(const FacesRef& F, const std::vector<char>& sound, UnionFind& pieces) {
  std::vector<std::array<int, 3>> edges;  // both ends ascending, then the face
  for (int f = 0; f < static_cast<int>(F.rows()); ++f)
    if (sound[static_cast<size_t>(f)])
      for (int k = 0; k < 3; ++k) {
        const int a = F(f, k), b = F(f, (k + 1) % 3);
        edges.push_back({std::min(a, b), std::max(a, b), f});
      }
  std::sort(edges.begin(), edges.end());
  for (size_t i = 1; i < edges.size(); ++i)
    if (edges[i][0] == edges[i - 1][0] && edges[i][1] == edges[i - 1][1])
      pieces.unite(edges[i][2], edges[i - 1][2]);
}

}  // namespace

Attachment attach(const VerticesRef& V, const FacesRef& F) {
  validate_mesh(V, F);
  const auto n = static_cast<int>(V.rows());
  const auto m = static_cast<int>(F.rows());
  const Eigen::VectorXd area = face_areas(V, F);

  // Pieces: the sound faces joined across edges, and the area of each (at its root face). A
  // doubled triangle counts once: its two copies fold onto each other at hinges whose angle's sign
  // is undefined, so a fin on such a pair alone would be a zero mode; one copy is a flap welded to
  // the surface, while leaving both out would free the doubled triangles that bridge surface
  // vertices (docs/design.md, "Attachment").
  std::vector<char> sound(static_cast<size_t>(m), 1);
  for (int f : duplicate_faces(F)) sound[static_cast<size_t>(f)] = 0;
  for (int f = 0; f < m; ++f)
    sound[static_cast<size_t>(f)] =
        sound[static_cast<size_t>(f)] && face_shape_ratio(V, F, f) > kMinSimulatedShape;
  UnionFind pieces(m);
  join_across_edges(F, sound, pieces);
  std::vector<double> piece_area(static_cast<size_t>(m), 0.0);
  for (int f = 0; f < m; ++f)
    if (sound[static_cast<size_t>(f)]) piece_area[static_cast<size_t>(pieces.find(f))] += area[f];
  const double largest = *std::max_element(piece_area.begin(), piece_area.end());
  if (!(largest > 0))
    throw InputError(message(
        "F: every face is degenerate or a sliver (twice its area below ", kMinSimulatedShape,
        " of its longest edge squared) or a copy; the mesh has nothing to simulate"));
  const double threshold = kSimulatedAreaFraction * largest;
  std::vector<char> large(static_cast<size_t>(m), 0);  // a sound face of a simulated piece
  for (int f = 0; f < m; ++f)
    large[static_cast<size_t>(f)] = sound[static_cast<size_t>(f)] &&
                                    piece_area[static_cast<size_t>(pieces.find(f))] >= threshold;

  // Vertices: simulated on a large piece's face, the large pieces that share a vertex one
  // component (pinned there: they share rigid motions, and turning about the pin is a zero mode);
  // attached vertices joined by any other face one group, an affine body (a small piece, with the
  // copies and slivers on it).
  UnionFind sets(n);
  std::vector<char> simulated(static_cast<size_t>(n), 0), in_a_face(static_cast<size_t>(n), 0);
  for (int f = 0; f < m; ++f)
    if (large[static_cast<size_t>(f)]) {
      sets.unite(F(f, 0), F(f, 1));
      sets.unite(F(f, 0), F(f, 2));
      for (int k = 0; k < 3; ++k) simulated[static_cast<size_t>(F(f, k))] = 1;
    }
  for (int f = 0; f < m; ++f) {
    if (large[static_cast<size_t>(f)]) continue;
    int first = -1;
    for (int k = 0; k < 3; ++k) {
      const int v = F(f, k);
      in_a_face[static_cast<size_t>(v)] = 1;
      if (simulated[static_cast<size_t>(v)]) continue;
      if (first < 0) first = v;
      sets.unite(first, v);
    }
  }

  Attachment result;
  result.submesh_index = Eigen::VectorXi::Constant(n, -1);
  std::vector<int> label_of_root(static_cast<size_t>(n), -1);
  std::vector<int> group_of_root(static_cast<size_t>(n), -1);
  std::vector<Group> groups;
  std::vector<int> labels;
  for (int v = 0; v < n; ++v) {
    if (!simulated[static_cast<size_t>(v)] && !in_a_face[static_cast<size_t>(v)]) {
      groups.push_back({{v}});
      continue;
    }
    const auto root = static_cast<size_t>(sets.find(v));
    if (simulated[static_cast<size_t>(v)]) {
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
  result.component =
      Eigen::Map<const Eigen::VectorXi>(labels.data(), static_cast<Eigen::Index>(labels.size()));

  std::vector<int> faces;
  for (int f = 0; f < m; ++f)
    if (large[static_cast<size_t>(f)])
      for (int k = 0; k < 3; ++k) faces.push_back(result.submesh_index[F(f, k)]);
  result.faces =
      Eigen::Map<const RowMatrixX3i>(faces.data(), static_cast<Eigen::Index>(faces.size() / 3), 3);

  RowMatrixX3d P(static_cast<Eigen::Index>(result.simulated.size()), 3);
  for (size_t s = 0; s < result.simulated.size(); ++s)
    P.row(static_cast<Eigen::Index>(s)) = V.row(result.simulated[s]);
  const Eigen::VectorXd mass = lumped_mass(V, F)(result.simulated);
  const VertexGrid grid(P);
  for (const Group& group : groups) result.followers.push_back(follow(V, P, grid, mass, group));
  return result;
}

Eigen::MatrixXd extend_to_attached(const Attachment& attachment,
                                   const Eigen::Ref<const Eigen::MatrixXd>& U) {
  const auto S = static_cast<Eigen::Index>(attachment.simulated.size());
  if (U.rows() != 3 * S)
    throw InputError(
        message("U: expected ", 3 * S, " rows (3 per simulated vertex), got ", U.rows()));
  const Eigen::Index n = attachment.submesh_index.size();
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(3 * n, U.cols());
#pragma omp parallel for schedule(static)
  for (Eigen::Index j = 0; j < U.cols(); ++j) {
    for (Eigen::Index s = 0; s < S; ++s)
      out.col(j).segment<3>(3 * attachment.simulated[static_cast<size_t>(s)]) =
          U.col(j).segment<3>(3 * s);
    for (const Attachment::Follower& follower : attachment.followers) {
      // The fitted affine displacement t + A y of this column (header).
      Eigen::Vector3d t = Eigen::Vector3d::Zero(), turn = Eigen::Vector3d::Zero();
      Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
      for (size_t k = 0; k < follower.anchors.size(); ++k) {
        const Eigen::Vector3d u = U.col(j).segment<3>(3 * follower.anchors[k]);
        const Eigen::Vector3d beta = follower.beta.row(static_cast<Eigen::Index>(k)).transpose();
        t += follower.alpha[static_cast<Eigen::Index>(k)] * u;
        A += u * beta.transpose();
        turn += beta * follower.normal.dot(u);
      }
      A -= turn * follower.normal.transpose();
      for (size_t i = 0; i < follower.vertices.size(); ++i)
        out.col(j).segment<3>(3 * follower.vertices[i]) =
            t + A * follower.offsets.row(static_cast<Eigen::Index>(i)).transpose();
    }
  }
  return out;
}

}  // namespace modal_deform
