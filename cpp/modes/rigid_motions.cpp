#include "modes/rigid_motions.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <vector>

#include "util/errors.h"

namespace modal_deform {
namespace {

// A principal moment of inertia this much smaller than the largest means the vertices lie on a
// line: the rotation about it moves nothing.
constexpr double kCollinearRatio = 1e-12;

Eigen::Matrix3d cross_matrix(const Eigen::Vector3d& r) {
  Eigen::Matrix3d X;
  X << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;
  return X;
}

}  // namespace

Eigen::MatrixXd rigid_motions(const VerticesRef& V,
                              const Eigen::Ref<const Eigen::VectorXi>& component,
                              const VectorRef& mass) {
  const Eigen::Index n = V.rows();
  if (component.size() != n)
    throw InputError(message("labels: expected ", n, " values, got ", component.size()));
  if (mass.size() != n)
    throw InputError(message("mass: expected ", n, " values, got ", mass.size()));
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!V.row(i).allFinite()) throw InputError(message("V[", i, "] is not finite"));
    if (!(std::isfinite(mass[i]) && mass[i] >= 0))
      throw InputError(
          message("mass[", i, "] = ", mass[i], ": expected a finite non-negative mass"));
    if (component[i] < -1)
      throw InputError(message("labels[", i, "] = ", component[i], ": expected -1 or more"));
  }
  const int c = n ? component.maxCoeff() + 1 : 0;

  // Per component: total mass, then centroid, then inertia tensor Σ mᵢ (|rᵢ|² I − rᵢ rᵢᵀ).
  std::vector<double> total(static_cast<size_t>(c), 0.0);
  std::vector<int> size(static_cast<size_t>(c), 0);
  std::vector<Eigen::Vector3d> centroid(static_cast<size_t>(c), Eigen::Vector3d::Zero());
  for (Eigen::Index i = 0; i < n; ++i) {
    if (component[i] < 0) continue;
    const auto k = static_cast<size_t>(component[i]);
    total[k] += mass[i];
    ++size[k];
    centroid[k] += mass[i] * V.row(i).transpose();
  }
  for (size_t k = 0; k < total.size(); ++k) {
    if (size[k] == 0) throw InputError(message("labels: component ", k, " has no vertices"));
    if (!(total[k] > 0))
      throw InputError(message("mass: component ", k, " has no mass; label its vertices -1"));
    centroid[k] /= total[k];
  }
  std::vector<Eigen::Matrix3d> inertia(static_cast<size_t>(c), Eigen::Matrix3d::Zero());
  for (Eigen::Index i = 0; i < n; ++i) {
    if (component[i] < 0) continue;
    const auto k = static_cast<size_t>(component[i]);
    const Eigen::Vector3d r = V.row(i).transpose() - centroid[k];
    inertia[k] += mass[i] * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
  }
  // The rotation about a unit axis a moves vertex i by a × rᵢ, with squared M-norm aᵀ I a; the
  // principal axes make the three rotations M-orthogonal, and the centroid makes them
  // M-orthogonal to the translations.
  std::vector<Eigen::Matrix3d> scaled_axes(static_cast<size_t>(c));
  for (size_t k = 0; k < inertia.size(); ++k) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> principal(inertia[k]);
    const Eigen::Vector3d moments = principal.eigenvalues();
    if (!(moments[0] > kCollinearRatio * moments[2]))
      throw InputError(message("V: the vertices with mass of component ", k, " lie on a line"));
    scaled_axes[k] = principal.eigenvectors() * moments.cwiseSqrt().cwiseInverse().asDiagonal();
  }

  Eigen::MatrixXd Z = Eigen::MatrixXd::Zero(3 * n, kRigidMotions * c);
  for (Eigen::Index i = 0; i < n; ++i) {
    if (component[i] < 0) continue;
    const auto k = static_cast<size_t>(component[i]);
    const Eigen::Vector3d r = V.row(i).transpose() - centroid[k];
    const Eigen::Index column = kRigidMotions * static_cast<Eigen::Index>(k);
    Z.block<3, 3>(3 * i, column) = Eigen::Matrix3d::Identity() / std::sqrt(total[k]);
    // a × r = −[r]× a for each scaled axis a.
    Z.block<3, 3>(3 * i, column + kTranslations) = -cross_matrix(r) * scaled_axes[k];
  }
  return Z;
}

}  // namespace modal_deform
