#include "solve/handle_term.h"

#include <algorithm>
#include <cmath>

#include "util/errors.h"
#include "util/require_positions.h"
#include "util/require_weight.h"

namespace modal_deform {

Eigen::VectorXd checked_handle_weights(const Handles& handles, const VectorRef& weights, int num_vertices) {
  const int count = static_cast<int>(handles.size());
  if (count == 0) throw InputError("handles: no handle given; posing needs at least one");
  std::vector<int> seen_in(num_vertices, -1);  // the last handle that listed each vertex
  for (int h = 0; h < count; ++h) {
    if (handles[h].empty()) throw InputError(message("handles[", h, "] is empty"));
    for (size_t k = 0; k < handles[h].size(); ++k) {
      const int v = handles[h][k];
      if (v < 0 || v >= num_vertices)
        throw InputError(message("handles[", h, "][", k, "] = ", v, " is outside [0, ", num_vertices, ")"));
      if (seen_in[v] == h) throw InputError(message("handles[", h, "] lists vertex ", v, " twice"));
      seen_in[v] = h;
    }
  }
  if (weights.size() == 0) return Eigen::VectorXd::Ones(count);
  if (weights.size() != count)
    throw InputError(message("weights: expected ", count, " values (one per handle), got ", weights.size()));
  for (int h = 0; h < count; ++h)
    if (!(weights[h] >= 0 && weights[h] <= kMaxWeight))
      throw InputError(message("weights[", h, "] = ", weights[h], " is not a finite number in [0, ", kMaxWeight, "]"));
  return weights;
}

void check_transforms(const Transforms& transforms, int num_handles) {
  if (static_cast<int>(transforms.size()) != num_handles)
    throw InputError(message("transforms: expected ", num_handles, " (one per handle), got ", transforms.size()));
  for (int h = 0; h < num_handles; ++h) {
    const Eigen::Matrix4d& T = transforms[h];
    if (!T.allFinite()) throw InputError(message("transforms[", h, "] has non-finite entries"));
    if (T.row(3) != Eigen::RowVector4d(0, 0, 0, 1))
      throw InputError(message("transforms[", h, "]: last row is (", T.row(3), "), expected (0 0 0 1)"));
    const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
    const double error = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (error > 1e-5)
      throw InputError(message("transforms[", h, "]: the 3 by 3 block is not a rotation (max |RᵀR - I| = ", error,
                               "; scaling and shear are not rigid)"));
    if (R.determinant() < 0) throw InputError(message("transforms[", h, "]: the 3 by 3 block is a reflection"));
    // Targets beyond the coordinates the energies take would make the objective overflow.
    if (!positions_in_range(T.topRightCorner<3, 1>()))
      throw InputError(message("transforms[", h, "]: the translation (", T(0, 3), ", ", T(1, 3), ", ", T(2, 3),
                               ") is beyond ", kMaxCoordinate, " in a coordinate"));
  }
}

HandleTerm::HandleTerm(const VerticesRef& rest, const VectorRef& mass, const Eigen::Ref<const RowMatrixXf>& U,
                       const Handles& handles, const VectorRef& weights, double coefficient) {
  const int n = static_cast<int>(rest.rows());
  const Eigen::Index r = U.cols();
  // A = Σ_i ω_i U_iᵀU_i with ω_i = coefficient Σ_{h∋i} w_h m_i: rank updates with the gathered
  // rows √ω_i U_i, a block of vertices at a time (bounded memory for a handle of any size).
  Eigen::VectorXd omega = Eigen::VectorXd::Zero(n);
  for (size_t h = 0; h < handles.size(); ++h)
    for (int v : handles[h]) omega[v] += coefficient * weights[h] * mass[v];
  std::vector<int> members;
  for (int v = 0; v < n; ++v)
    if (omega[v] > 0) members.push_back(v);
  constexpr size_t kBlock = 1024;
  A_ = Eigen::MatrixXd::Zero(r, r);
  Eigen::MatrixXd G(3 * kBlock, r);
  for (size_t begin = 0; begin < members.size(); begin += kBlock) {
    const size_t count = std::min(kBlock, members.size() - begin);
    for (size_t k = 0; k < count; ++k) {
      const int v = members[begin + k];
      G.middleRows<3>(3 * k) = std::sqrt(omega[v]) * U.middleRows<3>(3 * v).cast<double>();
    }
    A_.selfadjointView<Eigen::Lower>().rankUpdate(G.topRows(3 * count).transpose());
  }
  A_.triangularView<Eigen::StrictlyUpper>() = A_.transpose();

  for (size_t h = 0; h < handles.size(); ++h) {
    const double scale = coefficient * weights[h];
    Handle handle;
    handle.mass = 0;
    handle.centroid.setZero();
    for (int v : handles[h]) {
      handle.mass += mass[v];
      handle.centroid += mass[v] * rest.row(v).transpose();
    }
    // Without mass the term is zero and any centre will do.
    handle.centroid =
        handle.mass > 0 ? Eigen::Vector3d(handle.centroid / handle.mass) : Eigen::Vector3d(rest.row(handles[h][0]));
    handle.second_moment.setZero();
    handle.coefficients = Eigen::MatrixXd::Zero(r, 12);
    for (int v : handles[h]) {
      const Eigen::Vector3d offset = rest.row(v).transpose() - handle.centroid;
      handle.second_moment += mass[v] * offset * offset.transpose();
      for (int a = 0; a < 3; ++a) {
        const Eigen::VectorXd row = U.row(3 * v + a).transpose().cast<double>();
        for (int c = 0; c < 3; ++c) handle.coefficients.col(3 * a + c) += mass[v] * offset[c] * row;
        handle.coefficients.col(9 + a) += mass[v] * row;
      }
    }
    handle.mass *= scale;
    handle.second_moment *= scale;
    handle.coefficients *= scale;
    handles_.push_back(std::move(handle));
  }
  b_ = Eigen::VectorXd::Zero(r);
}

void HandleTerm::set_transforms(const Transforms& transforms) {
  b_.setZero();
  c_ = 0;
  Eigen::Matrix<double, 12, 1> parameters;
  for (size_t h = 0; h < handles_.size(); ++h) {
    const Handle& handle = handles_[h];
    const Eigen::Matrix3d D = Eigen::Matrix3d::Identity() - transforms[h].topLeftCorner<3, 3>();
    const Eigen::Vector3d e = D * handle.centroid - transforms[h].topRightCorner<3, 1>();
    // vec(D) row by row, matching the columns 3a + c of C_h.
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c) parameters[3 * a + c] = D(a, c);
    parameters.tail<3>() = e;
    b_.noalias() += handle.coefficients * parameters;
    c_ += (D * handle.second_moment * D.transpose()).trace() + handle.mass * e.squaredNorm();
  }
}

double HandleTerm::value_and_gradient(const VectorRef& q, Eigen::Ref<Eigen::VectorXd> gradient) const {
  gradient.noalias() = A_ * q;
  const double value = q.dot(gradient) + 2 * b_.dot(q) + c_;
  gradient = 2 * (gradient + b_);
  return value;
}

}  // namespace modal_deform
