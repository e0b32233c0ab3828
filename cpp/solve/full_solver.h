// The reference solve: Newton's method on the full mesh for the reduced solver's objective, to
// measure how far the reduced answer is from the true minimiser.
//
// In the normalised frame y = s x (s = normalizing_scale(V)):
//
//   F(y) = E(y) + μ Σ_h w_h Σ_{i∈h} s²m_i ‖y_i − s (R_h x̄_i + t_h)‖²
//
// with E the discrete shells energy (bending, membrane) or ARAP of the rest mesh s V, and m_i the
// lumped masses of (V, F): the reduced solver's objective with U = I and no ghost.
//
// Large motions are taken in load steps, as an animation would: the handles' transforms are
// interpolated from the identity (each handle turning about its centre, the mean of its rest
// vertices, by at most 30° per step, the centre moving by at most a tenth of the bounding-box
// diagonal per step, or by a hundredth of the move when it is longer than 10 diagonals: at most
// 100 steps), and Newton converges at each step before the next. From rest, the first
// Newton step is the linear elastic answer, which for a turned handle stretches the mesh
// without bound; and a handle turned by 180° pulls its vertices straight through its axis.
//
// Each Newton iteration factors ∇²F + τ D with CHOLMOD (the pattern is analysed once): τ = 0
// when that is positive definite, else grown tenfold from 1e-8 of the Hessian's scale until the
// factorisation succeeds (Hessian modification, Nocedal & Wright section 3.4), the next
// iteration starting from a tenth of the last τ. D is the normalised lumped mass per coordinate
// (floored at 1e-6 of its mean, so massless vertices are regularised too). Vertices in no energy
// term and no handle (unreferenced ones) stay at rest. The step is then halved until F decreases
// sufficiently (Armijo, c1 = 1e-4); where that decrease is below the rounding of F, a step that
// reduces ‖∇F‖ is taken.
#pragma once

#include "energy/make_energy.h"
#include "solve/handle_term.h"
#include "util/types.h"

namespace modal_deform {

struct FullSolveResult {
  RowMatrixX3d positions;     // #V by 3, mesh units
  int steps = 0;              // load steps
  int iterations = 0;         // Newton steps, all load steps together
  int factorizations = 0;     // numeric factorisations, failed ones (τ too small) included
  double energy = 0;          // F at the result: deformation energy plus handle term
  double gradient_norm = 0;   // ‖∇F‖ at the result (normalised frame)
  double gradient_scale = 0;  // the larger ‖∇F‖ at rest and at `initial`: the tolerance's unit
  bool converged = false;     // gradient_norm ≤ tolerance · gradient_scale
};

// V: #V by 3 rest positions, F: #F by 3 triangles (validate_mesh); handles and weights as in
// checked_handle_weights; transforms: one rigid 4 by 4 transform per handle (check_transforms);
// stiffness μ > 0; bending, membrane: the shells weights (ignored by ARAP); tolerance in (0, 1):
// the factor by which ‖∇F‖ must drop below the larger of its values at rest and at `initial`
// (at each load step); at most
// max_iterations ≥ 0 Newton steps per load step. Starts at rest, or at `initial` (#V by 3, mesh
// units) when given, in a single load step: the caller takes the steps (an animation passes the
// previous frame's answer). Throws InputError for bad input and NumericalError when no shift
// makes the Hessian factorisable. Runs single-threaded but for CHOLMOD's BLAS and the energy's
// own threads.
FullSolveResult solve_full(const VerticesRef& V, const FacesRef& F, const Handles& handles, const VectorRef& weights,
                           const Transforms& transforms, double stiffness, EnergyKind energy, double bending,
                           double membrane, double tolerance, int max_iterations,
                           const RowMatrixX3d* initial = nullptr);

}  // namespace modal_deform
