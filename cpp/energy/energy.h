// The interface every deformation energy implements (discrete shells, ARAP).
//
// Positions x are flat vectors of length 3n (x0 y0 z0 x1 ...); the rest state x̄ is fixed when
// the energy is built, and E(x̄) = 0, ∇E(x̄) = 0. The solvers and the bake see only this
// interface.
#pragma once

#include "util/types.h"

namespace modal_deform {

class Energy {
 public:
  virtual ~Energy() = default;

  virtual int num_vertices() const = 0;
  // The rest positions x̄ (3n).
  virtual const Eigen::VectorXd& rest() const = 0;

  // E(x).
  virtual double value(const VectorRef& x) const = 0;
  // E(x), with ∇E(x) written into `gradient` (3n).
  virtual double value_and_gradient(const VectorRef& x,
                                    Eigen::Ref<Eigen::VectorXd> gradient) const = 0;
  // ∇²E(x): symmetric 3n by 3n, both triangles stored.
  virtual SparseMatrix hessian(const VectorRef& x) const = 0;
  // A positive semidefinite stand-in for ∇²E(x), element by element: each element's Hessian
  // projected onto the positive semidefinite matrices (its negative eigenvalues set to zero) or,
  // where the energy says so, a Gauss–Newton block; the same pattern as hessian(x), and equal to
  // it at rest. Far from a minimum, Newton's method descends with it where the exact Hessian would
  // need a large shift. An energy that is not a sum over elements returns hessian(x).
  virtual SparseMatrix projected_hessian(const VectorRef& x) const { return hessian(x); }
  // projected_hessian(x) or hessian(x) written into H; an energy that assembles into a fixed
  // pattern reuses H's storage from an earlier call.
  virtual void hessian_into(const VectorRef& x, bool projected, SparseMatrix& H) const {
    H = projected ? projected_hessian(x) : hessian(x);
  }
  // ∇³E(x)(u, w) (3n): the Hessian's derivative along u, applied to w.
  virtual Eigen::VectorXd third(const VectorRef& x, const VectorRef& u,
                                const VectorRef& w) const = 0;
};

}  // namespace modal_deform
