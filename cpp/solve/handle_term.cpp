#include "solve/handle_term.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <map>

#include "util/errors.h"
#include "util/require_positions.h"
#include "util/require_weight.h"

namespace modal_deform {

Eigen::VectorXd checked_handle_weights(const Handles& handles, const VectorRef& weights,
                                       int num_vertices) {
  const int count = static_cast<int>(handles.size());
  if (count == 0) throw InputError("handles: no handle given; posing needs at least one");
  std::vector<int> seen_in(num_vertices, -1);  // the last handle that listed each vertex
  for (int h = 0; h < count; ++h) {
    if (handles[h].empty()) throw InputError(message("handles[", h, "] is empty"));
    for (size_t k = 0; k < handles[h].size(); ++k) {
      const int v = handles[h][k];
      if (v < 0 || v >= num_vertices)
        throw InputError(
            message("handles[", h, "][", k, "] = ", v, " is outside [0, ", num_vertices, ")"));
      if (seen_in[v] == h) throw InputError(message("handles[", h, "] lists vertex ", v, " twice"));
      seen_in[v] = h;
    }
  }
  if (weights.size() == 0) return Eigen::VectorXd::Ones(count);
  if (weights.size() != count)
    throw InputError(
        message("weights: expected ", count, " values (one per handle), got ", weights.size()));
  for (int h = 0; h < count; ++h)
    if (!(weights[h] >= 0 && weights[h] <= kMaxWeight))
      throw InputError(message("weights[", h, "] = ", weights[h], " is not a finite number in [0, ",
                               kMaxWeight, "]"));
  return weights;
}

void check_transforms(const Transforms& transforms, int num_handles) {
  if (static_cast<int>(transforms.size()) != num_handles)
    throw InputError(message("transforms: expected ", num_handles, " (one per handle), got ",
                             transforms.size()));
  for (int h = 0; h < num_handles; ++h) {
    const Eigen::Matrix4d& T = transforms[h];
    if (!T.allFinite()) throw InputError(message("transforms[", h, "] has non-finite entries"));
    if (T.row(3) != Eigen::RowVector4d(0, 0, 0, 1))
      throw InputError(
          message("transforms[", h, "]: last row is (", T.row(3), "), expected (0 0 0 1)"));
    const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
    const double error = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (error > 1e-5)
      throw InputError(message("transforms[", h,
                               "]: the 3 by 3 block is not a rotation (max |RᵀR - I| = ", error,
                               "; scaling and shear are not rigid)"));
    if (R.determinant() < 0)
      throw InputError(message("transforms[", h, "]: the 3 by 3 block is a reflection"));
    // Targets beyond the coordinates the energies take would make the objective overflow.
    if (!positions_in_range(T.topRightCorner<3, 1>()))
      throw InputError(message("transforms[", h, "]: the translation (", T(0, 3), ", ", T(1, 3),
                               ", ", T(2, 3), ") is beyond ", kMaxCoordinate, " in a coordinate"));
  }
}

Eigen::Matrix4d nearest_rigid(const Eigen::Matrix4d& M, const Eigen::Vector3d& centre) {
  if (!M.allFinite() || !centre.allFinite()) throw InputError("matrix: has non-finite entries");
  const Eigen::Matrix3d A = M.topLeftCorner<3, 3>();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d U = svd.matrixU();
  Eigen::Matrix3d R = U * svd.matrixV().transpose();
  if (R.determinant() < 0) {
    U.col(2) = -U.col(2);
    R = U * svd.matrixV().transpose();
  }
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = R;
  T.topRightCorner<3, 1>() = A * centre + M.topRightCorner<3, 1>() - R * centre;
  return T;
}

HandleTerm::HandleTerm(const VerticesRef& rest, const VectorRef& mass, const Handles& handles,
                       const VectorRef& weights, double coefficient) {
  for (size_t h = 0; h < handles.size(); ++h) {
    std::vector<Member>& members = members_.emplace_back();
    for (int v : handles[h])
      members.push_back({v, coefficient * weights[h] * mass[v], rest.row(v).transpose()});
    std::vector<Eigen::Vector3d>& targets = targets_.emplace_back();
    for (const Member& member : members) targets.push_back(member.rest);
  }
}

void HandleTerm::set_transforms(const Transforms& transforms) {
  for (size_t h = 0; h < members_.size(); ++h) {
    const Eigen::Matrix3d R = transforms[h].topLeftCorner<3, 3>();
    const Eigen::Vector3d t = transforms[h].topRightCorner<3, 1>();
    for (size_t k = 0; k < members_[h].size(); ++k) targets_[h][k] = R * members_[h][k].rest + t;
  }
}

double HandleTerm::add_value_and_gradient(const VectorRef& x,
                                          Eigen::Ref<Eigen::VectorXd> gradient) const {
  double value = 0;
  for (size_t h = 0; h < members_.size(); ++h)
    for (size_t k = 0; k < members_[h].size(); ++k) {
      const Member& member = members_[h][k];
      const Eigen::Vector3d d = x.segment<3>(3 * member.vertex) - targets_[h][k];
      value += member.weight * d.squaredNorm();
      gradient.segment<3>(3 * member.vertex) += 2 * member.weight * d;
    }
  return value;
}

Eigen::VectorXd HandleTerm::hessian_diagonal(int num_vertices) const {
  Eigen::VectorXd diagonal = Eigen::VectorXd::Zero(3 * num_vertices);
  for (const std::vector<Member>& members : members_)
    for (const Member& member : members)
      diagonal.segment<3>(3 * member.vertex).array() += 2 * member.weight;
  return diagonal;
}

ReducedHandleTerm::ReducedHandleTerm(const HandleTerm& term, const VertexRows& rows,
                                     Eigen::Index r) {
  // A = Σ_i ω_i U_iᵀU_i with ω_i = Σ_{h∋i} c w_h m_i: rank updates with the gathered rows √ω_i U_i,
  // a block of vertices at a time (bounded memory for a handle of any size).
  std::map<int, double> omega;
  for (const std::vector<HandleTerm::Member>& members : term.members())
    for (const HandleTerm::Member& member : members) omega[member.vertex] += member.weight;
  std::vector<int> pulled;
  for (const auto& [v, w] : omega)
    if (w > 0) pulled.push_back(v);
  constexpr size_t kBlock = 1024;
  A_ = Eigen::MatrixXd::Zero(r, r);
  Eigen::MatrixXd G(3 * kBlock, r);
  for (size_t begin = 0; begin < pulled.size(); begin += kBlock) {
    const size_t count = std::min(kBlock, pulled.size() - begin);
    for (size_t k = 0; k < count; ++k) {
      const int v = pulled[begin + k];
      G.middleRows<3>(3 * k) = std::sqrt(omega[v]) * rows(v);
    }
    A_.selfadjointView<Eigen::Lower>().rankUpdate(G.topRows(3 * count).transpose());
  }
  A_.triangularView<Eigen::StrictlyUpper>() = A_.transpose();

  for (const std::vector<HandleTerm::Member>& members : term.members()) {
    Handle handle;
    handle.mass = 0;
    handle.centroid.setZero();
    for (const HandleTerm::Member& member : members) {
      handle.mass += member.weight;
      handle.centroid += member.weight * member.rest;
    }
    // Without weight the term is zero and any centre will do.
    handle.centroid =
        handle.mass > 0 ? Eigen::Vector3d(handle.centroid / handle.mass) : members.front().rest;
    handle.second_moment.setZero();
    handle.coefficients = Eigen::MatrixXd::Zero(r, 12);
    for (const HandleTerm::Member& member : members) {
      const Eigen::Vector3d offset = member.rest - handle.centroid;
      handle.second_moment += member.weight * offset * offset.transpose();
      const Eigen::Matrix<double, 3, Eigen::Dynamic> U_i = rows(member.vertex);
      for (int a = 0; a < 3; ++a) {
        const Eigen::VectorXd row = U_i.row(a).transpose();
        for (int c = 0; c < 3; ++c)
          handle.coefficients.col(3 * a + c) += member.weight * offset[c] * row;
        handle.coefficients.col(9 + a) += member.weight * row;
      }
    }
    handles_.push_back(std::move(handle));
  }
  b_ = Eigen::VectorXd::Zero(r);
}

void ReducedHandleTerm::set_transforms(const Transforms& transforms) {
  b_.setZero();
  e_ = 0;
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
    e_ += (D * handle.second_moment * D.transpose()).trace() + handle.mass * e.squaredNorm();
  }
}

double ReducedHandleTerm::value_and_gradient(const VectorRef& q,
                                             Eigen::Ref<Eigen::VectorXd> gradient) const {
  gradient.noalias() = A_ * q;
  const double value = q.dot(gradient) + 2 * b_.dot(q) + e_;
  gradient = 2 * (gradient + b_);
  return value;
}

}  // namespace modal_deform
