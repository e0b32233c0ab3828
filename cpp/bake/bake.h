// The bake: the paper's preprocess (sections 4 and 5), from a mesh to the reduced space the
// solver poses in. One forward pipeline:
//
//   1. validate_mesh; scale = normalizing_scale(V): the energy lives in the paper's normalised
//      frame (longest bounding-box edge 10). The basis keeps the rest mesh and its masses.
//   2. Simulated vertices (attachment.h): components with less than 10% of the largest one's
//      area, unreferenced vertices and vertices without mass are attached, not simulated; they
//      follow the affine motion fitted to the simulated surface around them.
//   3. K = ∇²E(x̄) of the simulated submesh, M lumped.
//   4. The shifted pencil (shifted_pencil.h): K − σM, factored once for steps 5 and 6, with the
//      rigid motions of the components as its kernel (analytic, M-orthonormal, 6 per component).
//      CHOLMOD orders K while the ghost is simplified beside it (edge collapse of the whole mesh
//      to about `ghost` vertices).
//   5. Vibration modes: the lowest eigenpairs M-orthogonal to the kernel (deflation). A floppy
//      mesh (large parts joined at a single vertex; scan debris is attached in step 2) has
//      further zero modes, with λ < kZeroEigenvalue tr K/tr M: they come on top of `modes` (a
//      scan's count of mechanisms is not known before the bake, and each would take the place
//      of a deformation mode), stay in the basis after the rigid motions (Basis::num_floppy) and
//      join the pencil's kernel.
//   6. Modal derivatives (eq. 13) for the pairs of the modes other than translations and zero
//      modes (the linearised rotations and the flexible modes), in the paper's order:
//      right-hand sides ∇³E(x̄)(φᵢ, φⱼ) (third_batch), solved in the range of K in the pencil,
//      corrected on the eigenpairs found and refined: one CHOLMOD factorisation in all, the most
//      expensive step at 100k vertices.
//   7. [rigid motions, zero modes, modes, derivatives] M-orthonormalised (orthonormalize.h),
//      numerically dependent derivatives dropped (Basis::num_dropped).
//   8. Attached rows, conversion to mesh units (x = x̄ + U q), float32 vectors; the ghost's
//      vectors restricted from them.
//
// A region (options.region) changes steps 2 to 4: the simulated vertices are the region's, the
// energy is that of the faces touching it with the vertices outside clamped, K and M are the
// blocks of the simulated vertices, there are no rigid motions (a free part of the region has
// them as zero modes), and the rows of the vertices outside are zero (region.h; the part of the
// mesh that moves: region_bake.h).
//
// A mesh of more than options.proxy_above vertices goes through steps 2 to 8 as a proxy: the fine
// mesh simplified by the same edge collapse to about options.proxy vertices ("proxy"), baked in the
// fine mesh's normalised frame; then each fine vertex gets its barycentric weights on the nearest
// proxy triangle ("prolongation"). The Basis keeps the fine rest positions and masses, the
// proxy's vectors and the prolongation (proxy_bake.h): memory and storage grow with the fine
// mesh only by those weights. A region of more than options.proxy_above free vertices is baked so too: the proxy
// is its submesh's, simplified with the free and clamped vertices kept apart (so the line between
// them stays), baked as a region, and every fine vertex outside the region gets zero weights.
//
// Stages (kBakeStages in util/bake_stages.h, in the order they run) are timed into Basis::timings and
// reported through Progress with the same names: for a proxy bake "proxy" first; "attachment",
// "hessian", "factorisation" (CHOLMOD's analysis, reported before the ghost, and the numeric
// factorisation of the pencil; the pencil times its own parts), "ghost" (the wait for the ghost beyond the analysis: it is
// simplified on a thread of its own beside it), "modes" (the rest of them), "third derivatives",
// "derivative solves", "orthonormalisation", "assembly" (step 8: the fine and the ghost's
// vectors); for a proxy bake "prolongation" last; seconds.
// A cancel throws Cancelled at the next report and leaves nothing behind. CHOLMOD cannot report
// during its analysis and factorisation, nor a blocked solve during its right-hand sides: the bar
// pauses there (bench/results/bake_busy.json times them).
#pragma once

#include <string>

#include "energy/make_energy.h"
#include "basis/basis.h"
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
  int modes = 20;                 // vibration modes, rigid motions included
  int derivatives = 52;           // modal derivatives
  int ghost = 1000;               // ghost vertices to aim for (≥ 4; the mesh itself when ≥ #V)
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
               "Vibration modes, the rigid motions of the simulated parts (6 each) included: more let poses "
               "take more shapes and make the bake and posing slower.",
               at_least(1)},
        [](auto& o) -> auto& { return o.modes; });
  visit(Option{"derivatives",
               "Modal derivatives of pairs of modes, low eigenvalues first (Discrete Shells only): they let large "
               "bends and twists keep the mesh's volume; more cost bake and posing time.",
               at_least(0)},
        [](auto& o) -> auto& { return o.derivatives; });
  visit(Option{"ghost",
               "Vertices of the ghost, the coarse copy of the mesh posing weighs the deformation on (the mesh "
               "itself when it has fewer): more follow the mesh more closely, fewer pose faster.",
               at_least(kFewestSimplifiedVertices)},
        [](auto& o) -> auto& { return o.ghost; });
  visit(Option{"energy", "The deformation energy: \"shells\" (Discrete Shells) or \"arap\" (as-rigid-as-possible, "
                         "with derivatives=0: it has no third derivative)."},
        [](auto& o) -> auto& { return o.energy; });
  for_each_material_option(visit);
  visit(Option{"rotation_pairs",
               "Derivatives of pairs with the linearised rotations too (the paper's rule), or of pairs of flexible "
               "modes only (False: needs more modes for as many derivatives)."},
        [](auto& o) -> auto& { return o.rotation_pairs; });
  visit(Option{"proxy_above",
               "A mesh with more vertices than this is baked on a proxy of about `proxy` vertices (0: never).",
               at_least(0)},
        [](auto& o) -> auto& { return o.proxy_above; });
  visit(Option{"proxy",
               "Vertices of the proxy a dense mesh is baked on, made by the ghost's edge collapse; every fine vertex "
               "follows it by barycentric weights on its nearest proxy triangle.",
               at_least(kFewestSimplifiedVertices)},
        [](auto& o) -> auto& { return o.proxy; });
  visit(Option{"region",
               "The vertices that may move, (k,) indices, or None for the whole mesh: every other vertex stays "
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
