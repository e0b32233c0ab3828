// The full solve's objective (full_solver.h) in the normalised frame y = s x:
//
//   F(y) = E(y) + μ Σ_h w_h Σ_{i∈h} s²m_i ‖y_i − s (R_h x̄_i + t_h)‖²,
//
// with the parts of its Hessian that do not change (the handle term's diagonal) and the shape of
// the Newton shift (the lumped mass per coordinate).
#pragma once

#include <memory>

#include "energy/make_energy.h"
#include "solve/handle_term.h"
#include "util/types.h"

namespace modal_deform {

class PoseObjective {
 public:
  // V: #V by 3 rest positions and F: #F by 3 triangles (validated); handles and weights as
  // checked_handle_weights returns them; stiffness μ > 0; energy and material as make_energy takes
  // them.
  // `held` (vertex indices in range) stay where y puts them: their gradient and their Hessian rows
  // are zero.
  PoseObjective(const VerticesRef& V, const FacesRef& F, const Handles& handles,
                const Eigen::VectorXd& weights, double stiffness, EnergyKind energy,
                const Material& material, const std::vector<int>& held = {});

  // The same objective, up to a constant, as a function of the `free` vertices' coordinates (none
  // held) with every other vertex held: only the faces that touch a free vertex or a neighbour of
  // one, which hold every term a free vertex is in (its hinges' and its neighbours' rotations too).
  // In this objective's normalised frame (its scale() is 1) and under its transforms. `vertices`
  // receives the parent's index of each of its vertices, ascending.
  PoseObjective around(const std::vector<int>& free, std::vector<int>& vertices) const;

  double scale() const { return scale_; }
  Eigen::VectorXd rest_positions() const { return flatten(rest_); }
  // The energy's Hessian at y, exact or projected (each element's made semidefinite), with the held
  // coordinates' rows and columns zero, written into H (its storage reused from an earlier call).
  void hessian_into(const Eigen::VectorXd& y, bool projected, SparseMatrix& H) const;
  // D (3#V): the normalised lumped mass per coordinate, the shape of the Hessian's shift, floored
  // at 1e-6 of its mean.
  const Eigen::VectorXd& mass_diagonal() const { return mass_diagonal_; }
  // The handle term's Hessian (diagonal, constant) and the fixed unreferenced coordinates.
  const Eigen::VectorXd& constant_diagonal() const { return constant_diagonal_; }
  // The smallest shift τ used: 2.5e-8 of the median curvature per unit mass (|∇²F_ii| / D_i) at
  // rest.
  double smallest_shift() const { return smallest_shift_; }

  // Whether a triangle turns over between y and y_new: its normal reverses (a triangle with no
  // normal at y, collapsed already, is not counted, nor one degenerate at rest: is_degenerate_face,
  // no orientation and no energy term; a raw scan's zero-area slivers turn over at any step). F has
  // a kink where a triangle collapses (its hinges' angles flip by π as its normal does), and a
  // step through it lands beyond the smooth part of F that Newton's method can converge in, often
  // lower: iterates are kept out of it.
  bool turns_a_triangle_over(const Eigen::VectorXd& y, const Eigen::VectorXd& y_new) const;
  // The smallest α > 0 at which y + αp turns a triangle over, to within rounding: where its normal
  // first stands perpendicular to its normal at y (n(y)·n(y + αp) = 0, quadratic in α); +inf when
  // no triangle turns for any α.
  double step_to_turning(const Eigen::VectorXd& y, const Eigen::VectorXd& p) const;

  // Transforms (one per handle) in mesh units, applied to the handle term in the normalised frame.
  void set_transforms(Transforms transforms);

  // F(y), ∇F(y) written into `gradient`; +inf where y is beyond what the energy takes.
  double operator()(const Eigen::VectorXd& y, Eigen::VectorXd& gradient) const;

  const RowMatrixX3d& rest() const { return rest_; }  // #V by 3, normalised frame
  const RowMatrixX3i& faces() const { return faces_; }
  bool held(int vertex) const { return !held_.empty() && held_[3 * static_cast<size_t>(vertex)]; }

 private:
  // What the objective is made of, kept for around().
  struct Terms {
    Handles handles;
    Eigen::VectorXd weights;
    double stiffness;
    EnergyKind energy;
    Material material;
  };
  // rest: #V by 3 in the normalised frame, scale the factor it was scaled by from mesh units.
  PoseObjective(RowMatrixX3d rest, double scale, const FacesRef& F, Terms terms,
                const std::vector<int>& held);

  Terms terms_;
  Transforms transforms_;  // normalised frame, as the handle term has them
  double scale_;
  RowMatrixX3d rest_;
  std::unique_ptr<Energy> energy_;
  HandleTerm handle_term_;
  Eigen::VectorXd mass_diagonal_, constant_diagonal_;
  double smallest_shift_ = 0;
  RowMatrixX3i faces_;
  RowMatrixX3i oriented_faces_;  // the faces not degenerate at rest: the ones that can turn over
  std::vector<char> held_;       // per coordinate, empty when nothing is held
};

}  // namespace modal_deform
