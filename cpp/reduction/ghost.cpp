#include "reduction/ghost.h"

#include <cmath>
#include <vector>

#include "mesh/edge_collapse.h"
#include "util/bake_stages.h"
#include "util/errors.h"

namespace modal_deform {

Ghost ghost_mesh(const VerticesRef& V, const FacesRef& F, const VectorRef& mass, int target,
                 Progress* progress, const std::vector<char>& sides) {
  EdgeCollapse collapse = collapse_edges(V, F, mass, target, progress, sides);
  Ghost ghost;
  ghost.F = std::move(collapse.F);
  ghost.map = std::move(collapse.cluster);
  // Vertices without a face join the nearest cluster. Unreferenced ones have no mass; those whose
  // faces cancelled (double sheets) have a little, and move the centroid by their share of it.
  for (Eigen::Index i = 0; i < ghost.map.size(); ++i)
    if (ghost.map[i] < 0)
      (collapse.V.rowwise() - V.row(i)).rowwise().squaredNorm().minCoeff(&ghost.map[i]);
  const int num_ghost = static_cast<int>(collapse.V.rows());
  const Eigen::MatrixXd positions = restrict_to_ghost(ghost.map, num_ghost, mass, flatten(V));
  ghost.V = Eigen::Map<const RowMatrixX3d>(positions.data(), num_ghost, 3);
  if (progress) progress->report(stages::kGhost, 1.0);
  return ghost;
}

int nearest_fine_vertex(const Ghost& ghost, const VerticesRef& fine_V, int g) {
  if (g < 0 || g >= ghost.V.rows())
    throw InputError(message("g: ghost vertex ", g, " is outside [0, ", ghost.V.rows(), ")"));
  if (fine_V.rows() != ghost.map.size())
    throw InputError(message("fine_V: expected ", ghost.map.size(),
                             " vertices (one per entry of the map), got ", fine_V.rows()));
  int nearest = -1;
  double least = 0;
  for (Eigen::Index i = 0; i < ghost.map.size(); ++i) {
    if (ghost.map[i] != g) continue;
    const double distance = (fine_V.row(i) - ghost.V.row(g)).squaredNorm();
    if (nearest < 0 || distance < least) {
      nearest = static_cast<int>(i);
      least = distance;
    }
  }
  if (nearest < 0) throw InputError(message("map: no fine vertex maps to ghost vertex ", g));
  return nearest;
}

namespace {

// The weight of each fine vertex in the mean over its ghost vertex's preimage: its share of the
// preimage's mass, or 1 / its size when the preimage has no mass. m/m is exactly 1, so a
// preimage of one vertex restricts to that vertex's values unchanged.
Eigen::VectorXd mean_weights(const Eigen::Ref<const Eigen::VectorXi>& map, int num_ghost,
                             const VectorRef& fine_mass) {
  const Eigen::Index n = map.size();
  if (num_ghost < 1)
    throw InputError(message("num_ghost: expected at least 1 ghost vertex, got ", num_ghost));
  if (fine_mass.size() != n)
    throw InputError(
        message("mass: expected ", n, " values (one per fine vertex), got ", fine_mass.size()));
  std::vector<double> cluster_mass(num_ghost, 0.0);
  std::vector<int> cluster_size(num_ghost, 0);
  for (Eigen::Index i = 0; i < n; ++i) {
    if (map[i] < 0 || map[i] >= num_ghost)
      throw InputError(
          message("map[", i, "]: ghost vertex ", map[i], " is outside [0, ", num_ghost, ")"));
    if (!std::isfinite(fine_mass[i]) || fine_mass[i] < 0)
      throw InputError(message("mass[", i, "]: expected a finite value >= 0, got ", fine_mass[i]));
    cluster_mass[map[i]] += fine_mass[i];
    ++cluster_size[map[i]];
  }
  for (int s = 0; s < num_ghost; ++s)
    if (cluster_size[s] == 0)
      throw InputError(message("map: no fine vertex maps to ghost vertex ", s));
  Eigen::VectorXd weight(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const int s = map[i];
    weight[i] = cluster_mass[s] > 0 ? fine_mass[i] / cluster_mass[s] : 1.0 / cluster_size[s];
  }
  return weight;
}

}  // namespace

Eigen::MatrixXd restrict_to_ghost(const Eigen::Ref<const Eigen::VectorXi>& map, int num_ghost,
                                  const VectorRef& fine_mass,
                                  const Eigen::Ref<const Eigen::MatrixXd>& U) {
  const Eigen::Index n = map.size();
  if (U.rows() != 3 * n)
    throw InputError(message("U: expected ", 3 * n, " rows (3 per fine vertex), got ", U.rows()));
  const Eigen::VectorXd weight = mean_weights(map, num_ghost, fine_mass);
  Eigen::MatrixXd restricted = Eigen::MatrixXd::Zero(3 * num_ghost, U.cols());
#pragma omp parallel for schedule(static)
  for (Eigen::Index j = 0; j < U.cols(); ++j) {
    const double* in = U.col(j).data();
    double* out = restricted.col(j).data();
    for (Eigen::Index i = 0; i < n; ++i) {
      const double w = weight[i];
      double* target = out + 3 * map[i];
      target[0] += w * in[3 * i];
      target[1] += w * in[3 * i + 1];
      target[2] += w * in[3 * i + 2];
    }
  }
  // Weights in [0, 1] summing to 1 keep finite input finite: read all of U again only to name
  // the culprit.
  if (!restricted.allFinite())
    for (Eigen::Index j = 0; j < U.cols(); ++j)
      for (Eigen::Index i = 0; i < U.rows(); ++i)
        if (!std::isfinite(U(i, j)))
          throw InputError(message("U[", i, ", ", j, "]: not a finite number"));
  return restricted;
}

StiffnessPaint restrict_to_ghost(const Eigen::Ref<const Eigen::VectorXi>& map, int num_ghost,
                                 const VectorRef& fine_mass, const StiffnessPaint& paint) {
  StiffnessPaint coarse{Eigen::VectorXd(), paint.max_stiffness};
  if (paint.weights.size() == 0) return coarse;
  if (paint.weights.size() != map.size())
    throw InputError(message("stiffness_weights: expected ", map.size(),
                             " values (one per fine vertex), got ", paint.weights.size()));
  const Eigen::VectorXd weight = mean_weights(map, num_ghost, fine_mass);
  coarse.weights = Eigen::VectorXd::Zero(num_ghost);
  for (Eigen::Index i = 0; i < map.size(); ++i)
    coarse.weights[map[i]] += weight[i] * paint.weights[i];
  // Means of weights in [0, 1], but for rounding.
  coarse.weights = coarse.weights.cwiseMax(0.0).cwiseMin(1.0);
  return coarse;
}

}  // namespace modal_deform
