// Optimized cubature (An, Kim, James, "Optimizing Cubature for Efficient Integration of Subspace
// Deformations", ACM TOG 27(5), 2008), the hyper-reduction the 2015 shape-space paper evaluates
// its energy with: a reduced energy Σ_t E_t(x̄ + U q) over all the terms t of a mesh is replaced
// by Σ_{t ∈ S} ω_t E_t over a few terms with weights ω_t ≥ 0, chosen so that the weighted sum of
// the terms' reduced gradients U_tᵀ ∇E_t reproduces the full one, Uᵀ ∇E, at training points. An
// evaluation then touches only the chosen terms and the rows of U at their vertices. Non-negative
// weights keep the terms' minima: where every term is at its rest, the cubature's gradient is zero
// too.
//
// The fit is the paper's greedy NNLS (section 4.2): starting from no term, each round adds the
// terms whose reduced gradients (over all training points, as one column) correlate best with what
// is left of the target, then solves the non-negative least-squares problem on the chosen columns
// (Lawson–Hanson; a term whose weight drops to zero leaves), until the relative residual is within
// the tolerance or the term budget is spent.
#pragma once

#include <array>
#include <vector>

#include "util/types.h"

namespace modal_deform {

struct CubatureOptions {
  int max_terms = 1000;     // terms chosen at most (≥ 1)
  double tolerance = 0.02;  // relative residual ‖Σ ω_t a_t − b‖ / ‖b‖ at which the fit stops, in (0, 1)
};

// The chosen terms (ascending) and their weights (> 0).
struct Cubature {
  std::vector<int> terms;
  std::vector<double> weights;
};

struct CubatureFit {
  Cubature cubature;
  double residual = 0;  // the relative residual reached (0 when the target is zero)
};

// One training point: every term's gradient there (#terms by 12, as DiscreteShells::term_gradients
// writes them) and the weight of the point's equations in the fit (e.g. one over the norm of a
// reference gradient, so that every point counts alike).
struct CubatureSample {
  RowMatrixXd term_gradients;
  double scale = 1;
};

// The cubature of the terms whose vertices are `term_vertices` (#terms, −1 after a term's last
// vertex, as DiscreteShells::term_vertices) for the subspace U (3n by d): at each sample p, the
// weighted sum of scale_p U_tᵀ g_{t,p} approximates scale_p Uᵀ Σ_t g_{t,p} (g_{t,p} term t's
// gradient over its vertices). A zero target gives no term. Deterministic. Throws InputError for
// mismatched sizes, a vertex outside U's rows or an option out of range.
CubatureFit fit_cubature(const Eigen::Ref<const Eigen::MatrixXd>& U,
                         const std::vector<std::array<int, 4>>& term_vertices,
                         const std::vector<CubatureSample>& samples,
                         const CubatureOptions& options = {});

}  // namespace modal_deform
