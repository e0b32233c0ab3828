// Handles and the handle term of the posing objective (paper section 5, E_C): on the fine mesh
// for the full solve, and restricted to the reduced coordinates for the reduced solver.
//
// A handle is a set of fine vertices that follows a rigid transform T_h of its rest positions,
// with a weight w_h ≥ 0; with c = μs⁴ (mesh units, normalization.h) or μ (normalised positions):
//
//   E_C(x) = c Σ_h w_h Σ_{i∈h} m_i ‖x_i − R_h x̄_i − t_h‖²                    (HandleTerm)
//   E_C(q) = qᵀ A q + 2 bᵀ q + e   on x = x̄ + U q                          (ReducedHandleTerm)
//
// A and per-handle moments about each handle's mass centroid are computed once, so moving handles
// costs O(r) per handle and evaluating the term O(r²), whatever the number of handle vertices.
// A vertex in several handles settles between their targets by their weights. The formulas for
// b and e: docs/design.md, "The handle term".
#pragma once

#include <functional>
#include <vector>

#include "util/option.h"
#include "util/require_weight.h"
#include "util/types.h"

namespace modal_deform {

using Handles = std::vector<std::vector<int>>;    // per handle, its fine vertex indices
using Transforms = std::vector<Eigen::Matrix4d>;  // per handle, a rigid transform (mesh units)

// μ where nothing else says, for posing and dynamics alike: stiff enough that handles land within
// a small fraction of a percent of the model's size (bench/results/accuracy.json), soft enough to
// keep BFGS well conditioned.
constexpr double kDefaultPull = 1000.0;

// The pull μ as every table that takes it declares it (option.h); check_option(kPull, μ) refuses
// a value out of range.
inline constexpr Option kPull{
    "pull",
    "How hard the handles pull their vertices toward their targets (μ of the handle "
    "term): higher follows the controllers more exactly, lower lets the surface hold "
    "them back.",
    above_up_to(0, kMaxWeight)};

// Throws InputError naming the first problem: no handle, an empty handle, an index outside
// [0, num_vertices), an index repeated within a handle, or weights (empty, or one per handle)
// that are negative, not finite or above kMaxWeight (require_weight.h). Returns the weights, all 1
// when `weights` is empty.
Eigen::VectorXd checked_handle_weights(const Handles& handles, const VectorRef& weights,
                                       int num_vertices);

// Throws InputError naming the first transform that is not rigid: not finite, a last row other
// than (0, 0, 0, 1), a rotation block R with max |RᵀR − I| > 1e-5, det R < 0 (a reflection), or
// a translation coordinate beyond kMaxCoordinate; or when there is not one transform per handle.
void check_transforms(const Transforms& transforms, int num_handles);

// The rigid transform closest to M (4 by 4: a controller's, which may be scaled or sheared) that
// takes `centre` where M does: the rotation is the orthogonal polar factor of M's 3 by 3 block
// (U Vᵀ of its SVD, a reflection turned into a rotation), the translation M centre − R centre.
// Throws InputError when M or centre has a non-finite entry.
Eigen::Matrix4d nearest_rigid(const Eigen::Matrix4d& M, const Eigen::Vector3d& centre);

// E_C on the fine mesh: the full solve's handle term, and what ReducedHandleTerm restricts.
class HandleTerm {
 public:
  // One handle vertex: its rest position and its share c w_h m_i of the term.
  struct Member {
    int vertex;
    double weight;
    Eigen::Vector3d rest;
  };

  // rest: #V by 3 and mass: #V; coefficient: c. The handles must pass checked_handle_weights.
  // Transforms start at the identity.
  HandleTerm(const VerticesRef& rest, const VectorRef& mass, const Handles& handles,
             const VectorRef& weights, double coefficient);

  // One transform per handle (check_transforms first), in the units of `rest`.
  void set_transforms(const Transforms& transforms);

  // E_C(x) for positions x (3#V, interleaved), with ∇E_C(x) added to `gradient` (3#V).
  double add_value_and_gradient(const VectorRef& x, Eigen::Ref<Eigen::VectorXd> gradient) const;
  // The diagonal of ∇²E_C (3#V), constant: 2 c Σ_{h∋i} w_h m_i for each coordinate of vertex i.
  Eigen::VectorXd hessian_diagonal(int num_vertices) const;

  const std::vector<std::vector<Member>>& members() const { return members_; }

 private:
  std::vector<std::vector<Member>> members_;           // per handle
  std::vector<std::vector<Eigen::Vector3d>> targets_;  // per handle and member: T_h x̄_i
};

// The 3 by r rows U_v of a basis x = x̄ + U q at fine vertex v (Basis::vertex_rows).
using VertexRows = std::function<Eigen::Matrix<double, 3, Eigen::Dynamic>(int vertex)>;

// E_C restricted to x = x̄ + U q, in O(r²) per evaluation.
class ReducedHandleTerm {
 public:
  // rows: U's rows at the fine term's vertices, asked only for those of the handles; r columns.
  ReducedHandleTerm(const HandleTerm& term, const VertexRows& rows, Eigen::Index r);

  // One transform per handle (check_transforms first).
  void set_transforms(const Transforms& transforms);

  // E_C(q), with ∇E_C(q) = 2 (A q + b) written into `gradient` (r).
  double value_and_gradient(const VectorRef& q, Eigen::Ref<Eigen::VectorXd> gradient) const;
  // ∇²E_C = 2A (r by r), constant.
  Eigen::MatrixXd hessian() const { return 2 * A_; }

  int dimension() const { return static_cast<int>(A_.rows()); }

 private:
  struct Handle {
    Eigen::Vector3d centroid;
    double mass;
    Eigen::Matrix3d second_moment;  // S_h
    Eigen::MatrixXd coefficients;   // r by 12: [C_h T_h]
  };
  std::vector<Handle> handles_;  // coefficient and weights folded in
  Eigen::MatrixXd A_;
  Eigen::VectorXd b_;
  double e_ = 0;
};

}  // namespace modal_deform
