// The bake: the paper's preprocess (sections 4 and 5), from a mesh to the reduced space the
// solver poses in. One forward pipeline, in the mesh's normalised frame: the simulated vertices
// (attachment.h; the others attached), K = ∇²E(x̄) and lumped M, the shifted pencil K − σM
// factored once (CHOLMOD's ordering beside the ghost's edge collapse), the lowest vibration modes
// (a floppy mesh's zero modes on top of `modes`), modal derivatives (eq. 13) of the pairs of modes
// other than translations and zero modes, M-orthonormalisation, and the float32 vectors in mesh
// units with the ghost's restricted from them. A region bakes only its vertices (region.h); a
// mesh of more than options.proxy_above vertices is baked on a proxy and prolongated
// (proxy_bake.h). Stages are timed into Basis::timings and reported through Progress under the
// names of kBakeStages (util/bake_stages.h); a cancel throws Cancelled at the next report and
// leaves nothing behind. Each step and its reasons: docs/design.md, "The bake's stages".
#pragma once

#include <string>

#include "basis/basis.h"
#include "energy/make_energy.h"
#include "util/option.h"
#include "util/progress.h"
#include "util/types.h"

namespace modal_deform {

// A mode with λ below this fraction of tr K / tr M (a mass-weighted mean of the spectrum, which
// grows with the resolution as rounding in K does) is a zero mode: on the shared scans the zero
// modes lie orders of magnitude below it and the lowest flexible modes orders of magnitude above.
constexpr double kZeroEigenvalue = 1e-12;

// The fewest vertices of a mesh simplified by edge collapse (the ghost, a proxy): a tetrahedron's.
constexpr int kFewestSimplifiedVertices = 4;

struct BakeOptions {
  int modes = 20;        // vibration modes, rigid motions included
  int derivatives = 52;  // modal derivatives
  int ghost = 1000;      // ghost vertices to aim for (≥ 4; the mesh itself when ≥ #V)
  EnergyKind energy = EnergyKind::kShells;  // or ARAP, with derivatives = 0
  // Shells: α, β and the stiffness painted per vertex; every stage that sees the energy sees the
  // paint, a proxy with its fine vertices' means; the basis keeps it for the solver's ghost.
  Material material = {};
  // Derivatives of pairs with the linearised rotations too (the paper's rule), or of pairs of
  // flexible modes only (false; needs more modes for as many derivatives).
  bool rotation_pairs = true;
  // A mesh of more than proxy_above vertices (0: never) is baked on a proxy of about `proxy`
  // vertices (4 ≤ proxy ≤ proxy_above; a ghost of as many or more is the proxy itself), made by
  // edge collapse, and its basis prolongated to the fine vertices (prolongation.h). The sizes: a
  // mesh of proxy_above bakes as it is within the memory of an artist's machine, and a proxy of
  // `proxy` poses as closely as the mesh's own basis (bench/results/multires.json).
  int proxy_above = 150000;
  int proxy = 50000;
  // Fine vertex indices that may move (any order; empty: the whole mesh). Every other vertex
  // stays at rest, clamped (region.h); the region's free vertices decide on a proxy.
  Eigen::VectorXi region = {};
};

// The options as the Python API and the add-on take them (option.h), with their defaults from
// BakeOptions{}: visit(option, field) with `field` an accessor o -> o.member.
template <typename Visit>
void for_each_bake_option(Visit&& visit) {
  visit(Option{"modes",
               "Vibration modes, the rigid motions of the simulated parts (6 each) included: more "
               "let poses "
               "take more shapes and make the bake and posing slower.",
               at_least(1)},
        [](auto& o) -> auto& { return o.modes; });
  visit(Option{"derivatives",
               "Modal derivatives of pairs of modes, low eigenvalues first (Discrete Shells only): "
               "they let large "
               "bends and twists keep the mesh's volume; more cost bake and posing time.",
               at_least(0)},
        [](auto& o) -> auto& { return o.derivatives; });
  visit(Option{"ghost",
               "Vertices of the ghost, the coarse copy of the mesh posing weighs the deformation "
               "on (the mesh "
               "itself when it has fewer): more follow the mesh more closely, fewer pose faster.",
               at_least(kFewestSimplifiedVertices)},
        [](auto& o) -> auto& { return o.ghost; });
  visit(
      Option{
          "energy",
          "The deformation energy: \"shells\" (Discrete Shells) or \"arap\" (as-rigid-as-possible, "
          "with derivatives=0: it has no third derivative)."},
      [](auto& o) -> auto& { return o.energy; });
  for_each_material_option(visit);
  visit(Option{"rotation_pairs",
               "Derivatives of pairs with the linearised rotations too (the paper's rule), or of "
               "pairs of flexible "
               "modes only (False: needs more modes for as many derivatives)."},
        [](auto& o) -> auto& { return o.rotation_pairs; });
  visit(Option{"proxy_above",
               "A mesh with more vertices than this is baked on a proxy of about `proxy` vertices "
               "(0: never).",
               at_least(0)},
        [](auto& o) -> auto& { return o.proxy_above; });
  visit(Option{"proxy",
               "Vertices of the proxy a dense mesh is baked on, made by the ghost's edge collapse; "
               "every fine vertex "
               "follows it by barycentric weights on its nearest proxy triangle.",
               at_least(kFewestSimplifiedVertices)},
        [](auto& o) -> auto& { return o.proxy; });
  visit(Option{"region",
               "The vertices that may move, (k,) indices, or None for the whole mesh: every other "
               "vertex stays "
               "exactly at rest and the faces around the region hold it as a fixed boundary."},
        [](auto& o) -> auto& { return o.region; });
}

// The reduced space of (V #V by 3, F #F by 3, any length unit) per the pipeline above: a Basis in
// the mesh's units with num_modes = modes + num_floppy and r = num_modes + derivatives − dropped
// columns. Throws InputError for a bad mesh or option (naming it), among them: modes not above the
// rigid motions of the simulated components (6 each), more derivatives than pairs of the modes
// that are neither rigid nor zero, "arap" with derivatives or with painted stiffness, paint that
// require_stiffness_paint refuses; NumericalError when a solver fails;
// OutOfMemory when the memory the bake needs (bake_memory.h, estimated once CHOLMOD has analysed
// K and before the numeric factorisation) is more than is available, or an allocation fails;
// Cancelled when `progress` says stop.
Basis bake(const VerticesRef& V, const FacesRef& F, const BakeOptions& options, Progress& progress);

}  // namespace modal_deform
