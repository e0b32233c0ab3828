#include "solve/reduced_map.h"

#include <limits>

#include "mesh/normalization.h"
#include "reduction/prolongation.h"
#include "util/errors.h"
#include "util/require_positions.h"

namespace modal_deform {

void add_columns(const Eigen::VectorXd& rest, const Eigen::MatrixXd& U, const Eigen::VectorXd& q,
                 Eigen::VectorXd& x) {
  const Eigen::Index r = U.cols(), panels = r - r % 4;
  x = rest;
  for (Eigen::Index j = 0; j < panels; j += 4)
    x += U.col(j) * q[j] + U.col(j + 1) * q[j + 1] + U.col(j + 2) * q[j + 2] +
         U.col(j + 3) * q[j + 3];
  for (Eigen::Index j = panels; j < r; ++j) x += U.col(j) * q[j];
}

GhostEnergy::GhostEnergy(const Basis& basis, EnergyKind energy)
    : energy_(make_energy(energy, basis.scale * basis.ghost_vertices, basis.ghost_faces,
                          ghost_material(basis))),
      rest_(basis.scale * flatten(basis.ghost_vertices)),
      vectors_(basis.scale * basis.ghost_vectors),
      x_(rest_.size()),
      gradient_(rest_.size()) {}

double GhostEnergy::value_and_gradient(const Eigen::VectorXd& q, Eigen::VectorXd& gradient) {
  if (!in_range(q)) return std::numeric_limits<double>::infinity();
  const double value = energy_->value_and_gradient(x_, gradient_);
  gradient.noalias() = vectors_.transpose() * gradient_;
  return value;
}

bool GhostEnergy::in_range(const Eigen::VectorXd& q) {
  add_columns(rest_, vectors_, q, x_);
  return positions_in_range(x_);
}

Eigen::MatrixXd GhostEnergy::rest_hessian() const {
  const SparseMatrix K = energy_->hessian(rest_);
  const Eigen::MatrixXd KU = K * vectors_;
  return vectors_.transpose() * KU;
}

FinePositions::FinePositions(const Basis& basis)
    : basis_(basis),
      rest_(flatten(basis.rest).cast<float>()),
      quantized_vectors_(basis.vectors),
      tolerance_(kTolerance * bounding_box_diagonal(basis.rest)),
      q_(Eigen::VectorXf::Zero(basis.dimension())) {
  if (basis.on_proxy()) proxy_displacement_.resize(basis.vectors.rows());
}

void FinePositions::write(const Eigen::VectorXf& q, const float* rest,
                          Eigen::Ref<Eigen::VectorXf> out) const {
  const Eigen::Index fine_rows = 3 * static_cast<Eigen::Index>(basis_.num_vertices());
  if (out.size() != fine_rows)
    throw InputError(
        message("out: expected ", fine_rows, " values (3 per vertex), got ", out.size()));
  if (!basis_.on_proxy()) {
    quantized_vectors_.map(basis_.vectors, q, rest, tolerance_, out.data());
    return;
  }
  // On a proxy: its displacement U q, then (x̄ +) P (U q) on the fine vertices (convex weights: the
  // displacement's error bound holds there too).
  quantized_vectors_.map(basis_.vectors, q, nullptr, tolerance_, proxy_displacement_.data());
  prolongate_positions(basis_.prolongation, rest, proxy_displacement_.data(), out.data());
}

}  // namespace modal_deform
