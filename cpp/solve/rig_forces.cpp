#include "solve/rig_forces.h"

#include <Eigen/LU>
#include <cmath>

#include "util/errors.h"
#include "util/require_positions.h"

namespace modal_deform {

void check_skinning_weights(const SkinningWeights& weights, int num_vertices) {
  if (weights.rows() != num_vertices)
    throw InputError(message("rig: expected skinning weights for ", num_vertices,
                             " vertices (one row each), got ", weights.rows(), " rows"));
  if (weights.cols() < 1) throw InputError("rig: expected at least one bone (column), got none");
  for (int i = 0; i < weights.outerSize(); ++i) {
    double sum = 0;
    for (SkinningWeights::InnerIterator it(weights, i); it; ++it) {
      if (!std::isfinite(it.value()))
        throw InputError(message("rig[", i, ", ", it.col(), "]: not finite"));
      if (it.value() < 0)
        throw InputError(message("rig[", i, ", ", it.col(), "]: negative weight ", it.value(),
                                 " (the Armature modifier takes none)"));
      sum += it.value();
    }
    if (sum == 0)
      throw InputError(message("rig: vertex ", i,
                               " is weighted to no bone (give it a bone, or a column whose matrix "
                               "is the object's world matrix, to leave it unskinned)"));
    if (!(std::abs(sum - 1) <= kWeightSumTolerance))
      throw InputError(message("rig: the weights of vertex ", i, " sum to ", sum,
                               ", expected 1 (normalise each row)"));
  }
}

SkinningWeights skinning_weights_from_rows(int num_vertices, int num_bones,
                                           const Eigen::VectorXi& row_pointers,
                                           const Eigen::VectorXi& columns,
                                           const Eigen::VectorXd& values) {
  if (num_vertices < 0 || num_bones < 1)
    throw InputError(message("rig: expected (vertices, bones) weights with a bone at least, got (",
                             num_vertices, ", ", num_bones, ")"));
  if (row_pointers.size() != num_vertices + 1 || columns.size() != values.size())
    throw InputError(message("rig: expected ", num_vertices + 1,
                             " row pointers and as many column "
                             "indices as values, got ",
                             row_pointers.size(), ", ", columns.size(), " and ", values.size()));
  if (row_pointers[0] != 0 || row_pointers[num_vertices] != values.size())
    throw InputError("rig: the row pointers do not span the values");
  for (int i = 0; i < num_vertices; ++i)
    if (row_pointers[i + 1] < row_pointers[i])
      throw InputError(message("rig: the row pointers decrease at row ", i));
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<size_t>(values.size()));
  for (int i = 0; i < num_vertices; ++i)
    for (int k = row_pointers[i]; k < row_pointers[i + 1]; ++k) {
      if (columns[k] < 0 || columns[k] >= num_bones)
        throw InputError(message("rig: row ", i, " names bone ", columns[k], ", not one of the ",
                                 num_bones, " columns"));
      entries.emplace_back(i, columns[k], values[k]);
    }
  SkinningWeights weights(num_vertices, num_bones);
  weights.setFromTriplets(entries.begin(), entries.end());
  weights.makeCompressed();
  check_skinning_weights(weights, num_vertices);
  return weights;
}

void check_bone_matrices(const Transforms& bones, int num_bones) {
  if (static_cast<int>(bones.size()) != num_bones)
    throw InputError(message("bones: expected ", num_bones,
                             " matrices (one per bone, a column of rig each), got ", bones.size()));
  for (int b = 0; b < num_bones; ++b) {
    const Eigen::Matrix4d& B = bones[b];
    if (!B.allFinite()) throw InputError(message("bones[", b, "]: has non-finite entries"));
    if (!(B.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).isZero(1e-9))
      throw InputError(message("bones[", b, "]: not affine (last row should be 0 0 0 1)"));
    // Beyond the coordinates the core takes, the rig's acceleration (a second difference times
    // fps²) and the determinant below would overflow.
    if (!(B.topRows<3>().cwiseAbs().maxCoeff() <= kMaxCoordinate))
      throw InputError(message("bones[", b, "]: an entry is beyond ", kMaxCoordinate,
                               " in magnitude (the core takes coordinates up to it)"));
    const Eigen::Matrix3d L = B.topLeftCorner<3, 3>();
    const double norm = L.norm();
    if (!(std::abs(L.determinant()) > kSingularBone * norm * norm * norm))
      throw InputError(message("bones[", b,
                               "]: singular (a bone scaled to zero along some axis has no frame to "
                               "pull the motion back into)"));
  }
}

RigForces::RigForces(const Basis& basis, const SkinningWeights& weights) {
  check_skinning_weights(weights, basis.num_vertices());
  const double s2 = basis.scale * basis.scale;
  scale4_ = s2 * s2;
  const Eigen::Index r = basis.dimension();
  const Eigen::Index b = weights.cols();
  projections_ = Eigen::MatrixXd::Zero(r, 12 * b);
  work_.resize(12 * b);
  for (int i = 0; i < basis.num_vertices(); ++i) {
    if (weights.outerIndexPtr()[i] == weights.outerIndexPtr()[i + 1]) continue;
    const Eigen::Matrix<double, 3, Eigen::Dynamic> rows = basis.vertex_rows(i);
    const Eigen::Vector4d point(basis.rest(i, 0), basis.rest(i, 1), basis.rest(i, 2), 1);
    for (SkinningWeights::InnerIterator it(weights, i); it; ++it) {
      const double w = it.value() * basis.mass[i];
      if (w == 0) continue;
      for (int j = 0; j < 3; ++j)
        for (int l = 0; l < 4; ++l)
          projections_.col(12 * it.col() + 4 * j + l) += (w * point[l]) * rows.row(j).transpose();
    }
  }
}

void RigForces::acceleration(const Transforms& previous, const Transforms& current,
                             const Transforms& next, double dt, Eigen::VectorXd& g) const {
  const int b = num_bones();
  check_bone_matrices(previous, b);
  check_bone_matrices(current, b);
  check_bone_matrices(next, b);
  const double frequency2 = 1 / (dt * dt);
  for (int bone = 0; bone < b; ++bone) {
    const Eigen::Matrix<double, 3, 4> second_difference =
        ((next[bone] - 2 * current[bone] + previous[bone]).topRows<3>() * frequency2).eval();
    const Eigen::Matrix<double, 3, 4> felt =
        current[bone].topLeftCorner<3, 3>().partialPivLu().solve(second_difference);
    // A bone scaled to almost nothing (1e-100, which the relative singularity check lets pass)
    // pulls its motion back enormously: refused where a frame's worth of it leaves the coordinates
    // the core takes, before it overflows the force.
    if (!(felt.cwiseAbs().maxCoeff() * dt * dt <= kMaxCoordinate))
      throw InputError(message("bones[", bone,
                               "]: its motion pulled back into its frame is beyond ",
                               kMaxCoordinate, " a frame (a bone scaled to almost nothing)"));
    for (int j = 0; j < 3; ++j)
      for (int l = 0; l < 4; ++l) work_[12 * bone + 4 * j + l] = felt(j, l);
  }
  g.noalias() = projections_ * work_;
  g *= -scale4_;
}

}  // namespace modal_deform
