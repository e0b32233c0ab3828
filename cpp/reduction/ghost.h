// The ghost: a coarse mesh on which the reduced solver evaluates the energy (paper section 5).
//
// Each fine vertex collapses onto exactly one ghost vertex; a ghost quantity is the mass-weighted
// mean of the fine quantity over the vertices collapsed onto it (the plain mean when they have no
// mass). The ghost's rest positions are that mean of the fine rest positions, so the restriction
// of a rigid motion of the fine mesh is the same rigid motion of the ghost.
#pragma once

#include <vector>

#include "energy/stiffness_paint.h"
#include "util/progress.h"
#include "util/types.h"

namespace modal_deform {

struct Ghost {
  RowMatrixX3d V;       // #G by 3 rest positions (the restriction of the fine rest positions)
  RowMatrixX3i F;       // #GF by 3 triangles over the ghost vertices
  Eigen::VectorXi map;  // #V: the ghost vertex each fine vertex collapses onto, in [0, #G)
};

// Simplifies (V #V by 3, F #F by 3) by edge collapse (see collapse_edges) to about `target`
// vertices (fewer are not reached when no valid collapse is left; the result says how many).
// `mass` (#V, length², lumped_mass) weights the means. Vertices left without a face (unreferenced,
// or only on faces that cancelled) join the nearest ghost vertex. A target of at least #V gives the
// mesh itself with the identity map. `sides` (#V or empty) keeps vertices of different sides apart
// (collapse_edges). Reports stage "ghost"; throws Cancelled when told to stop, InputError for bad
// input.
Ghost ghost_mesh(const VerticesRef& V, const FacesRef& F, const VectorRef& mass, int target,
                 Progress* progress = nullptr, const std::vector<char>& sides = {});

// The fine vertex (row of fine_V, #V by 3) nearest to ghost vertex g among those that collapse onto
// it: how a message names a vertex of a ghost or proxy to the artist, whose mesh it is not. Throws
// InputError when g is not a ghost vertex or no fine vertex collapses onto it.
int nearest_fine_vertex(const Ghost& ghost, const VerticesRef& fine_V, int g);

// Restricts fine vectors to the ghost: U (3#V by r, interleaved x0 y0 z0 x1 ...) to 3#G by r,
// each ghost vertex getting the `fine_mass`-weighted mean of its fine vertices, per coordinate.
// `map` (#V) sends fine vertices to ghost vertices in [0, num_ghost); every ghost vertex needs at
// least one. Columns run in parallel.
Eigen::MatrixXd restrict_to_ghost(const Eigen::Ref<const Eigen::VectorXi>& map, int num_ghost,
                                  const VectorRef& fine_mass,
                                  const Eigen::Ref<const Eigen::MatrixXd>& U);

inline Eigen::MatrixXd restrict_to_ghost(const Ghost& ghost, const VectorRef& fine_mass,
                                         const Eigen::Ref<const Eigen::MatrixXd>& U) {
  return restrict_to_ghost(ghost.map, static_cast<int>(ghost.V.rows()), fine_mass, U);
}

// The painted stiffness of the ghost (or of a proxy): each ghost vertex's weight is the
// `fine_mass`-weighted mean of its fine vertices' weights, so its elements are as stiff as the fine
// ones around them on average (the factor is linear in the weights, stiffness_paint.h).
StiffnessPaint restrict_to_ghost(const Eigen::Ref<const Eigen::VectorXi>& map, int num_ghost,
                                 const VectorRef& fine_mass, const StiffnessPaint& paint);

}  // namespace modal_deform
