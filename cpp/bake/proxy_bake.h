// A dense mesh's bake: the stages (bake.h) on a proxy made by edge collapse to about
// options.proxy vertices of the part that moves (MovingPart; a region's free and clamped vertices
// stay apart, so the line between them stays in place), then the prolongation of the proxy's basis
// to the mesh's vertices (prolongation.h); the ghost is the proxy's, reached from a mesh vertex
// through its proxy vertex. A region's proxy is baked as a region (its clamped vertices still),
// and every vertex but the region's free ones is held at rest by a prolongation of zero weights.
#pragma once

#include "bake/bake_run.h"

namespace modal_deform {

// The basis of (V, `part` of it moving) on its proxy, from the mesh's rest state `fine`.
Basis bake_on_proxy(const VerticesRef& V, const MovingPart& part, const BakeOptions& options,
                    Basis fine, Progress& progress);

}  // namespace modal_deform
