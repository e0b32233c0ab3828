#include "bake/bake.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <future>
#include <memory>
#include <new>
#include <string>
#include <type_traits>

#include "bake/bake_memory.h"
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
#include "reduction/prolongation.h"
#include "reduction/region.h"
#include "util/bake_stages.h"
#include "util/errors.h"
#include "util/require_weight.h"
#include "util/stopwatch.h"

namespace modal_deform {
namespace {

// Pairs per third_batch call: each call is one pass over the elements, and the bar moves between
// calls. 64 takes the paper's 52 derivatives in one pass and its 110 in two, for a temporary of 64
// columns.
constexpr int kPairsPerPass = 64;

// How a bake error names a vertex of the mesh being baked: as the vertex of the artist's mesh it
// stands for, with its position (vertex_at).
using VertexName = std::function<std::string(int vertex)>;

std::string vertex_at(const VerticesRef& V, int vertex) {
  return message("vertex ", vertex, " at (", V(vertex, 0), ", ", V(vertex, 1), ", ", V(vertex, 2), ")");
}

// The ghost mesh, simplified on its own thread while CHOLMOD orders the stiffness matrix: both are
// serial, so together they take the time of the longer, and the factorisation after them has
// both cores for its BLAS. When the
// bake stops early, the destructor cancels the ghost and waits, so nothing outlives the bake.
class GhostInBackground {
 public:
  GhostInBackground(const VerticesRef& V, const FacesRef& F, const VectorRef& mass, int target)
      : progress_([this](const std::string&, double fraction) {
          fraction_ = fraction;
          return !stop_.load();
        }),
        ghost_(std::async(std::launch::async,
                          [&V, &F, &mass, target, this] { return ghost_mesh(V, F, mass, target, &progress_); })) {}
  ~GhostInBackground() {
    stop_ = true;
    if (ghost_.valid()) ghost_.wait();
  }
  GhostInBackground(const GhostInBackground&) = delete;
  GhostInBackground& operator=(const GhostInBackground&) = delete;

  // Waits for the ghost, passing its progress on to the bake's bar (which may cancel): the stage is
  // reported at least at its start and end, however soon the ghost was ready.
  Ghost get(Progress& progress) {
    do {
      progress.report(stages::kGhost, fraction_.load());
    } while (ghost_.wait_for(std::chrono::milliseconds(50)) != std::future_status::ready);
    progress.report(stages::kGhost, 1.0);
    return ghost_.get();
  }

 private:
  std::atomic<bool> stop_{false};
  std::atomic<double> fraction_{0.0};
  Progress progress_;
  std::future<Ghost> ghost_;
};

void check_options(const BakeOptions& o, Eigen::Index num_vertices) {
  if (o.modes < 1) throw InputError(message("modes: expected at least 1, got ", o.modes));
  if (o.derivatives < 0) throw InputError(message("derivatives: expected 0 or more, got ", o.derivatives));
  if (o.ghost < 4) throw InputError(message("ghost: a ghost needs at least 4 vertices, got ", o.ghost));
  if (o.proxy_above < 0) throw InputError(message("proxy_above: expected 0 (never) or more, got ", o.proxy_above));
  if (o.proxy_above > 0 && (o.proxy < 4 || o.proxy > o.proxy_above))
    throw InputError(message("proxy: expected between 4 and proxy_above's ", o.proxy_above, " vertices, got ", o.proxy));
  if (o.energy == EnergyKind::kArap && o.derivatives > 0)
    throw InputError(message("derivatives: the ARAP energy has no third derivative, so it has no modal derivatives; ",
                             "bake it with derivatives = 0, or use the shells energy (asked for ", o.derivatives, ")"));
  require_material(o.material, num_vertices);
  require_paintable(o.energy, o.material.paint);
}

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
Basis rest_state(const VerticesRef& V, const FacesRef& F, const BakeOptions& options, double scale) {
  Basis basis;
  basis.rest = V;
  basis.mass = lumped_mass(V, F);
  basis.scale = scale;
  basis.material = options.material;
  basis.region = options.region;
  std::sort(basis.region.begin(), basis.region.end());
  return basis;
}

// The simulated submesh in the normalised frame, and the modes asked of it.
struct Simulated {
  Attachment attachment;
  RowMatrixX3d V;        // #S by 3
  Eigen::VectorXd mass;  // #S
  // A region bake's clamped vertices (#C by 3, after the simulated ones in attachment.faces); the
  // energy sees them, the eigenproblem does not (region.h). Empty otherwise.
  RowMatrixX3d clamped;
  // A region bake's submesh: the fine indices of the simulated vertices, then the clamped ones.
  // Empty otherwise.
  std::vector<int> region_vertices;
  StiffnessPaint paint;  // the painted stiffness of the simulated vertices, then the clamped ones
  int num_rigid = 0;     // 6 per simulated component (none in a region: its boundary is fixed)
  int flexible = 0;      // modes besides the rigid motions
  Eigen::Index size() const { return V.rows(); }
  // The rest positions the energy is built on: the simulated vertices, then the clamped ones.
  RowMatrixX3d energy_vertices() const {
    RowMatrixX3d all(V.rows() + clamped.rows(), 3);
    all << V, clamped;
    return all;
  }
};

// 2 for a region bake: the region's free vertices are simulated, those outside it on a face with
// them are clamped (region.h), and nothing is attached.
Attachment region_attachment(const RegionMesh& region, Eigen::Index num_vertices) {
  Attachment attachment;
  attachment.simulated.assign(region.vertices.begin(), region.vertices.begin() + region.num_free);
  attachment.submesh_index = Eigen::VectorXi::Constant(num_vertices, -1);
  for (int s = 0; s < region.num_free; ++s) attachment.submesh_index[region.vertices[static_cast<size_t>(s)]] = s;
  attachment.faces = region.faces;
  attachment.component = Eigen::VectorXi::Zero(region.num_free);
  return attachment;
}

// 2. Which vertices are simulated and which follow them (attachment.h), or a region bake's
// (`region`, null for the whole mesh); refuses mode counts the submesh cannot give.
Simulated simulated_submesh(const VerticesRef& V, const FacesRef& F, const RegionMesh* region_or_null, BakeRun& run) {
  const BakeOptions& options = run.options;
  const Basis& basis = run.basis;
  Simulated sim;
  static const RegionMesh kWholeMesh;  // no clamped vertices
  const RegionMesh& region = region_or_null ? *region_or_null : kWholeMesh;
  sim.attachment = run.stage(stages::kAttachment, [&] {
    return region_or_null ? region_attachment(region, V.rows()) : attach(V, F);
  });
  const std::vector<int>& simulated = sim.attachment.simulated;
  const auto S = static_cast<Eigen::Index>(simulated.size());
  sim.V.resize(S, 3);
  sim.mass.resize(S);
  for (Eigen::Index s = 0; s < S; ++s) {
    sim.V.row(s) = basis.scale * V.row(simulated[static_cast<size_t>(s)]);
    sim.mass[s] = basis.scale * basis.scale * basis.mass[simulated[static_cast<size_t>(s)]];
  }
  const std::vector<int> clamped(region.vertices.begin() + region.num_free, region.vertices.end());
  sim.region_vertices = region.vertices;
  sim.clamped = basis.scale * V(clamped, Eigen::all);
  const StiffnessPaint& paint = options.material.paint;
  sim.paint.max_stiffness = paint.max_stiffness;
  if (paint.weights.size() > 0) {
    sim.paint.weights.resize(S + static_cast<Eigen::Index>(clamped.size()));
    sim.paint.weights << paint.weights(simulated), paint.weights(clamped);
  }
  const int components = sim.attachment.num_components;
  sim.num_rigid = 6 * components;
  if (options.modes <= sim.num_rigid)
    throw InputError(message("modes: ", options.modes, " modes are not more than the ", sim.num_rigid,
                             " rigid motions of the mesh's ", components,
                             " simulated components (6 each); ask for more than ", sim.num_rigid));
  sim.flexible = options.modes - sim.num_rigid;
  if (sim.flexible >= 3 * S - sim.num_rigid)
    throw InputError(message("modes: the simulated mesh has ", 3 * S - sim.num_rigid,
                             " degrees of freedom besides its rigid motions; ask for fewer than ", 3 * S,
                             " modes, got ", options.modes));
  return sim;
}

// 3. K = ∇²E(x̄) of the submesh; the shells energy is kept for its third derivatives.
struct Stiffness {
  std::unique_ptr<DiscreteShells> shells;  // null for ARAP, and once the third derivatives are taken
  SparseMatrix K;
};

Stiffness stiffness_at_rest(const Simulated& sim, BakeRun& run) {
  const BakeOptions& options = run.options;
  return run.stage(stages::kHessian, [&] {
    Stiffness stiffness;
    const RowMatrixX3d V = sim.energy_vertices();
    if (options.energy == EnergyKind::kShells) {
      stiffness.shells =
          std::make_unique<DiscreteShells>(V, sim.attachment.faces, options.material.bending,
                                                           options.material.membrane, sim.paint);
      stiffness.K = stiffness.shells->hessian(stiffness.shells->rest());
    } else {
      const Arap arap(V, sim.attachment.faces);
      stiffness.K = arap.hessian(arap.rest());
    }
    // A region's clamped vertices do not move: the block of the simulated ones (a fixed boundary).
    if (sim.clamped.rows() > 0) stiffness.K = SparseMatrix(stiffness.K.topLeftCorner(3 * sim.size(), 3 * sim.size()));
    return stiffness;
  });
}

// The part of the mesh that moves (mesh units), with its masses: the whole mesh, or a region bake's
// submesh (its free vertices, then the clamped ones: RegionMesh::vertices, and its faces). The
// ghost and a proxy simplify it, so that all their vertices are spent where the mesh moves.
class MovingPart {
 public:
  MovingPart(const VerticesRef& mesh_V, const FacesRef& mesh_F, const VectorRef& mesh_mass,
             const std::vector<int>& submesh, const FacesRef& submesh_F)
      : submesh_V_(mesh_V(submesh, Eigen::all)),
        submesh_mass_(mesh_mass(submesh)),
        V(submesh.empty() ? mesh_V : VerticesRef(submesh_V_)),
        F(submesh.empty() ? mesh_F : submesh_F),
        mass(submesh.empty() ? mesh_mass : VectorRef(submesh_mass_)) {}
  MovingPart(const MovingPart&) = delete;
  MovingPart& operator=(const MovingPart&) = delete;

 private:
  const RowMatrixX3d submesh_V_;
  const Eigen::VectorXd submesh_mass_;

 public:
  const VerticesRef V;
  const FacesRef F;
  const VectorRef mass;
};

// 4. The pencil (K, M) with the rigid motions as its kernel, and CHOLMOD's ordering of K while the
// ghost of what moves (MovingPart) is simplified beside it (step 8 uses it). Ordered here
// rather than at the pencil's first factorisation, so the bar moves between the two (CHOLMOD
// reports nothing during either), and so that the factor's size is known before the numeric
// factorisation: what cannot fit is refused at once, not half a minute later.
Ghost order_beside_the_ghost(const MovingPart& source, const SparseMatrix& K, ShiftedPencil& pencil, BakeRun& run) {
  const BakeOptions& options = run.options;
  GhostInBackground ghost(source.V, source.F, source.mass, options.ghost);
  run.progress.report(stages::kFactorisation, 0.0);
  try {
    pencil.analyze();
  } catch (const OutOfMemory& e) {
    throw OutOfMemory(message("bake: not enough memory to order the stiffness matrix (", K.rows(), " rows, ",
                              K.nonZeros(), " entries): ", e.what()));
  }
  require_memory(estimate_bake_memory(run.basis.num_vertices(), K.rows() / 3, static_cast<double>(K.nonZeros()),
                                      pencil.factor_bytes(), options.modes, options.derivatives),
                 available_memory());
  run.progress.report(stages::kFactorisation, 1.0);
  const Stopwatch stopwatch(run.basis.timings[stages::kGhost]);  // the wait beyond the ordering
  return ghost.get(run.progress);
}

// 5. The vibration modes (eigenvalue problem K φ = λ M φ), the zero modes of a floppy mesh
// deflated into the pencil's kernel. A breakdown of the factorisation names the artist's vertex of
// the failing row (`name`).
FlexibleModes vibration_stage(const VertexName& name, const Simulated& sim, const SparseMatrix& K,
                              ShiftedPencil& pencil,
                      BakeRun& run) {
  try {
    return pencil.flexible_modes(sim.flexible, kZeroEigenvalue * K.diagonal().sum() / (3 * sim.mass.sum()),
                                 &run.progress);
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

PairedModes paired_modes(const Simulated& sim, const Eigen::MatrixXd& rigid, const FlexibleModes& modes,
                         const BakeOptions& options) {
  const Eigen::Index S = sim.size();
  const int paired_rotations = options.rotation_pairs ? 3 * sim.attachment.num_components : 0;
  PairedModes paired;
  Eigen::MatrixXd& phi = paired.phi;
  phi.resize(3 * S, paired_rotations + sim.flexible);
  // The rigid motions come 6 per component, the rotations after the translations.
  for (int r = 0; r < paired_rotations; ++r) phi.col(r) = rigid.col(6 * (r / 3) + 3 + r % 3);
  phi.rightCols(sim.flexible) = modes.flexible;
  paired.pairs = derivative_pairs(components_moved(phi, sim.attachment.component), options.derivatives);
  // Modes are zero at a region's clamped vertices, which the energy has after the simulated ones.
  phi.conservativeResizeLike(Eigen::MatrixXd::Zero(3 * (S + sim.clamped.rows()), phi.cols()));
  return paired;
}

// The right-hand sides ∇³E(x̄)(φᵢ, φⱼ) of the pairs, kPairsPerPass per pass over the elements, in
// the rows of the simulated vertices (3S by pairs).
Eigen::MatrixXd third_derivatives(const DiscreteShells& shells, const PairedModes& paired, Eigen::Index S,
                                  BakeRun& run) {
  const std::vector<std::array<int, 2>>& pairs = paired.pairs;
  Eigen::MatrixXd B(3 * S, static_cast<Eigen::Index>(pairs.size()));
  run.stage(stages::kThirdDerivatives, [&] {
    for (size_t first = 0; first < pairs.size(); first += kPairsPerPass) {
      run.progress.report(stages::kThirdDerivatives, static_cast<double>(first) / pairs.size());
      const size_t last = std::min(pairs.size(), first + kPairsPerPass);
      const RowMatrixXd batch = shells.third_batch(shells.rest(), paired.phi, {pairs.begin() + first, pairs.begin() + last});
      for_row_blocks(B.rows(), [&](Eigen::Index row, Eigen::Index rows) {
        B.block(row, static_cast<Eigen::Index>(first), rows, batch.cols()) = batch.middleRows(row, rows);
      });
    }
  });
  return B;
}

// The derivatives, solved in the pencil. The shells energy and the paired modes are freed before
// the solves, where the bake's memory peaks (bench/results/bake_limit.json).
Eigen::MatrixXd derivative_stage(const Simulated& sim, Stiffness& stiffness, const FlexibleModes& modes,
                                 ShiftedPencil& pencil,
                                 BakeRun& run) {
  if (run.options.derivatives == 0) return Eigen::MatrixXd(3 * sim.size(), 0);
  Eigen::MatrixXd B =
      third_derivatives(*stiffness.shells, paired_modes(sim, pencil.kernel(), modes, run.options), sim.size(), run);
  stiffness.shells.reset();
  return pencil.solve_in_range(std::move(B), &run.progress);
}

// 7. [rigid motions, zero modes, modes, derivatives], M-orthonormal; derivatives that came out
// dependent are dropped (basis.num_dropped).
Eigen::MatrixXd orthonormal_basis(const Simulated& sim, const ShiftedPencil& pencil, const FlexibleModes& modes,
                                  Eigen::MatrixXd derivatives, BakeRun& run) {
  Basis& basis = run.basis;
  const Eigen::MatrixXd& kernel = pencil.kernel();  // the rigid motions, then the zero modes
  const auto leading = static_cast<int>(kernel.cols() + modes.flexible.cols());
  const Eigen::Index num_derivatives = derivatives.cols();
  Eigen::MatrixXd U(kernel.rows(), leading + num_derivatives);
  U << kernel, modes.flexible, derivatives;
  derivatives.resize(0, 0);
  {
    const Stopwatch stopwatch(basis.timings[stages::kOrthonormalisation]);
    const std::vector<int> kept = orthonormalize(U, dof_masses(sim.mass), kDependentTolerance, &run.progress);
    for (int j = 0; j < leading; ++j)
      if (j >= static_cast<int>(kept.size()) || kept[static_cast<size_t>(j)] != j)
        throw NumericalError(message("bake: column ", j, " of the rigid motions and modes came out dependent; ",
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
void fine_and_ghost_vectors(Eigen::MatrixXd U, const Simulated& sim, const MovingPart& source, Ghost coarse,
                            BakeRun& run) {
  Basis& basis = run.basis;
  const StiffnessPaint& paint = run.options.material.paint;
  run.stage(stages::kAssembly, [&] {
    if (U.rows() < basis.rest.size()) U = extend_to_attached(sim.attachment, U);
    U /= basis.scale;
    basis.vectors = U.cast<float>();
    const int g = static_cast<int>(coarse.V.rows());
    const std::vector<int>& sub = sim.region_vertices;
    if (sub.empty()) {
      basis.ghost_vectors = restrict_to_ghost(coarse, source.mass, U);
      basis.ghost_stiffness_weights = restrict_to_ghost(coarse.map, g, source.mass, paint).weights;
      basis.ghost_map = std::move(coarse.map);
    } else {
      Eigen::MatrixXd rows(3 * static_cast<Eigen::Index>(sub.size()), U.cols());
      for (size_t i = 0; i < sub.size(); ++i)
        rows.middleRows<3>(3 * static_cast<Eigen::Index>(i)) = U.middleRows<3>(3 * static_cast<Eigen::Index>(sub[i]));
      basis.ghost_vectors = restrict_to_ghost(coarse, source.mass, rows);
      StiffnessPaint on_submesh{Eigen::VectorXd(), paint.max_stiffness};
      if (paint.weights.size() > 0) on_submesh.weights = paint.weights(sub);
      basis.ghost_stiffness_weights = restrict_to_ghost(coarse.map, g, source.mass, on_submesh).weights;
      basis.ghost_map = Eigen::VectorXi::Zero(basis.rest.rows());
      basis.ghost_map(sub) = coarse.map;
    }
    basis.ghost_vertices = std::move(coarse.V);
    basis.ghost_faces = std::move(coarse.F);
  });
}

// The bake of (V, F) itself, stages 2 to 8 on the rest state `basis`, for a region bake in
// `region` (region_mesh of options.region; null for the whole mesh); errors name V's vertices by
// `name`.
Basis bake_stages(const VerticesRef& V, const FacesRef& F, const RegionMesh* region, const BakeOptions& options,
                  Basis basis, const VertexName& name, Progress& progress) {
  BakeRun run{options, basis, progress};
  const Simulated sim = simulated_submesh(V, F, region, run);
  Stiffness stiffness = stiffness_at_rest(sim, run);
  const MovingPart source(V, F, basis.mass, sim.region_vertices, sim.attachment.faces);
  ShiftedPencil pencil(stiffness.K, sim.mass,
                       sim.num_rigid > 0 ? rigid_motions(sim.V, sim.attachment.component, sim.mass)
                                         : Eigen::MatrixXd(3 * sim.size(), 0));
  Ghost coarse = order_beside_the_ghost(source, stiffness.K, pencil, run);
  const FlexibleModes modes = vibration_stage(name, sim, stiffness.K, pencil, run);
  Eigen::MatrixXd derivatives = derivative_stage(sim, stiffness, modes, pencil, run);
  const ShiftedPencil::Timings pencil_timings = pencil.timings();
  basis.timings[stages::kFactorisation] = pencil_timings.factorisation;
  basis.timings[stages::kModes] = pencil_timings.modes;
  if (options.derivatives > 0) basis.timings[stages::kDerivativeSolves] = pencil_timings.solves;
  Eigen::MatrixXd U = orthonormal_basis(sim, pencil, modes, std::move(derivatives), run);
  fine_and_ghost_vectors(std::move(U), sim, source, std::move(coarse), run);
  return basis;
}

// The proxy's region: the proxy vertices that only free vertices collapsed onto.
Eigen::VectorXi proxy_region(const Ghost& proxy, const RegionMesh& region) {
  std::vector<char> free(static_cast<size_t>(proxy.V.rows()), 0);
  for (Eigen::Index s = 0; s < region.num_free; ++s) free[proxy.map[s]] = 1;
  for (Eigen::Index s = region.num_free; s < proxy.map.size(); ++s) free[proxy.map[s]] = 0;
  std::vector<int> vertices;
  for (size_t p = 0; p < free.size(); ++p)
    if (free[p]) vertices.push_back(static_cast<int>(p));
  return Eigen::Map<const Eigen::VectorXi>(vertices.data(), static_cast<Eigen::Index>(vertices.size()));
}

// A dense mesh: the stages above on a proxy made by edge collapse to about options.proxy vertices
// of the part that moves (MovingPart; a region's free and clamped vertices stay apart, so the line
// between them stays in place), then the prolongation of the proxy's basis to the fine vertices
// (prolongation.h); the ghost is the proxy's, reached from a fine vertex through its proxy vertex.
// A region's proxy is baked as a region (its clamped vertices still), and every fine vertex but the
// region's free ones is held at rest by a prolongation of zero weights.
Basis bake_on_proxy(const VerticesRef& V, const FacesRef& F, const RegionMesh* region, const BakeOptions& options,
                    Basis fine, Progress& progress) {
  Basis timed;  // the proxy stage's time, until the proxy's basis exists
  Progress as_proxy([&progress](const std::string&, double fraction) {
    progress.report(stages::kProxy, fraction);
    return true;
  });
  const MovingPart source(V, F, fine.mass, region ? region->vertices : std::vector<int>(),
                          region ? FacesRef(region->faces) : F);
  std::vector<char> sides;  // a region's: 1 for its free vertices, 0 for the clamped ones
  if (region) {
    sides.assign(region->vertices.size(), 0);
    std::fill_n(sides.begin(), region->num_free, 1);
  }
  BakeRun proxy_run{options, timed, progress};
  const Ghost proxy = proxy_run.stage(stages::kProxy, [&] {
    return ghost_mesh(source.V, source.F, source.mass, options.proxy, &as_proxy, sides);
  });
  // The proxy's elements carry the fine paint's means (restrict_to_ghost).
  BakeOptions on_proxy = options;
  const int num_proxy = static_cast<int>(proxy.V.rows());
  StiffnessPaint paint = options.material.paint;
  if (region && paint.weights.size() > 0) paint.weights = paint.weights(region->vertices).eval();
  on_proxy.material.paint = restrict_to_ghost(proxy.map, num_proxy, source.mass, paint);
  // A region with nothing clamped around it (a free component) is its whole proxy.
  const bool clamped = region && region->num_free < static_cast<int>(region->vertices.size());
  on_proxy.region = clamped ? proxy_region(proxy, *region) : Eigen::VectorXi();
  Basis basis = rest_state(proxy.V, proxy.F, on_proxy, fine.scale);
  basis.timings = timed.timings;
  // A proxy vertex's index means nothing to the artist: errors name the nearest of its fine vertices.
  const VertexName fine_vertex = [&](int p) {
    const int s = nearest_fine_vertex(proxy, source.V, p);
    return message(vertex_at(V, region ? region->vertices[static_cast<size_t>(s)] : s),
                   ", the nearest of the mesh's vertices to the proxy's vertex ", p);
  };
  const RegionMesh proxy_region_mesh =
      clamped ? region_mesh(proxy.F, basis.mass, on_proxy.region) : RegionMesh();
  basis = bake_stages(proxy.V, proxy.F, clamped ? &proxy_region_mesh : nullptr, on_proxy, std::move(basis),
                      fine_vertex, progress);
  BakeRun{options, basis, progress}.stage(stages::kProlongation, [&] {
    Prolongation onto_proxy = prolongation_to_proxy(source.V, proxy.V, proxy.F, proxy.map);
    Eigen::VectorXi ghost_map = basis.ghost_map(proxy.map);
    if (!region) {
      basis.prolongation = std::move(onto_proxy);
      basis.ghost_map = std::move(ghost_map);
    } else {
      basis.prolongation = held_at_rest(V.rows());
      basis.ghost_map = Eigen::VectorXi::Zero(V.rows());
      for (int s = 0; s < region->num_free; ++s) {
        basis.prolongation.vertices.row(region->vertices[static_cast<size_t>(s)]) = onto_proxy.vertices.row(s);
        basis.prolongation.weights.row(region->vertices[static_cast<size_t>(s)]) = onto_proxy.weights.row(s);
      }
      basis.ghost_map(region->vertices) = ghost_map;
    }
    basis.rest = std::move(fine.rest);
    basis.mass = std::move(fine.mass);
    basis.material.paint.weights = std::move(fine.material.paint.weights);
    basis.region = std::move(fine.region);
  });
  return basis;
}

}  // namespace

Basis bake(const VerticesRef& V, const FacesRef& F, const BakeOptions& options, Progress& progress) {
  try {
    check_options(options, V.rows());
    validate_mesh(V, F);
    Basis fine = rest_state(V, F, options, normalizing_scale(V));
    const bool proxies = options.proxy_above > 0;
    const VertexName own_vertex = [&V](int vertex) { return vertex_at(V, vertex); };
    Basis basis;
    if (options.region.size() == 0) {
      basis = proxies && V.rows() > options.proxy_above
                  ? bake_on_proxy(V, F, nullptr, options, std::move(fine), progress)
                  : bake_stages(V, F, nullptr, options, std::move(fine), own_vertex, progress);
    } else {
      const RegionMesh region = region_mesh(F, fine.mass, options.region);
      basis = proxies && region.num_free > options.proxy_above
                  ? bake_on_proxy(V, F, &region, options, std::move(fine), progress)
                  : bake_stages(V, F, &region, options, std::move(fine), own_vertex, progress);
    }
    validate_basis(basis);
    return basis;
  } catch (const std::bad_alloc&) {
    throw OutOfMemory(message("bake: out of memory: an allocation failed (", available_memory() / 1e9,
                              " GB still available); close other programs, bake fewer modes and derivatives, "
                              "or decimate the mesh"));
  }
}

}  // namespace modal_deform
