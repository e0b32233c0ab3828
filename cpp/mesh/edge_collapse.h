// Quadric-error edge collapse (Garland–Heckbert 1997) that tracks which fine vertices merge:
// the simplification behind the ghost mesh (paper section 5).
//
// Works on an indexed face set, so non-manifold edges and vertices, several components,
// unreferenced vertices, duplicate and degenerate faces are all accepted. Copies of a face with
// opposite orientations cancel first: decimated scans are full of such zero-thickness double
// sheets (dragon_vrip_res2: 2,534 non-manifold edges, 117 once they cancel). They cancel too when
// a collapse makes them: a double sheet whose two sides are triangulated differently (refined
// scans: bench/subdivision.split_edges cuts the two copies of a face along different diagonals)
// is not a copy of a face until its vertices merge. Two faces a collapse lays on each other cancel
// when they are such a sheet already (their four vertices in one plane, folded onto each other);
// the two sides of a thin part are not, and are never merged. A vertex whose faces all cancel
// leaves the mesh. (Refusing such collapses would leave each vertex of a sheet a cluster of its
// own, a proxy vertex whose stiffness per mass makes K − σM numerically indefinite.) Every collapse merges
// two clusters of fine vertices and puts the merged vertex at the mass-weighted centroid of its
// cluster's rest positions (the plain mean for a cluster without mass), which is where the ghost
// needs it; the quadric (plus a small compactness term) only ranks the candidates.
//
// A collapse is done only when it keeps the mesh sound:
//   - topology: the link condition (every common neighbour of the two vertices spans a face with
//     them), no duplicate face (a face laid on the other side of a double sheet cancels with it,
//     see above), the merged vertex keeps a face;
//   - boundary: boundary vertices merge only along boundary edges, never with interior vertices,
//     so boundary loops are neither pulled inward nor pinched;
//   - geometry: no changed face of quality at least kMinFaceQuality turns its normal by more than
//     kMaxNormalTurnDegrees (a needle's normal is noise), no changed face points against the input
//     face it descends from or becomes degenerate, and the worst face around the merged vertex is
//     no needle (quality below kMinFaceQuality) unless it is no worse than the worst face around
//     the two vertices before (the removed faces included). The worst face is judged around the
//     vertex, not face by face: on subdivided scans every collapse thins some needle a little or
//     turns its normal, and face by face would leave islands of uncollapsed fine vertices, tiny
//     ghost triangles that a pose crushes first.
//   - sides: vertices of different sides (a region bake's free and clamped vertices) never merge,
//     and a vertex next to the other side merges only with another such vertex along an edge of a
//     face that reaches the other side, so the line between the sides stays where it is.
// Edges of degenerate input faces are collapsed first, which removes those faces.
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
// the input and as collapses make them; vertices left without a face belong to no cluster. A target of at least #V gives (V, F) unchanged, each vertex
// its own cluster. `sides` (#V, or empty for one side) splits the vertices into sides that stay
// apart (see above). Reports progress as stage "ghost"; throws Cancelled when told to stop and
// InputError for bad input (see validate_mesh; target < 4; mass or sides of the wrong size, mass
// negative or not finite; no triangle left once faces cancel).
EdgeCollapse collapse_edges(const VerticesRef& V, const FacesRef& F, const VectorRef& mass, int target,
                            Progress* progress = nullptr, const std::vector<char>& sides = {});

}  // namespace modal_deform
