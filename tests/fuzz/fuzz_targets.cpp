#include "fuzz_targets.h"

#include <algorithm>
#include <string>
#include <vector>

#include "bake/bake.h"
#include "energy/arap.h"
#include "energy/discrete_shells.h"
#include "fuzz_input.h"
#include "mesh/mass.h"
#include "mesh/mesh_check.h"
#include "mesh/normalization.h"
#include "reduction/ghost.h"
#include "solve/full_solver.h"
#include "solve/reduced_solver.h"
#include "util/errors.h"
#include "util/require_positions.h"
#include "util/require_weight.h"

namespace modal_deform::fuzz {
namespace {

[[noreturn]] void fail(const std::string& what) { throw Failure(what); }

// Runs call(); true when it returned, false when it refused with InputError, NumericalError or
// OutOfMemory (the bake's up-front memory estimate; whose message must say something). Other
// exceptions propagate: they are failures.
template <typename Call>
bool runs(const char* what, Call&& call) {
  try {
    call();
    return true;
  } catch (const InputError& error) {
    if (std::string(error.what()).empty()) fail(message(what, ": InputError without a message"));
  } catch (const NumericalError& error) {
    if (std::string(error.what()).empty())
      fail(message(what, ": NumericalError without a message"));
  } catch (const OutOfMemory& error) {
    if (std::string(error.what()).empty()) fail(message(what, ": OutOfMemory without a message"));
  }
  return false;
}

// Like runs, for calls that must not refuse input that passed validation.
template <typename Call>
void must_run(const char* what, Call&& call) {
  try {
    call();
  } catch (const std::exception& error) {
    fail(message(what, " refused input it must accept: ", error.what()));
  }
}

template <typename Matrix>
void require_finite(const Matrix& values, const char* what) {
  if (!values.allFinite()) fail(message(what, ": not finite"));
}

void require_finite(double value, const char* what) {
  if (!std::isfinite(value)) fail(message(what, ": not finite (", value, ")"));
}

void require_finite(const SparseMatrix& matrix, const char* what) {
  require_finite(Eigen::Map<const Eigen::VectorXd>(matrix.valuePtr(), matrix.nonZeros()), what);
}

bool valid_mesh(const TriangleMesh& mesh) {
  try {
    validate_mesh(mesh.V, mesh.F);
    return true;
  } catch (const InputError&) {
    return false;
  }
}

// Positions to evaluate an energy at: near rest, far from rest, collapsed, or with an awkward
// coordinate.
Eigen::VectorXd fuzz_positions(FuzzInput& in, const Eigen::VectorXd& rest) {
  Eigen::VectorXd x = rest;
  switch (in.byte() % 4) {
    case 0:
      for (Eigen::Index i = 0; i < x.size(); ++i) x[i] += 0.1 * in.number();
      break;
    case 1:
      x *= in.number();
      break;
    case 2:
      x.setZero();
      break;
    default:
      if (x.size()) {
        const double value = in.number();
        x[in.integer(0, static_cast<int>(x.size()) - 1)] = value;
      }
      break;
  }
  return x;
}

void energy_at(const Energy& energy, const Eigen::VectorXd& x, FuzzInput& in, bool has_third) {
  // The energies take finite coordinates up to kMaxCoordinate in magnitude, and refuse the rest.
  const bool in_range = positions_in_range(x);
  const bool accepted = runs("Energy::value", [&] { require_finite(energy.value(x), "E(x)"); });
  if (accepted != in_range)
    fail(message("Energy::value accepted = ", accepted, " for in range = ", in_range));
  if (!in_range) return;
  Eigen::VectorXd gradient(x.size());
  must_run("Energy::value_and_gradient", [&] {
    require_finite(energy.value_and_gradient(x, gradient), "E(x)");
    require_finite(gradient, "gradient");
  });
  must_run("Energy::hessian", [&] {
    const SparseMatrix H = energy.hessian(x);
    require_finite(H, "Hessian");
    if (H.rows() != x.size() || H.cols() != x.size()) fail("Hessian of the wrong size");
  });
  Eigen::VectorXd u(x.size()), w(x.size());
  for (Eigen::Index i = 0; i < x.size(); ++i) u[i] = in.number(), w[i] = in.number();
  if (!has_third) {
    if (runs("Energy::third", [&] { energy.third(x, u, w); }))
      fail("ARAP computed a third derivative");
    return;
  }
  const bool third_accepted =
      runs("Energy::third", [&] { require_finite(energy.third(x, u, w), "third"); });
  if (third_accepted != (positions_in_range(u) && positions_in_range(w)))
    fail("third: accepted a direction out of range or refused one in range");
}

}  // namespace

void mesh_entry_points(const std::uint8_t* data, std::size_t size) {
  FuzzInput in(data, size);
  const TriangleMesh mesh = fuzz_mesh(in, 24, 40);
  const bool valid = valid_mesh(mesh);
  const bool checked = runs("check_mesh", [&] {
    const MeshReport report = check_mesh(mesh.V, mesh.F);
    if (report.num_vertices != mesh.V.rows() || report.num_faces != mesh.F.rows())
      fail("check_mesh: wrong counts");
  });
  if (checked != valid)
    fail(message("check_mesh accepted = ", checked, " but validate_mesh accepted = ", valid));
  if (!valid) return;

  const Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
  require_finite(mass, "lumped_mass");
  if ((mass.array() < 0).any()) fail("lumped_mass: a negative mass");

  const double bending = in.positive(), membrane = in.positive();
  const bool weights_valid =
      bending >= 0 && bending <= kMaxWeight && membrane >= 0 && membrane <= kMaxWeight;
  std::unique_ptr<DiscreteShells> shells;
  const bool built = runs("DiscreteShells", [&] {
    shells = std::make_unique<DiscreteShells>(mesh.V, mesh.F, bending, membrane);
  });
  if (built != weights_valid)
    fail(message("DiscreteShells built = ", built, " for weights ", bending, ", ", membrane));
  std::unique_ptr<Arap> arap;
  must_run("Arap", [&] { arap = std::make_unique<Arap>(mesh.V, mesh.F); });

  if (shells) {
    Eigen::VectorXd gradient(shells->rest().size());
    const double at_rest = shells->value_and_gradient(shells->rest(), gradient);
    if (at_rest != 0 || !gradient.isZero(0))
      fail(message("shells: E(rest) = ", at_rest, ", |gradient| = ", gradient.norm()));
    energy_at(*shells, shells->rest(), in, true);
    energy_at(*shells, fuzz_positions(in, shells->rest()), in, true);
  }
  energy_at(*arap, arap->rest(), in, false);
  energy_at(*arap, fuzz_positions(in, arap->rest()), in, false);

  const int target = in.integer(0, static_cast<int>(mesh.V.rows()) + 2);
  Ghost ghost;
  try {
    ghost = ghost_mesh(mesh.V, mesh.F, mass, target);
  } catch (const InputError& error) {
    // On a valid mesh and masses, only a target below 4 or a mesh whose faces all repeat an index
    // or cancel in oppositely oriented pairs may be refused.
    if (target >= 4 && std::string(error.what()).find("no triangle is left") == std::string::npos)
      fail(message("ghost_mesh refused a valid mesh: ", error.what()));
    return;
  }
  const auto g = static_cast<int>(ghost.V.rows());
  require_finite(ghost.V, "ghost vertices");
  if (ghost.map.size() != mesh.V.rows()) fail("ghost map of the wrong size");
  std::vector<int> preimage(g, 0);
  for (Eigen::Index v = 0; v < ghost.map.size(); ++v) {
    if (ghost.map[v] < 0 || ghost.map[v] >= g)
      fail(message("ghost map[", v, "] = ", ghost.map[v], " out of range"));
    ++preimage[ghost.map[v]];
  }
  if (std::count(preimage.begin(), preimage.end(), 0)) fail("a ghost vertex without fine vertices");
  if (ghost.F.size() && (ghost.F.minCoeff() < 0 || ghost.F.maxCoeff() >= g))
    fail("ghost face index out of range");
}

void bake_and_pose(const std::uint8_t* data, std::size_t size) {
  FuzzInput in(data, size);
  const TriangleMesh mesh = fuzz_mesh(in, 14, 24);
  BakeOptions options;
  options.modes = in.integer(0, 24);
  options.derivatives = in.integer(0, 12);
  if (in.byte() == 255) options.derivatives -= 1;  // -1 reachable
  options.ghost = in.integer(3, 20);
  options.energy = in.flag() ? EnergyKind::kArap : EnergyKind::kShells;
  if (options.energy == EnergyKind::kArap && in.byte() < 200) options.derivatives = 0;
  options.material.bending = in.positive();
  options.material.membrane = in.positive();
  Progress progress;
  Basis basis;
  if (!runs("bake", [&] { basis = bake(mesh.V, mesh.F, options, progress); })) return;
  must_run("validate_basis", [&] { validate_basis(basis); });
  // Ascending past the rigid motions and the zero modes (whose eigenvalues are rounding noise).
  for (Eigen::Index i = basis.num_rigid + basis.num_floppy + 1; i < basis.eigenvalues.size(); ++i)
    if (basis.eigenvalues[i] < basis.eigenvalues[i - 1]) fail("bake: eigenvalues not ascending");

  const Handles handles = fuzz_handles(in, basis.num_vertices(), 3, 5);
  Eigen::VectorXd weights(in.flag() ? 0 : static_cast<Eigen::Index>(handles.size()));
  for (Eigen::Index h = 0; h < weights.size(); ++h) weights[h] = in.positive();
  const double stiffness = in.positive();
  const EnergyKind kind = in.flag() ? EnergyKind::kArap : EnergyKind::kShells;
  const Transforms transforms = fuzz_transforms(in, static_cast<int>(handles.size()));
  const int iterations = in.integer(0, 8);
  const double tolerance = in.byte() < 200 ? 1e-6 : in.number();

  std::unique_ptr<ReducedSolver> solver;
  if (runs("ReducedSolver", [&] {
        solver = std::make_unique<ReducedSolver>(basis, handles, weights, stiffness, kind);
      })) {
    if (runs("set_transforms", [&] { solver->set_transforms(transforms); })) {
      runs("solve", [&] {
        const ReducedSolveStats stats = solver->solve(iterations, tolerance);
        require_finite(stats.energy, "solve: energy");
        require_finite(solver->q(), "solve: q");
      });
    }
    Eigen::VectorXf positions(3 * basis.num_vertices());
    runs("positions", [&] {
      solver->positions(positions);
      require_finite(positions, "positions");
    });
  }
  runs("solve_full", [&] {
    const FullSolveResult result = solve_full(
        mesh.V, mesh.F, handles, weights, transforms, stiffness,
        FullSolveOptions{
            kind, {options.material.bending, options.material.membrane}, tolerance, iterations});
    require_finite(result.positions, "solve_full: positions");
    require_finite(result.energy, "solve_full: energy");
  });
}

void stored_basis(const std::uint8_t* data, std::size_t size) {
  FuzzInput in(data, size);
  // Mostly consistent shapes (so the solver is reached), each one off now and then.
  auto off = [&in] { return in.byte() > 245 ? in.integer(-1, 1) : 0; };
  const int n = in.integer(0, 8), r = in.integer(0, 6), g = in.integer(0, 6), h = in.integer(0, 6);
  // Now and then a multiresolution bake's basis: vectors over p proxy vertices, and each fine
  // vertex a mostly barycentric combination of three of them (reduction/prolongation.h).
  const bool proxy = in.byte() > 200;
  const int p = proxy ? in.integer(1, 5) : n;
  Basis b;
  b.rest.resize(std::max(0, n + off()), 3);
  for (Eigen::Index i = 0; i < b.rest.size(); ++i) b.rest.data()[i] = in.number();
  b.mass.resize(std::max(0, n + off()));
  for (Eigen::Index i = 0; i < b.mass.size(); ++i) b.mass[i] = in.positive();
  b.vectors.resize(std::max(0, 3 * p + off()), std::max(0, r + off()));
  for (Eigen::Index i = 0; i < b.vectors.size(); ++i)
    b.vectors.data()[i] = static_cast<float>(in.number());
  if (proxy) {
    Prolongation& P = b.prolongation;
    P.vertices.resize(std::max(0, n + off()), 3);
    P.weights.resize(std::max(0, static_cast<int>(P.vertices.rows()) + off()), 3);
    for (Eigen::Index i = 0; i < P.vertices.size(); ++i) P.vertices.data()[i] = vertex_index(in, p);
    for (Eigen::Index i = 0; i < P.weights.rows(); ++i) {
      for (int k = 0; k < 3; ++k)
        P.weights(i, k) = static_cast<float>(in.byte() > 250 ? in.number() : in.positive());
      if (in.byte() < 240) P.weights.row(i) /= P.weights.row(i).sum();
    }
  }
  // The fine rows of vectors at vertex v when the prolongation has them in range, else none.
  const auto fine_rows = [&b, p](Eigen::Index v) -> Eigen::MatrixXd {
    if (!b.on_proxy()) return b.vectors.middleRows(3 * v, 3).cast<double>();
    const Prolongation& P = b.prolongation;
    if (v >= P.vertices.rows() || v >= P.weights.rows() || (P.vertices.row(v).array() < 0).any() ||
        (P.vertices.row(v).array() >= std::min<Eigen::Index>(p, b.vectors.rows() / 3)).any())
      return Eigen::MatrixXd::Zero(3, b.vectors.cols());
    return b.vertex_rows(static_cast<int>(v));
  };
  b.num_rigid = in.integer(-1, r + 1);
  b.num_modes = in.integer(-1, r + 1);
  b.num_floppy = in.integer(-1, 2);
  b.eigenvalues.resize(std::max(0, b.num_modes + off()));
  for (Eigen::Index i = 0; i < b.eigenvalues.size(); ++i) b.eigenvalues[i] = in.number();
  // Mostly what a bake stores (ghost vertices and vectors copied from fine ones, the normalising
  // scale), so validate_basis passes and the solver is reached; otherwise anything.
  const bool baked = in.byte() < 192 && n > 0 && b.rest.rows() == n && b.vectors.rows() == 3 * p;
  b.ghost_vertices.resize(std::max(0, g + off()), 3);
  b.ghost_vectors.resize(std::max(0, 3 * g + off()), std::max(0, r + off()));
  b.ghost_vectors.setZero();
  for (Eigen::Index i = 0; i < b.ghost_vertices.rows(); ++i) {
    if (!baked) {
      for (int c = 0; c < 3; ++c) b.ghost_vertices(i, c) = in.number();
      continue;
    }
    const int of = in.integer(0, static_cast<int>(b.rest.rows()) - 1);
    b.ghost_vertices.row(i) = b.rest.row(of);
    const Eigen::MatrixXd rows = fine_rows(of);
    for (Eigen::Index k = 3 * i; k < std::min<Eigen::Index>(3 * i + 3, b.ghost_vectors.rows()); ++k)
      for (Eigen::Index j = 0; j < std::min(b.ghost_vectors.cols(), b.vectors.cols()); ++j)
        b.ghost_vectors(k, j) = rows(k - 3 * i, j);
  }
  if (!baked)
    for (Eigen::Index i = 0; i < b.ghost_vectors.size(); ++i)
      b.ghost_vectors.data()[i] = in.number();
  b.ghost_faces.resize(std::max(0, h + off()), 3);
  for (Eigen::Index i = 0; i < b.ghost_faces.size(); ++i)
    b.ghost_faces.data()[i] = vertex_index(in, g);
  b.ghost_map.resize(std::max(0, n + off()));
  for (Eigen::Index i = 0; i < b.ghost_map.size(); ++i) b.ghost_map[i] = vertex_index(in, g);
  const double extent = bounding_box_extent(b.rest);
  b.scale = baked && in.byte() < 240 && extent > 0 ? kNormalizedExtent / extent : in.positive();
  b.material.bending = in.positive();
  b.material.membrane = in.positive();
  b.num_dropped = in.integer(-1, 1);
  // Now and then painted (weights mostly in [0, 1], on the fine mesh and the ghost) or baked in a
  // region (mostly ascending vertices, the rows outside mostly zero).
  const auto weight = [&in] { return in.byte() > 250 ? in.number() : in.byte() / 255.0; };
  if (in.byte() > 220) {
    b.material.paint.weights.resize(std::max(0, n + off()));
    for (Eigen::Index i = 0; i < b.material.paint.weights.size(); ++i)
      b.material.paint.weights[i] = weight();
    b.ghost_stiffness_weights.resize(std::max(0, g + off()));
    for (Eigen::Index i = 0; i < b.ghost_stiffness_weights.size(); ++i)
      b.ghost_stiffness_weights[i] = weight();
    b.material.paint.max_stiffness = in.byte() > 250 ? in.number() : 1.0 + in.byte();
  }
  if (in.byte() > 220 && n > 0) {
    std::vector<int> region;
    for (int v = 0; v < n; ++v)
      if (in.flag()) region.push_back(in.byte() > 250 ? in.integer(-1, n) : v);
    b.region =
        Eigen::Map<const Eigen::VectorXi>(region.data(), static_cast<Eigen::Index>(region.size()));
    for (int v = 0; v < n && b.vectors.rows() == 3 * n; ++v)
      if (!std::binary_search(region.begin(), region.end(), v) && in.byte() < 250)
        b.vectors.middleRows(3 * v, 3).setZero();
  }
  if (!runs("validate_basis", [&] { validate_basis(b); })) return;

  const Handles handles = fuzz_handles(in, n, 2, 4);
  const double stiffness = in.positive();
  const EnergyKind kind = in.flag() ? EnergyKind::kArap : EnergyKind::kShells;
  const Transforms transforms = fuzz_transforms(in, static_cast<int>(handles.size()));
  std::unique_ptr<ReducedSolver> solver;
  if (!runs("ReducedSolver", [&] {
        solver = std::make_unique<ReducedSolver>(b, handles, Eigen::VectorXd(), stiffness, kind);
      }))
    return;
  if (runs("set_transforms", [&] { solver->set_transforms(transforms); })) {
    runs("solve", [&] {
      const ReducedSolveStats stats = solver->solve(in.integer(0, 8), 1e-6);
      require_finite(stats.energy, "solve: energy");
      require_finite(solver->q(), "solve: q");
    });
  }
  Eigen::VectorXf positions(3 * n);
  runs("positions", [&] {
    solver->positions(positions);
    require_finite(positions, "positions");
  });
}

}  // namespace modal_deform::fuzz
