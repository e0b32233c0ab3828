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
// Each iteration factors ∇²F + τ D with CHOLMOD (the pattern is analysed once): τ = 0 when that
// is positive definite, else grown fourfold from a small multiple of the Hessian's scale until
// the factorisation succeeds (Hessian modification, Nocedal & Wright section 3.4), starting the
// next iteration from a quarter of the last τ. D is the normalised lumped mass per coordinate
// (floored at 1e-6 of its mean, so massless vertices are regularised too). Vertices in no energy
// term and no handle (unreferenced ones) stay at rest. The Newton step is then shortened by
// backtracking until f decreases sufficiently (Armijo, c1 = 1e-4, halving).
#pragma once

#include "energy/make_energy.h"
#include "solve/handle_term.h"
#include "util/types.h"

namespace modal_deform {

struct FullSolveResult {
  RowMatrixX3d positions;         // #V by 3, mesh units
  int iterations = 0;             // Newton steps
  int factorizations = 0;         // numeric factorisations, failed ones (τ too small) included
  double energy = 0;              // F at the result: deformation energy plus handle term
  double gradient_norm = 0;       // ‖∇F‖ at the result (normalised frame)
  double rest_gradient_norm = 0;  // ‖∇F‖ at rest, the scale of the relative tolerance
  bool converged = false;         // gradient_norm ≤ tolerance · rest_gradient_norm
};

// V: #V by 3 rest positions, F: #F by 3 triangles (validate_mesh); handles and weights as in
// checked_handle_weights; transforms: one rigid 4 by 4 transform per handle (check_transforms);
// stiffness μ > 0; bending, membrane: the shells weights (ignored by ARAP); tolerance in (0, 1):
// relative reduction of ‖∇F‖ from rest; at most max_iterations ≥ 0 Newton steps, starting at
// rest, or at `initial` (#V by 3, mesh units) when given: the previous frame's answer lets a
// large motion be reached in steps (a handle turned by 180° pulls its vertices straight through
// the axis at rest, so a solve from rest may find a crumpled minimum instead of the twist).
// Throws InputError for bad input and NumericalError when no shift makes the Hessian
// factorisable. Runs single-threaded but for CHOLMOD's BLAS and the energy's own threads.
FullSolveResult solve_full(const VerticesRef& V, const FacesRef& F, const Handles& handles, const VectorRef& weights,
                           const Transforms& transforms, double stiffness, EnergyKind energy, double bending,
                           double membrane, double tolerance, int max_iterations,
                           const RowMatrixX3d* initial = nullptr);

}  // namespace modal_deform
