#include "bake/bake.h"

#include <algorithm>
#include <memory>
#include <new>
#include <string>
#include <utility>

#include "bake/bake_memory.h"
#include "bake/bake_run.h"
#include "bake/ghost_in_background.h"
#include "bake/proxy_bake.h"
#include "bake/region_bake.h"
#include "energy/arap.h"
#include "energy/discrete_shells.h"
#include "linalg/row_blocks.h"
#include "mesh/mass.h"
#include "mesh/mesh_check.h"
#include "mesh/normalization.h"
#include "modes/modal_derivatives.h"
#include "modes/rigid_motions.h"
#include "modes/shifted_pencil.h"
#include "modes/stiffness_and_mass.h"
#include "reduction/attachment.h"
#include "reduction/ghost.h"
#include "reduction/orthonormalize.h"
#include "util/bake_stages.h"
#include "util/errors.h"
#include "util/require_weight.h"

namespace modal_deform {
namespace {

// Pairs per third_batch call: each call is one pass over the elements, and the bar moves between
// calls. 64 takes the paper's 52 derivatives in one pass and its 110 in two, for a temporary of 64
// columns.
constexpr int kPairsPerPass = 64;

void check_bake_options(const BakeOptions& o, Eigen::Index num_vertices) {
  check_options(o, [](auto visit) { for_each_bake_option(visit); });
  if (o.proxy_above > 0 && o.proxy > o.proxy_above)
    throw InputError(message("proxy: expected between ", kFewestSimplifiedVertices,
                             " and proxy_above's ", o.proxy_above, " vertices, got ", o.proxy));
  if (o.energy == EnergyKind::kArap && o.derivatives > 0)
    throw InputError(message(
        "derivatives: the ARAP energy has no third derivative, so it has no modal derivatives; ",
        "bake it with derivatives = 0, or use the shells energy (asked for ", o.derivatives, ")"));
  require_material(o.material, num_vertices);
  require_paintable(o.energy, o.material.paint);
}

// The simulated submesh in the normalised frame, and the modes asked of it.
struct Simulated {
  Attachment attachment;
  RowMatrixX3d V;        // #S by 3
  Eigen::VectorXd mass;  // #S
  // A region bake's clamped vertices (#C by 3, after the simulated ones in attachment.faces); the
  // energy sees them, the eigenproblem does not (region.h). Empty otherwise.
  RowMatrixX3d clamped;
  StiffnessPaint paint;  // the painted stiffness of the simulated vertices, then the clamped ones
  int num_rigid =
      0;  // kRigidMotions per simulated component (none in a region: its boundary is fixed)
  int flexible = 0;  // modes besides the rigid motions
  Eigen::Index size() const { return V.rows(); }
  // The rest positions the energy is built on: the simulated vertices, then the clamped ones.
  RowMatrixX3d energy_vertices() const {
    RowMatrixX3d all(V.rows() + clamped.rows(), 3);
    all << V, clamped;
    return all;
  }
};

// 2. Which vertices of V are simulated and which follow them (attachment.h), or a region bake's
// (`part`); refuses mode counts the submesh cannot give.
Simulated simulated_submesh(const VerticesRef& V, const MovingPart& part, BakeRun& run) {
  const BakeOptions& options = run.options;
  const Basis& basis = run.basis;
  Simulated sim;
  sim.attachment = run.stage(stages::kAttachment, [&] { return part.attachment(); });
  const std::vector<int>& simulated = sim.attachment.simulated;
  const auto S = static_cast<Eigen::Index>(simulated.size());
  sim.V.resize(S, 3);
  sim.mass.resize(S);
  for (Eigen::Index s = 0; s < S; ++s) {
    sim.V.row(s) = basis.scale * V.row(simulated[static_cast<size_t>(s)]);
    sim.mass[s] = basis.scale * basis.scale * basis.mass[simulated[static_cast<size_t>(s)]];
  }
  const std::vector<int> clamped = part.clamped();
  sim.clamped = basis.scale * V(clamped, Eigen::all);
  const StiffnessPaint& paint = options.material.paint;
  sim.paint.max_stiffness = paint.max_stiffness;
  if (paint.weights.size() > 0) {
    sim.paint.weights.resize(S + static_cast<Eigen::Index>(clamped.size()));
    sim.paint.weights << paint.weights(simulated), paint.weights(clamped);
  }
  const int components = sim.attachment.num_components;
  sim.num_rigid = kRigidMotions * components;
  if (options.modes <= sim.num_rigid)
    throw InputError(message("modes: ", options.modes, " modes are not more than the ",
                             sim.num_rigid, " rigid motions of the mesh's ", components,
                             " simulated components (", kRigidMotions, " each); ask for more than ",
                             sim.num_rigid));
  sim.flexible = options.modes - sim.num_rigid;
  if (sim.flexible >= 3 * S - sim.num_rigid)
    throw InputError(message("modes: the simulated mesh has ", 3 * S - sim.num_rigid,
                             " degrees of freedom besides its rigid motions; ask for fewer than ",
                             3 * S, " modes, got ", options.modes));
  return sim;
}

// 3. K = ∇²E(x̄) of the submesh; the shells energy is kept for its third derivatives.
struct Stiffness {
  std::unique_ptr<DiscreteShells>
      shells;  // null for ARAP, and once the third derivatives are taken
  SparseMatrix K;
};

Stiffness stiffness_at_rest(const Simulated& sim, BakeRun& run) {
  const BakeOptions& options = run.options;
  return run.stage(stages::kHessian, [&] {
    Stiffness stiffness;
    const RowMatrixX3d V = sim.energy_vertices();
    if (options.energy == EnergyKind::kShells) {
      stiffness.shells = std::make_unique<DiscreteShells>(
          V, sim.attachment.faces, options.material.bending, options.material.membrane, sim.paint);
      stiffness.K = stiffness.shells->hessian(stiffness.shells->rest());
    } else {
      const Arap arap(V, sim.attachment.faces);
      stiffness.K = arap.hessian(arap.rest());
    }
    // A region's clamped vertices do not move: the block of the simulated ones (a fixed boundary).
    if (sim.clamped.rows() > 0)
      stiffness.K = SparseMatrix(stiffness.K.topLeftCorner(3 * sim.size(), 3 * sim.size()));
    return stiffness;
  });
}

// 4. The pencil (K, M) with the rigid motions as its kernel, and CHOLMOD's ordering of K while the
// ghost of the part that moves is simplified beside it (step 8 uses it). Ordered here
// rather than at the pencil's first factorisation, so the bar moves between the two (CHOLMOD
// reports nothing during either), and so that the factor's size is known before the numeric
// factorisation: what cannot fit is refused at once, not half a minute later.
Ghost order_beside_the_ghost(const MovingPart& part, const SparseMatrix& K, ShiftedPencil& pencil,
                             BakeRun& run) {
  const BakeOptions& options = run.options;
  GhostInBackground ghost(part.V, part.F, part.mass, options.ghost);
  run.progress.report(stages::kFactorisation, 0.0);
  try {
    pencil.analyze();
  } catch (const OutOfMemory& e) {
    throw OutOfMemory(message("bake: not enough memory to order the stiffness matrix (", K.rows(),
                              " rows, ", K.nonZeros(), " entries): ", e.what()));
  }
  require_memory(estimate_bake_memory(run.basis.num_vertices(), K.rows() / 3,
                                      static_cast<double>(K.nonZeros()), pencil.factor_bytes(),
                                      options.modes, options.derivatives),
                 available_memory());
  run.progress.report(stages::kFactorisation, 1.0);
  const Stopwatch stopwatch(run.basis.timings[stages::kGhost]);  // the wait beyond the ordering
  return ghost.get(run.progress);
}

// 5. The vibration modes (eigenvalue problem K φ = λ M φ), the zero modes of a floppy mesh
// deflated into the pencil's kernel. A breakdown of the factorisation names the artist's vertex of
// the failing row (`name`).
FlexibleModes vibration_stage(const VertexName& name, const Simulated& sim, const SparseMatrix& K,
                              ShiftedPencil& pencil, BakeRun& run) {
  try {
    return pencil.flexible_modes(
        sim.flexible, kZeroEigenvalue * K.diagonal().sum() / (3 * sim.mass.sum()), &run.progress);
  } catch (const NumericalError& e) {
    const int row = pencil.failed_row();
    if (row < 0) throw;
    const int vertex = sim.attachment.simulated[static_cast<size_t>(row / 3)];
    throw NumericalError(message(e.what(), "; that row is ", "xyz"[row % 3], " of ", name(vertex)));
  }
}

// 6. Modal derivatives (paper eq. 9, ∇²E ψ_ij = −∇³E(φ_i, φ_j)) of the pairs of modes other than
// the translations and zero modes: the linearised rotations of each component (λ = 0, so first),
// then the flexible modes.
struct PairedModes {
  Eigen::MatrixXd phi;  // energy DOFs by paired modes: zero at a region's clamped vertices
  std::vector<std::array<int, 2>> pairs;  // options.derivatives of them, in the paper's order
};

PairedModes paired_modes(const Simulated& sim, const Eigen::MatrixXd& rigid,
                         const FlexibleModes& modes, const BakeOptions& options) {
  const Eigen::Index S = sim.size();
  const int paired_rotations =
      options.rotation_pairs ? kRotations * sim.attachment.num_components : 0;
  PairedModes paired;
  Eigen::MatrixXd& phi = paired.phi;
  phi.resize(3 * S, paired_rotations + sim.flexible);
  // The rigid motions come kRigidMotions per component, the rotations after the translations.
  for (int r = 0; r < paired_rotations; ++r)
    phi.col(r) = rigid.col(kRigidMotions * (r / kRotations) + kTranslations + r % kRotations);
  phi.rightCols(sim.flexible) = modes.flexible;
  paired.pairs =
      derivative_pairs(components_moved(phi, sim.attachment.component), options.derivatives);
  // Modes are zero at a region's clamped vertices, which the energy has after the simulated ones.
  phi.conservativeResizeLike(Eigen::MatrixXd::Zero(3 * (S + sim.clamped.rows()), phi.cols()));
  return paired;
}

// The right-hand sides ∇³E(x̄)(φᵢ, φⱼ) of the pairs, kPairsPerPass per pass over the elements, in
// the rows of the simulated vertices (3S by pairs).
Eigen::MatrixXd third_derivatives(const DiscreteShells& shells, const PairedModes& paired,
                                  Eigen::Index S, BakeRun& run) {
  const std::vector<std::array<int, 2>>& pairs = paired.pairs;
  Eigen::MatrixXd B(3 * S, static_cast<Eigen::Index>(pairs.size()));
  run.stage(stages::kThirdDerivatives, [&] {
    for (size_t first = 0; first < pairs.size(); first += kPairsPerPass) {
      run.progress.report(stages::kThirdDerivatives, static_cast<double>(first) / pairs.size());
      const size_t last = std::min(pairs.size(), first + kPairsPerPass);
      const RowMatrixXd batch = shells.third_batch(shells.rest(), paired.phi,
                                                   {pairs.begin() + first, pairs.begin() + last});
      for_row_blocks(B.rows(), [&](Eigen::Index row, Eigen::Index rows) {
        B.block(row, static_cast<Eigen::Index>(first), rows, batch.cols()) =
            batch.middleRows(row, rows);
      });
    }
  });
  return B;
}

// The derivatives, solved in the pencil. The shells energy and the paired modes are freed before
// the solves, where the bake's memory peaks (bench/results/bake_limit.json).
Eigen::MatrixXd derivative_stage(const Simulated& sim, Stiffness& stiffness,
                                 const FlexibleModes& modes, ShiftedPencil& pencil, BakeRun& run) {
  if (run.options.derivatives == 0) return Eigen::MatrixXd(3 * sim.size(), 0);
  Eigen::MatrixXd B = third_derivatives(
      *stiffness.shells, paired_modes(sim, pencil.kernel(), modes, run.options), sim.size(), run);
  stiffness.shells.reset();
  return pencil.solve_in_range(std::move(B), &run.progress);
}

// 7. [rigid motions, zero modes, modes, derivatives], M-orthonormal; derivatives that came out
// dependent are dropped (basis.num_dropped).
Eigen::MatrixXd orthonormal_basis(const Simulated& sim, const ShiftedPencil& pencil,
                                  const FlexibleModes& modes, Eigen::MatrixXd derivatives,
                                  BakeRun& run) {
  Basis& basis = run.basis;
  const Eigen::MatrixXd& kernel = pencil.kernel();  // the rigid motions, then the zero modes
  const auto leading = static_cast<int>(kernel.cols() + modes.flexible.cols());
  const Eigen::Index num_derivatives = derivatives.cols();
  Eigen::MatrixXd U(kernel.rows(), leading + num_derivatives);
  U << kernel, modes.flexible, derivatives;
  derivatives.resize(0, 0);
  {
    const Stopwatch stopwatch(basis.timings[stages::kOrthonormalisation]);
    const std::vector<int> kept =
        orthonormalize(U, dof_masses(sim.mass), kDependentTolerance, &run.progress);
    for (int j = 0; j < leading; ++j)
      if (j >= static_cast<int>(kept.size()) || kept[static_cast<size_t>(j)] != j)
        throw NumericalError(message("bake: column ", j,
                                     " of the rigid motions and modes came out dependent; ",
                                     "they are not M-orthonormal"));
  }
  basis.num_dropped = static_cast<int>(leading + num_derivatives - U.cols());
  basis.num_rigid = sim.num_rigid;
  basis.num_floppy = modes.num_zero;
  basis.num_modes = leading;
  basis.eigenvalues = Eigen::VectorXd::Zero(leading);
  basis.eigenvalues.tail(modes.eigenvalues.size()) = modes.eigenvalues;
  return U;
}

// 8. The fine basis (attached rows added, mesh units, single precision) and the ghost's,
// restricted from the double-precision one (rigid motions stay exact), with the ghost's painted
// stiffness. A region's ghost is its submesh's: restricted from the submesh's rows, and the
// vertices outside the submesh, which never move, map to ghost vertex 0 (the solver reads only
// the ghost's own arrays).
void fine_and_ghost_vectors(Eigen::MatrixXd U, const Simulated& sim, const MovingPart& part,
                            Ghost coarse, BakeRun& run) {
  Basis& basis = run.basis;
  run.stage(stages::kAssembly, [&] {
    if (U.rows() < basis.rest.size()) U = extend_to_attached(sim.attachment, U);
    U /= basis.scale;
    basis.vectors = U.cast<float>();
    basis.ghost_vectors = part.ghost_vectors(coarse, U);
    basis.ghost_stiffness_weights =
        restrict_to_ghost(coarse.map, static_cast<int>(coarse.V.rows()), part.mass,
                          part.paint(run.options.material.paint))
            .weights;
    basis.ghost_map = part.on_mesh(coarse.map);
    basis.ghost_vertices = std::move(coarse.V);
    basis.ghost_faces = std::move(coarse.F);
  });
}

}  // namespace

std::string vertex_at(const VerticesRef& V, int vertex) {
  return message("vertex ", vertex, " at (", V(vertex, 0), ", ", V(vertex, 1), ", ", V(vertex, 2),
                 ")");
}

Basis rest_state(const VerticesRef& V, const FacesRef& F, const BakeOptions& options,
                 double scale) {
  Basis basis;
  basis.rest = V;
  basis.mass = lumped_mass(V, F);
  basis.scale = scale;
  basis.material = options.material;
  basis.region = options.region;
  std::sort(basis.region.begin(), basis.region.end());
  return basis;
}

Basis bake_stages(const VerticesRef& V, const MovingPart& part, const BakeOptions& options,
                  Basis basis, const VertexName& name, Progress& progress) {
  BakeRun run{options, basis, progress};
  const Simulated sim = simulated_submesh(V, part, run);
  Stiffness stiffness = stiffness_at_rest(sim, run);
  ShiftedPencil pencil(stiffness.K, sim.mass,
                       sim.num_rigid > 0 ? rigid_motions(sim.V, sim.attachment.component, sim.mass)
                                         : Eigen::MatrixXd(3 * sim.size(), 0));
  Ghost coarse = order_beside_the_ghost(part, stiffness.K, pencil, run);
  const FlexibleModes modes = vibration_stage(name, sim, stiffness.K, pencil, run);
  Eigen::MatrixXd derivatives = derivative_stage(sim, stiffness, modes, pencil, run);
  const ShiftedPencil::Timings pencil_timings = pencil.timings();
  basis.timings[stages::kFactorisation] = pencil_timings.factorisation;
  basis.timings[stages::kModes] = pencil_timings.modes;
  if (options.derivatives > 0) basis.timings[stages::kDerivativeSolves] = pencil_timings.solves;
  Eigen::MatrixXd U = orthonormal_basis(sim, pencil, modes, std::move(derivatives), run);
  fine_and_ghost_vectors(std::move(U), sim, part, std::move(coarse), run);
  return basis;
}

Basis bake(const VerticesRef& V, const FacesRef& F, const BakeOptions& options,
           Progress& progress) {
  try {
    check_bake_options(options, V.rows());
    validate_mesh(V, F);
    Basis fine = rest_state(V, F, options, normalizing_scale(V));
    const MovingPart part(V, F, fine.mass, options.region);
    Basis basis = options.proxy_above > 0 && part.num_free() > options.proxy_above
                      ? bake_on_proxy(V, part, options, std::move(fine), progress)
                      : bake_stages(
                            V, part, options, std::move(fine),
                            [&V](int vertex) { return vertex_at(V, vertex); }, progress);
    validate_basis(basis);
    return basis;
  } catch (const std::bad_alloc&) {
    throw OutOfMemory(
        message("bake: out of memory: an allocation failed (", available_memory() / 1e9,
                " GB still available); close other programs, bake fewer modes and derivatives, "
                "or decimate the mesh"));
  }
}

}  // namespace modal_deform
