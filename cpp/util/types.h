// Shared array types of the native core.
//
// Positions cross the API as #V by 3 row-major matrices (the layout of a C-ordered numpy array and
// of Blender's foreach_get("co")), and inside the solvers as flat vectors of length 3n,
// interleaved x0 y0 z0 x1 ..., which is the same memory.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>

namespace modal_deform {

using RowMatrixX3d = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
using RowMatrixX3i = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;
using RowMatrixXf = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

using VerticesRef = Eigen::Ref<const RowMatrixX3d>;
using FacesRef = Eigen::Ref<const RowMatrixX3i>;
using VectorRef = Eigen::Ref<const Eigen::VectorXd>;

// The flat 3n view of a #V by 3 row-major matrix, without a copy.
inline Eigen::Map<const Eigen::VectorXd> flatten(const VerticesRef& V) {
  return Eigen::Map<const Eigen::VectorXd>(V.data(), 3 * V.rows());
}

}  // namespace modal_deform
