#include "solve/refine.h"

#include <string>
#include <utility>

namespace modal_deform {
namespace {

// `options` with its progress reported over [begin, begin + width] of the caller's bar.
FullSolveOptions on_share(const FullSolveOptions& options, double begin, double width) {
  FullSolveOptions share = options;
  if (options.progress)
    share.progress = [callback = options.progress, begin, width](const std::string& stage,
                                                                 double fraction) {
      return callback(stage, begin + width * fraction);
    };
  return share;
}

}  // namespace

RefineResult refine(const VerticesRef& V, const FacesRef& F, const Handles& handles,
                    const VectorRef& weights, const Transforms& transforms, double stiffness,
                    const FullSolveOptions& options, const RowMatrixX3d& initial) {
  RefineResult from_start{solve_full(V, F, handles, weights, transforms, stiffness,
                                     on_share(options, 0.0, kFromStartShare), &initial),
                          false};
  if (from_start.converged) {
    // The bar's second share is not needed; the work is done, so there is nothing left to cancel.
    if (options.progress) options.progress("solve", 1.0);
    return from_start;
  }
  FullSolveResult from_rest = solve_full(V, F, handles, weights, transforms, stiffness,
                                         on_share(options, kFromStartShare, 1.0 - kFromStartShare));
  const int iterations = from_start.iterations + from_rest.iterations;
  const int factorizations = from_start.factorizations + from_rest.factorizations;
  const double seconds = from_start.seconds + from_rest.seconds;
  std::vector<NewtonIteration> history = std::move(from_start.history);
  history.insert(history.end(), from_rest.history.begin(), from_rest.history.end());
  RefineResult result;
  if (from_rest.converged || from_rest.energy < from_start.energy) {
    const double initial_energy = from_start.initial_energy;
    result = RefineResult{std::move(from_rest), true};
    result.initial_energy = initial_energy;
  } else {
    result = std::move(from_start);
  }
  result.iterations = iterations;
  result.factorizations = factorizations;
  result.seconds = seconds;
  result.history = std::move(history);
  return result;
}

}  // namespace modal_deform
