// The corpus of bad and awkward meshes (tests/python/test_corpus.py's twin) through the native
// entry points, without the Python layer's checks: each works with finite results, or throws
// InputError whose message names the problem and where. docs/robustness.md lists the cases.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "bake/bake.h"
#include "energy/arap.h"
#include "energy/discrete_shells.h"
#include "mesh/mass.h"
#include "mesh/mesh_check.h"
#include "mesh/normalization.h"
#include "mesh/primitives.h"
#include "reduction/attachment.h"
#include "reduction/ghost.h"
#include "solve/full_solver.h"
#include "solve/reduced_solver.h"
#include "test_support.h"
#include "util/errors.h"
#include "util/math_constants.h"
#include "util/require_weight.h"

namespace modal_deform {
namespace {

using testing::expect_input_error;

TriangleMesh unit_grid() { return grid(3, 3, 1.0, 1.0); }

TriangleMesh with_vertices(TriangleMesh mesh, const RowMatrixX3d& extra) {
  const Eigen::Index n = mesh.V.rows();
  mesh.V.conservativeResize(n + extra.rows(), 3);
  mesh.V.bottomRows(extra.rows()) = extra;
  return mesh;
}

TriangleMesh with_face(TriangleMesh mesh, const Eigen::RowVector3i& face) {
  const Eigen::Index m = mesh.F.rows();
  mesh.F.conservativeResize(m + 1, 3);
  mesh.F.row(m) = face;
  return mesh;
}

// A triangle on the grid's first boundary edge whose apex sits `height` off it: a sliver that
// alone carries a vertex.
TriangleMesh sliver_flap(double height) {
  TriangleMesh mesh = unit_grid();
  const Eigen::RowVector3d apex =
      0.5 * (mesh.V.row(0) + mesh.V.row(1)) + Eigen::RowVector3d(0, -height, 0);
  const int n = static_cast<int>(mesh.V.rows());
  return with_face(with_vertices(mesh, apex), {1, 0, n});
}

// A wavy 6 by 6 grid whose face 30 has its third vertex moved to `height` above the midpoint of
// its first edge: a sliver inside the surface.
TriangleMesh inner_sliver(double height) {
  TriangleMesh mesh = grid(6, 6, 2.0, 2.0);
  for (Eigen::Index v = 0; v < mesh.V.rows(); ++v)
    mesh.V(v, 2) = 0.1 * std::sin(3 * mesh.V(v, 0)) * std::cos(2 * mesh.V(v, 1));
  const int p = mesh.F(30, 0), q = mesh.F(30, 1), r = mesh.F(30, 2);
  const Eigen::RowVector3d middle = 0.5 * (mesh.V.row(p) + mesh.V.row(q));
  mesh.V.row(r) = middle + height * (mesh.V.row(r) - middle).normalized();
  return mesh;
}

// Two fans of 5 triangles (cones) touching at their apex only: a non-manifold vertex.
TriangleMesh two_fans() {
  std::vector<double> positions{0, 0, 0};
  std::vector<int> faces;
  for (double side : {1.0, -1.0}) {
    const int ring = static_cast<int>(positions.size() / 3);
    for (int k = 0; k < 5; ++k) {
      const double angle = 2 * kPi * k / 5;
      positions.insert(positions.end(), {std::cos(angle), std::sin(angle), side});
    }
    for (int k = 0; k < 5; ++k) faces.insert(faces.end(), {0, ring + k, ring + (k + 1) % 5});
  }
  return mesh_from_buffers(positions, faces);
}

// A grid with a fin on an interior edge: a non-manifold edge with three faces.
TriangleMesh fin() {
  const TriangleMesh mesh = unit_grid();
  const int a = mesh.F(4, 0), b = mesh.F(4, 1), n = static_cast<int>(mesh.V.rows());
  const Eigen::RowVector3d top =
      0.5 * (mesh.V.row(a) + mesh.V.row(b)) + Eigen::RowVector3d(0, 0, 0.3);
  return with_face(with_vertices(mesh, top), {a, b, n});
}

// A grid with 20 small triangles floating beside it.
TriangleMesh debris() {
  TriangleMesh mesh = unit_grid();
  for (int k = 0; k < 20; ++k) {
    const int n = static_cast<int>(mesh.V.rows());
    RowMatrixX3d triangle(3, 3);
    triangle << 0, 0, 0, 0.01, 0, 0, 0, 0.01, 0.005;
    triangle.rowwise() += Eigen::RowVector3d(1.0 + 0.1 * k, 0.05 * (k % 7), 0.2);
    mesh = with_face(with_vertices(mesh, triangle), {n, n + 1, n + 2});
  }
  return mesh;
}

// The grid with a triangle `size` across floating above it.
TriangleMesh tiny_component(double size) {
  RowMatrixX3d triangle(3, 3);
  triangle << 0, 0, 0.5, size, 0, 0.5, 0, size, 0.5;
  const TriangleMesh mesh = unit_grid();
  const int n = static_cast<int>(mesh.V.rows());
  return with_face(with_vertices(mesh, triangle), {n, n + 1, n + 2});
}

TriangleMesh changed(TriangleMesh mesh, const std::function<void(TriangleMesh&)>& change) {
  change(mesh);
  return mesh;
}

struct MeshCase {
  std::string name;
  TriangleMesh mesh;
  const char* refusal;                         // nullptr: every entry point works
  std::map<std::string, const char*> entries;  // entry points with another outcome
};

constexpr const char* kWorks = nullptr;
constexpr const char* kNothingToSimulate = "F: every face is degenerate or a sliver";

std::vector<MeshCase> corpus() {
  const TriangleMesh g = unit_grid();
  const double nan = std::numeric_limits<double>::quiet_NaN(),
               inf = std::numeric_limits<double>::infinity();
  return {
      {"empty mesh", {RowMatrixX3d(0, 3), RowMatrixX3i(0, 3)}, "V: the mesh has no vertices", {}},
      {"vertices, no faces", {g.V, RowMatrixX3i(0, 3)}, "F: the mesh has no faces", {}},
      {"lone vertex in a face",
       {RowMatrixX3d::Zero(1, 3), RowMatrixX3i::Zero(1, 3)},
       "V: the mesh's extent",
       {}},
      {"one triangle", mesh_from_buffers({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2}), kWorks, {}},
      {"collinear faces",
       mesh_from_buffers({0, 0, 0, 1, 0, 0, 2, 0, 0, 3, 0, 0}, {0, 1, 2, 1, 2, 3}),
       kWorks,
       {{"bake", kNothingToSimulate}, {"pose", kNothingToSimulate}}},
      {"unreferenced vertices", with_vertices(g, RowMatrixX3d::Constant(2, 3, 5.0)), kWorks, {}},
      {"duplicate vertices",
       changed(with_vertices(g, g.V.row(5)),
               [](TriangleMesh& m) {
                 for (Eigen::Index f = 0; f < m.F.rows(); ++f)
                   if (m.F(f, 0) == 5) m.F(f, 0) = static_cast<int>(m.V.rows()) - 1;
               }),
       kWorks,
       {}},
      {"zero-area face", with_face(g, {0, 1, 2}), kWorks, {}},
      {"face with a repeated index", with_face(g, {0, 5, 5}), kWorks, {}},
      {"sliver flap (ratio 6e-9)", sliver_flap(1e-9), kWorks, {}},
      {"inner sliver (ratio 6e-6)", inner_sliver(1e-6), kWorks, {}},
      {"duplicate face", with_face(g, g.F.row(3)), kWorks, {}},
      {"double sheet", with_face(g, {g.F(3, 0), g.F(3, 2), g.F(3, 1)}), kWorks, {}},
      {"non-manifold edge", fin(), kWorks, {}},
      // Three zero modes from the cones' relative rotation: the bake deflates them and solves
      // again.
      {"non-manifold vertex", two_fans(), kWorks, {}},
      {"closed surface", bar(1, 1, 2, 1, 1, 4), kWorks, {}},
      {"many components (debris)", debris(), kWorks, {}},
      {"inverted faces",
       changed(g, [](TriangleMesh& m) { m.F.col(1).swap(m.F.col(2)); }),
       kWorks,
       {}},
      {"NaN coordinate",
       changed(g, [nan](TriangleMesh& m) { m.V(7, 1) = nan; }),
       "V[7]: vertex 7 has a non-finite",
       {}},
      {"infinite coordinate",
       changed(g, [inf](TriangleMesh& m) { m.V(3, 2) = -inf; }),
       "V[3]: vertex 3 has a non-finite",
       {}},
      {"tiny scale (1e-6)", changed(g, [](TriangleMesh& m) { m.V *= 1e-6; }), kWorks, {}},
      {"huge scale (1e6)", changed(g, [](TriangleMesh& m) { m.V *= 1e6; }), kWorks, {}},
      {"coordinate too large (1e200)",
       changed(g, [](TriangleMesh& m) { m.V(2, 0) = 1e200; }),
       "V[2]: vertex 2 has a coordinate too large",
       {}},
      {"extent too small (1e-200)",
       changed(g, [](TriangleMesh& m) { m.V *= 1e-200; }),
       "V: the mesh's extent",
       {}},
      {"a component 1e-20 the size of the mesh", tiny_component(1e-20), kWorks, {}},
      {"index out of range",
       changed(g, [](TriangleMesh& m) { m.F(4, 2) = 16; }),
       "F[4]: face 4 refers to vertex 16, outside [0, 16)",
       {}},
      {"negative index",
       changed(g, [](TriangleMesh& m) { m.F(2, 0) = std::numeric_limits<int>::min(); }),
       "F[2]: face 2 refers to vertex -2147483648",
       {}},
  };
}

void expect_finite(const Eigen::Ref<const Eigen::MatrixXd>& values, const std::string& what) {
  EXPECT_TRUE(values.allFinite()) << what;
}

Basis small_bake(const TriangleMesh& mesh) {
  BakeOptions options;
  options.modes = 8;
  options.derivatives = 3;
  options.ghost = 8;
  Progress progress;
  return bake(mesh.V, mesh.F, options, progress);
}

// One entry point on one mesh, checking what it returns.
void run(const std::string& entry, const TriangleMesh& mesh) {
  const auto n = static_cast<int>(mesh.V.rows());
  if (entry == "check") {
    EXPECT_EQ(check_mesh(mesh.V, mesh.F).num_vertices, n);
  } else if (entry == "mass") {
    validate_mesh(mesh.V, mesh.F);  // what mdc.mass does first
    const Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
    expect_finite(mass, "mass");
    EXPECT_GE(mass.minCoeff(), 0);
  } else if (entry == "shells" || entry == "arap") {
    std::unique_ptr<Energy> energy;
    if (entry == "shells")
      energy = std::make_unique<DiscreteShells>(mesh.V, mesh.F);
    else
      energy = std::make_unique<Arap>(mesh.V, mesh.F);
    const Eigen::VectorXd rest = energy->rest();
    const double extent = bounding_box_extent(mesh.V);
    for (const Eigen::VectorXd& x :
         {rest, Eigen::VectorXd(rest + 0.05 * extent * testing::random_vector(3 * n, 1))}) {
      Eigen::VectorXd gradient(3 * n);
      EXPECT_TRUE(std::isfinite(energy->value_and_gradient(x, gradient))) << entry;
      expect_finite(gradient, entry + " gradient");
      expect_finite(Eigen::MatrixXd(energy->hessian(x)), entry + " Hessian");
      if (entry == "shells")
        expect_finite(
            energy->third(x, testing::random_vector(3 * n, 2), testing::random_vector(3 * n, 3)),
            "third");
    }
  } else if (entry == "ghost") {
    validate_mesh(mesh.V, mesh.F);
    const Ghost ghost = ghost_mesh(mesh.V, mesh.F, lumped_mass(mesh.V, mesh.F), 4);
    expect_finite(ghost.V, "ghost");
    EXPECT_GE(ghost.map.minCoeff(), 0);
    EXPECT_LT(ghost.map.maxCoeff(), ghost.V.rows());
  } else if (entry == "bake") {
    const Basis basis = small_bake(mesh);
    expect_finite(basis.vectors.cast<double>(), "vectors");
  } else if (entry == "pose" || entry == "full") {
    const double extent = bounding_box_extent(mesh.V);
    Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
    T.topLeftCorner<3, 3>() = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    T(0, 3) = std::isfinite(extent) ? 0.1 * extent : 0.1;
    if (entry == "pose") {
      const Basis basis = small_bake(mesh);
      ReducedSolver solver(basis, {{0}}, Eigen::VectorXd(), 1e3);
      solver.set_transforms({T});
      EXPECT_TRUE(std::isfinite(solver.solve(10, 1e-6).energy));
      Eigen::VectorXf positions(3 * n);
      solver.positions(positions);
      expect_finite(positions.cast<double>(), "positions");
    } else {
      const FullSolveResult result =
          solve_full(mesh.V, mesh.F, {{0}}, Eigen::VectorXd(), {T}, 1e3,
                     FullSolveOptions{EnergyKind::kShells, {1, 1}, 1e-6, 10});
      expect_finite(result.positions, "solve_full");
    }
  }
}

TEST(Corpus, EveryMeshThroughEveryEntryPoint) {
  for (const MeshCase& c : corpus()) {
    for (const char* entry : {"check", "mass", "shells", "arap", "ghost", "bake", "pose", "full"}) {
      SCOPED_TRACE(c.name + " / " + entry);
      const auto it = c.entries.find(entry);
      const char* refusal = it != c.entries.end() ? it->second : c.refusal;
      if (refusal)
        expect_input_error([&] { run(entry, c.mesh); }, refusal);
      else
        EXPECT_NO_THROW(run(entry, c.mesh));
    }
  }
}

// Regression: a face 1e-9 thin made the bake's eigensolver fail (residuals, a shift too far
// below the modes) or let rounding decide the lowest modes; slivers are now attached, not
// simulated, and the eigenvalues match those of the mesh without the sliver.
TEST(Corpus, SliversAreNotSimulated) {
  const Basis clean = small_bake(unit_grid());
  const Basis flap = small_bake(sliver_flap(1e-9));
  EXPECT_EQ(attach(sliver_flap(1e-9).V, sliver_flap(1e-9).F).followers.size(), 1u);
  for (Eigen::Index i = 6; i < clean.eigenvalues.size(); ++i)
    EXPECT_NEAR(flap.eigenvalues[i], clean.eigenvalues[i], 1e-6 * clean.eigenvalues[i]);
  for (double height : {1e-9, 1e-7, 1e-5}) {
    const TriangleMesh mesh = inner_sliver(height);
    EXPECT_LT(face_shape_ratio(mesh.V, mesh.F, 30), kMinSimulatedShape);
    EXPECT_NO_THROW(small_bake(mesh)) << height;
  }
}

// Regression (fuzz_mesh_entry_points): a bending weight of 1.7e308 passed, and the shells energy
// at rest was NaN (inf · 0). Weights and stiffness are held to [0, kMaxWeight].
TEST(Corpus, WeightsBeyondTheLimitAreRefused) {
  TriangleMesh mesh = unit_grid();
  mesh.V *= 1e6;
  expect_input_error([&] { DiscreteShells(mesh.V, mesh.F, 1.7e308, 1); },
                     "bending: expected a finite weight >= 0 and at most 1e+12, got 1.7e+308");
  const DiscreteShells stiff(mesh.V, mesh.F, kMaxWeight, kMaxWeight);
  Eigen::VectorXd gradient(stiff.rest().size());
  EXPECT_EQ(stiff.value_and_gradient(stiff.rest(), gradient), 0);
  EXPECT_TRUE(gradient.allFinite());
  const Eigen::Matrix4d I = Eigen::Matrix4d::Identity();
  expect_input_error(
      [&] {
        solve_full(mesh.V, mesh.F, {{0}}, Eigen::VectorXd(), {I}, 1e300,
                   FullSolveOptions{EnergyKind::kShells, {1, 1}, 1e-6, 3});
      },
      "pull: expected a value in (0, 1e+12], got 1e+300");
  expect_input_error(
      [&] { checked_handle_weights({{0}}, Eigen::VectorXd::Constant(1, 1e300), 16); },
      "weights[0] = 1e+300 is not a finite number in [0, 1e+12]");
}

}  // namespace
}  // namespace modal_deform
