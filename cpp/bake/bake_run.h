// What the bake's files share: bake.cpp runs the stages, proxy_bake.cpp the proxy path around
// them, region_bake.h says which part of the mesh moves.
#pragma once

#include <functional>
#include <string>
#include <type_traits>

#include "bake/bake.h"
#include "bake/region_bake.h"
#include "util/stopwatch.h"

namespace modal_deform {

// How a bake error names a vertex of the mesh being baked: as the vertex of the artist's mesh it
// stands for, with its position (vertex_at).
using VertexName = std::function<std::string(int vertex)>;

std::string vertex_at(const VerticesRef& V, int vertex);

// What every step of one bake shares: the options, the basis it fills (its rest state first, its
// timings as it goes) and the bar.
struct BakeRun {
  const BakeOptions& options;
  Basis& basis;
  Progress& progress;

  // One stage of the bake: reported to the bar at its start and end, and its wall time added to
  // basis.timings[name] (a stage may run in parts). Returns what `work` returns.
  template <typename Work>
  auto stage(const char* name, Work&& work) {
    const Stopwatch stopwatch(basis.timings[name]);
    progress.report(name, 0.0);
    if constexpr (std::is_void_v<std::invoke_result_t<Work>>) {
      work();
      progress.report(name, 1.0);
    } else {
      auto result = work();
      progress.report(name, 1.0);
      return result;
    }
  }
};

// 1. What the basis keeps of the input: the rest mesh, its masses and the normalising scale
// (the fine mesh's, also for a proxy: the energy is the fine mesh's, in its frame).
Basis rest_state(const VerticesRef& V, const FacesRef& F, const BakeOptions& options, double scale);

// Stages 2 to 8 of the mesh V (whose `part` moves) on its rest state `basis`; errors name V's
// vertices by `name`.
Basis bake_stages(const VerticesRef& V, const MovingPart& part, const BakeOptions& options,
                  Basis basis, const VertexName& name, Progress& progress);

}  // namespace modal_deform
