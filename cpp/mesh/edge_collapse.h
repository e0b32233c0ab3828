// Quadric-error edge collapse (Garland–Heckbert 1997) that tracks which fine vertices merge:
// the simplification behind the ghost mesh (paper section 5) and a dense bake's proxy.
//
// Takes any indexed face set (non-manifold, several components, unreferenced vertices, duplicate
// and degenerate faces). Copies of a face with opposite orientations cancel, as given and as a
// collapse makes them. Every collapse merges two clusters of fine vertices and puts the merged
// vertex at the mass-weighted centroid of its cluster's rest positions, where the ghost needs it;
// the quadric (plus a small compactness term) only ranks the candidates. A collapse is done only
// when it keeps the mesh sound: topology (link condition, no duplicate face), boundary (loops
// neither pulled inward nor pinched), geometry (no turned or degenerate face, no worse needle) and
// sides (a region bake's free and clamped vertices never merge). Edges of degenerate input faces
// are collapsed first. Each rule and its reason: docs/design.md, "The edge collapse".
#pragma once

#include <vector>

#include "util/progress.h"
#include "util/types.h"

namespace modal_deform {

// Largest turn of a face normal in one collapse.
constexpr double kMaxNormalTurnDegrees = 60.0;
// Smallest triangle quality 4√3·area / Σ edge² (1 for equilateral) a collapse may create.
constexpr double kMinFaceQuality = 0.1;

struct EdgeCollapse {
  // #C by 3: the position of each cluster, the mass-weighted centroid of its fine vertices.
  RowMatrixX3d V;
  // #FC by 3 faces over clusters, each the image of one input face with its orientation.
  RowMatrixX3i F;
  // #V: the cluster of each fine vertex, in [0, #C); -1 for vertices no face uses, in the input
  // or once faces cancel (they belong to no cluster).
  Eigen::VectorXi cluster;
};

// Collapses edges of (V #V by 3, F #F by 3) until at most `target` clusters remain or no valid
// collapse is left (the result says how many were reached). `mass` (#V, length², e.g.
// lumped_mass) weights the centroids. Faces with repeated indices are dropped first, and faces
// on the same three vertices cancel by orientation (one copy of a surplus orientation stays), in
// the input and as collapses make them; vertices left without a face belong to no cluster. A target
// of at least #V gives (V, F) unchanged, each vertex its own cluster. `sides` (#V, or empty for one
// side) splits the vertices into sides that stay apart (see above). Reports progress as stage
// "ghost"; throws Cancelled when told to stop and InputError for bad input (see validate_mesh;
// target < 4; mass or sides of the wrong size, mass negative or not finite; no triangle left once
// faces cancel).
EdgeCollapse collapse_edges(const VerticesRef& V, const FacesRef& F, const VectorRef& mass,
                            int target, Progress* progress = nullptr,
                            const std::vector<char>& sides = {});

}  // namespace modal_deform
