// Refine: a pose's minimum on the full mesh, from a start near it (the reduced pose, or an
// animation's previous refined frame), falling back to the solve from rest.
//
// The solve from the start (solve_full with `initial`) is one load step. A start far from the
// minimum (a small basis, a strong pose) can lead Newton's first steps to collapse triangles, so
// that it stalls at a kink or spends its iterations; the solve from rest, in load steps, does not
// start there. When the solve from the start does not converge, the solve from rest runs as well,
// and its answer is taken when it converged or is lower.
#pragma once

#include "solve/full_solver.h"

namespace modal_deform {

struct RefineResult : FullSolveResult {
  bool from_rest = false;  // the answer is the solve from rest's
};

// The scalar fields of a RefineResult by name: solve_full's, then from_rest.
template <typename Visit>
void for_each_refine_stat(Visit&& visit) {
  for_each_full_solve_stat(visit);
  visit("from_rest", [](auto& r) -> auto& { return r.from_rest; });
}

// The share of the progress bar the solve from the start reports over, [0, kFromStartShare]; the
// solve from rest reports over the rest of it.
constexpr double kFromStartShare = 0.5;

// Arguments, options and errors as for solve_full, from `initial` (#V by 3, mesh units). The
// progress bar ends at 1 whichever solves run. With the fallback, iterations, factorizations,
// seconds and history count both solves, and initial_energy is F at `initial`, whichever answer
// is returned.
RefineResult refine(const VerticesRef& V, const FacesRef& F, const Handles& handles,
                    const VectorRef& weights, const Transforms& transforms, double stiffness,
                    const FullSolveOptions& options, const RowMatrixX3d& initial);

}  // namespace modal_deform
