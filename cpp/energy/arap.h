// The as-rigid-as-possible energy (Sorkine & Alexa 2007, "As-Rigid-As-Possible Surface Modeling"),
// the alternative objective of the solvers (the paper's Fig. 3 poses ARAP in a shells basis).
//
//   E(x) = Σ_i min_{R_i ∈ SO(3)} Σ_{j ∈ N(i)} w_ij ‖(x_i − x_j) − R_i (x̄_i − x̄_j)‖²   (S&A eq. 3,
//   7)
//
// with one cell per vertex (its one-ring of edges) and cotangent weights of the rest mesh,
// w_ij = ½ (cot α_ij + cot β_ij), clamped to w_ij ≥ 0 so that E ≥ 0 with its minimum at rest
// (a negative weight can make a cell's best rotation at rest other than the identity). Units:
// length². Vertices without edges add nothing; their Hessian rows are zero. Why the clamp and
// what it keeps: docs/design.md, "ARAP". Calls on one object are thread-safe: the energy keeps no
// state between calls.
#pragma once

#include <vector>

#include "energy/energy.h"

namespace modal_deform {

class Arap final : public Energy {
 public:
  // V: #V by 3 rest positions (length), F: #F by 3 triangles. Throws InputError for a mesh
  // validate_mesh refuses.
  Arap(const VerticesRef& V, const FacesRef& F);

  int num_vertices() const override { return num_vertices_; }
  const Eigen::VectorXd& rest() const override { return rest_; }

  // x: 3n positions. Throws InputError naming the first non-finite coordinate or a wrong length.
  double value(const VectorRef& x) const override;
  // E(x) and ∇E(x) (3n, length) with each R_i at its optimum.
  double value_and_gradient(const VectorRef& x,
                            Eigen::Ref<Eigen::VectorXd> gradient) const override;
  // The exact Hessian of E with optimal rotations (3n by 3n, dimensionless, both triangles;
  // symmetric up to rounding). Each cell couples its whole one-ring, so the pattern is the 2-ring.
  // Positive semi-definite at rest, with 6 zero eigenvalues per connected component; away from
  // rest it can be indefinite (a Newton solver has to modify it).
  SparseMatrix hessian(const VectorRef& x) const override;
  // ARAP's rotation fit has no third derivative here: throws InputError (modal derivatives need
  // the shells energy).
  Eigen::VectorXd third(const VectorRef& x, const VectorRef& u, const VectorRef& w) const override;

 private:
  // Cell i's covariance S_i = Σ_j w_ij ē_ij e_ijᵀ (S&A eq. 5) at positions x.
  Eigen::Matrix3d covariance(int i, const VectorRef& x) const;
  // Σ_j w_ij ‖e_ij − R ē_ij‖² of cell i.
  double cell_energy(int i, const VectorRef& x, const Eigen::Matrix3d& rotation) const;
  // The factors H_p (3 by 3) of cell i's rotation term in the Hessian, H_pᵀ H_q = f_pω f_ωω⁺ f_ωq,
  // written to out[0] (vertex i) and out[1 ..] (its neighbours in cell order).
  void rotation_factors(int i, const VectorRef& x, Eigen::Matrix3d* out) const;

  int num_vertices_;
  Eigen::VectorXd rest_;
  bool parallel_;
  // Cells: vertex i's neighbours j = cell_neighbors_[e] with weight cell_weights_[e] > 0 for
  // e in [cell_offsets_[i], cell_offsets_[i + 1]); cell_twins_[e] is the edge j -> i.
  std::vector<int> cell_offsets_;
  std::vector<int> cell_neighbors_;
  std::vector<double> cell_weights_;
  std::vector<int> cell_twins_;
  // Hessian pattern: the sorted vertices coupled to vertex k (its 2-ring through the cells) are
  // hessian_rows_[hessian_offsets_[k] .. hessian_offsets_[k + 1]).
  std::vector<int> hessian_offsets_;
  std::vector<int> hessian_rows_;
};

}  // namespace modal_deform
