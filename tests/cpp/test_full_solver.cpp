#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

#include "mesh/mass.h"
#include "mesh/normalization.h"
#include "mesh/primitives.h"
#include "solve/full_solver.h"
#include "solve/pose_objective.h"
#include "solve/reduced_solver.h"
#include "solve/relax_stretched.h"
#include "test_posing.h"
#include "test_support.h"
#include "util/errors.h"
#include "util/math_constants.h"

namespace modal_deform {
namespace {

using testing::dense_modal_basis;
using testing::rigid_transform;
using testing::SmallTube;
using testing::vertices_where;

double rms(const RowMatrixX3d& a, const RowMatrixX3d& b) {
  return std::sqrt((a - b).rowwise().squaredNorm().mean());
}

TEST(SolveFull, ConvergesToAStationaryPointWithTheHandlesNearTheirTargets) {
  const SmallTube tube;
  for (EnergyKind kind : {EnergyKind::kShells, EnergyKind::kArap}) {
    const FullSolveResult result =
        solve_full(tube.mesh.V, tube.mesh.F, tube.handles, Eigen::VectorXd(), tube.transforms, 1e3,
                   FullSolveOptions{kind, {1.0, 1.0}, 1e-10, 100});
    ASSERT_TRUE(result.converged) << "iterations " << result.iterations;
    EXPECT_LE(result.gradient_norm, 1e-10 * result.gradient_scale);
    EXPECT_TRUE(result.positions.allFinite());
    for (int v : tube.handles[1]) {
      const Eigen::Vector3d target =
          tube.transforms[1].topLeftCorner<3, 3>() * tube.mesh.V.row(v).transpose() +
          tube.transforms[1].topRightCorner<3, 1>();
      EXPECT_LE((result.positions.row(v).transpose() - target).norm(), 0.05) << "vertex " << v;
    }
    std::printf("solve_full %s: %d iterations, %d factorisations, F = %.6g\n",
                kind == EnergyKind::kShells ? "shells" : "arap", result.iterations,
                result.factorizations, result.energy);
  }
}

TEST(SolveFull, HandlesAtRestLeaveTheMeshAtRest) {
  const SmallTube tube;
  const Transforms identity(2, Eigen::Matrix4d::Identity());
  const FullSolveResult result =
      solve_full(tube.mesh.V, tube.mesh.F, tube.handles, Eigen::VectorXd(), identity, 1e3,
                 FullSolveOptions{EnergyKind::kShells, {1.0, 1.0}, 1e-8, 20});
  EXPECT_TRUE(result.converged);
  EXPECT_EQ(result.iterations, 0);
  EXPECT_LE((result.positions - tube.mesh.V).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(SolveFull, EqualsTheReducedSolveInAFullBasis) {
  const SmallTube tube;
  const int r = 3 * static_cast<int>(tube.mesh.V.rows());
  const Basis basis = dense_modal_basis(tube.mesh, r);
  for (EnergyKind kind : {EnergyKind::kShells, EnergyKind::kArap}) {
    const FullSolveResult full =
        solve_full(tube.mesh.V, tube.mesh.F, tube.handles, Eigen::VectorXd(), tube.transforms, 1e3,
                   FullSolveOptions{kind, {1.0, 1.0}, 1e-12, 100});
    ASSERT_TRUE(full.converged);
    ReducedSolver solver(basis, tube.handles, Eigen::VectorXd(), 1e3, kind);
    solver.set_transforms(tube.transforms);
    ReducedSolveStats stats;
    for (int call = 0; call < 100 && !stats.converged; ++call) stats = solver.solve(10, 1e-15);
    Eigen::VectorXf x(3 * basis.num_vertices());
    solver.positions(x);
    const RowMatrixX3d reduced =
        Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>>(
            x.data(), basis.num_vertices(), 3)
            .cast<double>();
    const double diagonal =
        (full.positions.colwise().maxCoeff() - full.positions.colwise().minCoeff()).norm();
    const double error = rms(reduced, full.positions) / diagonal;
    std::printf(
        "full basis (%d), %s: vertex RMS %.2e of the diagonal; F reduced %.12g, full %.12g\n", r,
        kind == EnergyKind::kShells ? "shells" : "arap", error, stats.energy, full.energy);
    EXPECT_LE(error, 1e-5);
    EXPECT_NEAR(stats.energy, full.energy, 1e-6 * full.energy);
  }
}

// A quarter turn from rest in load steps (the first of 30°): the same answer as three solves from
// the previous step's answer, and a twisted bar, not one crumpled by pulls through its axis.
TEST(SolveFull, LargeMotionsAreTakenInSteps) {
  const TriangleMesh mesh = bar(3, 3, 12, 1, 1, 4);
  const Handles handles = {
      vertices_where(mesh.V, [](const Eigen::Vector3d& x) { return x.z() < 1e-9; }),
      vertices_where(mesh.V, [](const Eigen::Vector3d& x) { return x.z() > 4 - 1e-9; })};
  auto turn = [](double angle) {
    return Transforms{Eigen::Matrix4d::Identity(),
                      rigid_transform({0, 0, 1}, angle, {0.5, 0.5, 0}, {0, 0, 0})};
  };
  const double pi = kPi;
  const FullSolveResult stepped =
      solve_full(mesh.V, mesh.F, handles, Eigen::VectorXd(), turn(pi / 2), 1e3,
                 FullSolveOptions{EnergyKind::kShells, {1, 1}, 1e-9, 100});
  EXPECT_TRUE(stepped.converged);
  EXPECT_GE(stepped.steps, 2);
  RowMatrixX3d X = mesh.V;
  for (int step = 1; step <= 3; ++step)
    X = solve_full(mesh.V, mesh.F, handles, Eigen::VectorXd(), turn(pi / 2 * step / 3), 1e3,
                   FullSolveOptions{EnergyKind::kShells, {1, 1}, 1e-9, 100}, &X)
            .positions;
  EXPECT_LE((stepped.positions - X).cwiseAbs().maxCoeff(), 1e-6);
  // Mid-bar, the cross-section has turned by about 45° and kept its size.
  const std::vector<int> middle = vertices_where(mesh.V, [](const Eigen::Vector3d& x) {
    return std::abs(x.z() - 2) < 1e-9 && x.x() < 1e-9 && x.y() < 1e-9;
  });
  ASSERT_EQ(middle.size(), 1u);
  const Eigen::Vector2d corner = X.row(middle[0]).head<2>().transpose() - Eigen::Vector2d(0.5, 0.5);
  EXPECT_NEAR(corner.norm(), std::sqrt(0.5), 0.1);  // a twist pulls the corners in a little
  EXPECT_NEAR(std::atan2(corner.y(), corner.x()), std::atan2(-0.5, -0.5) + pi / 4, 0.1);
}

// The iterations whose step came from a new factorisation (the others reused an older factor).
int factored_iterations(const FullSolveResult& result) {
  return static_cast<int>(
      std::count_if(result.history.begin(), result.history.end(),
                    [](const NewtonIteration& it) { return it.cg_iterations == 0; }));
}

// Started crushed to half its height, the tube's Hessian is indefinite (compressed edges buckle
// sideways). The shells take the projected Hessian there, which factors at once: one
// factorisation per iteration that factors. ARAP has no projection: its Hessian is shifted until
// it factors.
TEST(SolveFull, AnIndefiniteHessianIsProjectedOrShifted) {
  const SmallTube tube;
  RowMatrixX3d crushed = tube.mesh.V;
  crushed.col(2) *= 0.5;
  for (EnergyKind kind : {EnergyKind::kShells, EnergyKind::kArap}) {
    const FullSolveResult result =
        solve_full(tube.mesh.V, tube.mesh.F, tube.handles, Eigen::VectorXd(),
                   Transforms(2, Eigen::Matrix4d::Identity()), 1e3,
                   FullSolveOptions{kind, {1, 1}, 1e-10, 200}, &crushed);
    EXPECT_TRUE(result.converged);
    if (kind == EnergyKind::kShells) {
      EXPECT_EQ(result.factorizations, factored_iterations(result));
      EXPECT_LT(factored_iterations(result),
                result.iterations);  // later Newton systems by the older factor
    } else {
      EXPECT_GT(result.factorizations, factored_iterations(result));
    }
    EXPECT_LE((result.positions - tube.mesh.V).cwiseAbs().maxCoeff(), 1e-6);
  }
}

TEST(SolveFull, UnreferencedVerticesStayAtRest) {
  SmallTube tube;
  const int loose = static_cast<int>(tube.mesh.V.rows());
  tube.mesh.V.conservativeResize(loose + 1, 3);
  tube.mesh.V.row(loose) << 5, 5, 5;
  const FullSolveResult result =
      solve_full(tube.mesh.V, tube.mesh.F, tube.handles, Eigen::VectorXd(), tube.transforms, 1e3,
                 FullSolveOptions{EnergyKind::kShells, {1.0, 1.0}, 1e-10, 100});
  EXPECT_TRUE(result.converged);
  EXPECT_LE((result.positions.row(loose) - tube.mesh.V.row(loose)).norm(), 1e-14);
}

// The objective around a few vertices differs from the whole one by a constant over their
// coordinates: same change of F and same gradient there, with painted stiffness, a handle among
// them and transforms that move it.
TEST(PoseObjective, AroundFewVerticesIsTheObjectiveOfTheirCoordinates) {
  const SmallTube tube;
  const int n = static_cast<int>(tube.mesh.V.rows());
  const StiffnessPaint paint{Eigen::VectorXd::LinSpaced(n, 0, 1), 10};
  for (EnergyKind kind : {EnergyKind::kShells, EnergyKind::kArap}) {
    PoseObjective whole(tube.mesh.V, tube.mesh.F, tube.handles, Eigen::Vector2d(1, 0.5), 1e3, kind,
                        Material{1, 2, kind == EnergyKind::kShells ? paint : StiffnessPaint{}});
    whole.set_transforms(tube.transforms);
    const std::vector<int> free = {7, 12, tube.handles[1][2]};
    std::vector<int> vertices;
    const PoseObjective local = whole.around(free, vertices);
    ASSERT_LT(vertices.size(), static_cast<size_t>(n));
    const Eigen::VectorXd y = whole.rest_positions() + 0.05 * Eigen::VectorXd::Random(3 * n);
    Eigen::VectorXd moved = y;
    for (int v : free) moved.segment<3>(3 * v) += Eigen::Vector3d(0.03, -0.02, 0.04);
    auto restrict = [&](const Eigen::VectorXd& full) {
      Eigen::VectorXd part(3 * vertices.size());
      for (size_t i = 0; i < vertices.size(); ++i)
        part.segment<3>(3 * static_cast<Eigen::Index>(i)) = full.segment<3>(3 * vertices[i]);
      return part;
    };
    Eigen::VectorXd g_whole(3 * n), g_moved(3 * n), g_local(3 * vertices.size()),
        g_local_moved(3 * vertices.size());
    const double change = whole(moved, g_moved) - whole(y, g_whole);
    const double local_change = local(restrict(moved), g_local_moved) - local(restrict(y), g_local);
    EXPECT_NEAR(local_change, change, 1e-9 * std::abs(change));
    for (size_t i = 0; i < vertices.size(); ++i) {
      const bool is_free = std::find(free.begin(), free.end(), vertices[i]) != free.end();
      const Eigen::Vector3d expected =
          is_free ? Eigen::Vector3d(g_whole.segment<3>(3 * vertices[i])) : Eigen::Vector3d::Zero();
      EXPECT_LE((g_local.segment<3>(3 * static_cast<Eigen::Index>(i)) - expected).norm(),
                1e-9 * g_whole.norm())
          << "vertex " << vertices[i];
    }
  }
}

// The turning point along a step is where turns_a_triangle_over starts to say so: a vertex pushed
// through the opposite edge of one triangle (linear in α), and a random step on the tube
// (quadratic).
TEST(PoseObjective, StepToTurningIsWhereTheFirstTriangleTurnsOver) {
  const SmallTube tube;
  const int n = static_cast<int>(tube.mesh.V.rows());
  const PoseObjective objective(tube.mesh.V, tube.mesh.F, tube.handles, Eigen::VectorXd::Ones(2),
                                1e3, EnergyKind::kShells, Material{1, 1, StiffnessPaint{}});
  const Eigen::VectorXd y = objective.rest_positions();
  const int a = tube.mesh.F(0, 0), b = tube.mesh.F(0, 1), c = tube.mesh.F(0, 2);
  // Moving a by twice its height over bc flattens the triangle halfway, at α = 1/2 (its neighbours
  // sharing a turn no sooner: a moves within their plane or away from it less steeply).
  const Eigen::Vector3d pa = y.segment<3>(3 * a), pb = y.segment<3>(3 * b),
                        pc = y.segment<3>(3 * c);
  const Eigen::Vector3d along = (pc - pb).normalized();
  const Eigen::Vector3d foot = pb + along * along.dot(pa - pb);
  Eigen::VectorXd p = Eigen::VectorXd::Zero(3 * n);
  p.segment<3>(3 * a) = 2 * (foot - pa);
  const double turning = objective.step_to_turning(y, p);
  EXPECT_LE(turning, 0.5 + 1e-12);
  EXPECT_FALSE(objective.turns_a_triangle_over(y, y + 0.999 * turning * p));
  EXPECT_TRUE(objective.turns_a_triangle_over(y, y + 1.001 * turning * p));

  std::srand(3);
  const Eigen::VectorXd random = Eigen::VectorXd::Random(3 * n);
  const double random_turning = objective.step_to_turning(y, random);
  ASSERT_TRUE(std::isfinite(random_turning));
  EXPECT_FALSE(objective.turns_a_triangle_over(y, y + 0.999 * random_turning * random));
  EXPECT_TRUE(objective.turns_a_triangle_over(y, y + 1.001 * random_turning * random));
  EXPECT_EQ(objective.step_to_turning(y, Eigen::VectorXd::Zero(3 * n)),
            std::numeric_limits<double>::infinity());
}

// A face of zero area at rest (a scan's sliver) has no orientation to keep: once a step has given
// it an area, the next may turn it over. The ordinary face beside it is still guarded.
TEST(PoseObjective, FaceDegenerateAtRestIsNotGuarded) {
  RowMatrixX3d V(6, 3);
  V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 2, 0, 0, 3, 0, 0, 2.5, 0, 0;  // face 1: vertex 5 on the side 3-4
  RowMatrixX3i F(2, 3);
  F << 0, 1, 2, 3, 4, 5;
  const PoseObjective objective(V, F, Handles{{0}}, Eigen::VectorXd::Ones(1), 1e3,
                                EnergyKind::kShells, Material{1, 1, StiffnessPaint{}});
  Eigen::VectorXd y = objective.rest_positions(), p = Eigen::VectorXd::Zero(18);
  y[3 * 5 + 1] += 0.1;  // the sliver lifted into a triangle
  p[3 * 5 + 1] = -0.2;  // and lowered through its side at α = 1/2
  EXPECT_EQ(objective.step_to_turning(y, p), std::numeric_limits<double>::infinity());
  EXPECT_FALSE(objective.turns_a_triangle_over(y, y + p));
  p[3 * 2 + 1] = -2 * y[3 * 2 + 1];  // vertex 2 through the side 0-1, also at α = 1/2
  EXPECT_NEAR(objective.step_to_turning(y, p), 0.5, 1e-12);
  EXPECT_TRUE(objective.turns_a_triangle_over(y, y + p));
}

// The shift's floor follows the bulk of the mesh, not its few stiffest elements (a raw scan's
// slivers, here one vertex of 252 painted 1e4 times stiffer): a floor that rose with them would
// damp every step of the rest. With the paint the median curvature per unit mass rises 2.5-fold
// (the elements around the vertex move it up the ranks of the tube's coordinates), the mean
// 36-fold.
TEST(PoseObjective, ShiftFloorIgnoresAFewStiffElements) {
  const SmallTube tube(12, 20);
  const int n = static_cast<int>(tube.mesh.V.rows());
  auto floor_with = [&](const StiffnessPaint& paint) {
    return PoseObjective(tube.mesh.V, tube.mesh.F, tube.handles, Eigen::VectorXd::Ones(2), 1e3,
                         EnergyKind::kShells, Material{1, 1, paint})
        .smallest_shift();
  };
  Eigen::VectorXd weights = Eigen::VectorXd::Zero(n);
  weights[n / 2] = 1;
  const double uniform = floor_with(StiffnessPaint{}),
               painted = floor_with(StiffnessPaint{weights, 1e4});
  EXPECT_GT(uniform, 0);
  EXPECT_LT(painted, 3 * uniform);
}

// A vertex pulled far off the tube (30 edge lengths: its edges stretched 20 times and more) is put
// back on its own, with its neighbours: the rest of the mesh stays where it was to the bit, F falls
// by five orders (the relaxation stops at a thousandth of its gradient) and the vertex is back
// within 5% of an edge of its rest place.
TEST(RelaxStretched, PutsBackAVertexPulledOff) {
  const SmallTube tube;
  const int n = static_cast<int>(tube.mesh.V.rows());
  PoseObjective objective(tube.mesh.V, tube.mesh.F, tube.handles, Eigen::VectorXd::Ones(2), 1e3,
                          EnergyKind::kShells, Material{1, 1, StiffnessPaint{}});
  objective.set_transforms(Transforms(2, Eigen::Matrix4d::Identity()));
  const int pulled = 14;  // mid-tube, in no handle
  std::vector<char> neighbourhood(n, 0);
  for (Eigen::Index f = 0; f < tube.mesh.F.rows(); ++f)
    if ((tube.mesh.F.row(f).array() == pulled).any())
      for (int k = 0; k < 3; ++k) neighbourhood[tube.mesh.F(f, k)] = 1;
  const int expected = static_cast<int>(std::count(neighbourhood.begin(), neighbourhood.end(), 1));

  const double edge = (objective.rest().row(0) - objective.rest().row(1)).norm();
  NewtonPoint point{objective.rest_positions(), 0, Eigen::VectorXd(3 * n)};
  point.y(3 * pulled) += 30 * edge;
  point.value = objective(point.y, point.gradient);
  const Eigen::VectorXd before = point.y;
  const double value_before = point.value;
  EXPECT_EQ(relax_stretched(objective, point), expected);
  EXPECT_LE(point.value, 1e-5 * value_before);
  EXPECT_LE(
      (point.y.segment<3>(3 * pulled) - objective.rest_positions().segment<3>(3 * pulled)).norm(),
      0.05 * edge);
  for (int v = 0; v < n; ++v) {
    if (!neighbourhood[v]) {
      EXPECT_EQ(point.y.segment<3>(3 * v), before.segment<3>(3 * v)) << "vertex " << v;
    }
  }
  // Nothing stretched: nothing to do.
  NewtonPoint rest{objective.rest_positions(), 0, Eigen::VectorXd(3 * n)};
  rest.value = objective(rest.y, rest.gradient);
  EXPECT_EQ(relax_stretched(objective, rest), 0);
}

// A raw scan's unwelded duplicate vertex makes an edge of length 0 at rest, which has no term: a
// start that parts its ends a little (the reduced pose's float32 rounding) stretches nothing.
TEST(RelaxStretched, LeavesZeroLengthRestEdgesAlone) {
  SmallTube tube;
  const int n = static_cast<int>(tube.mesh.V.rows());
  tube.mesh.V.conservativeResize(n + 1, 3);
  tube.mesh.V.row(n) = tube.mesh.V.row(14);
  tube.mesh.F.conservativeResize(tube.mesh.F.rows() + 1, 3);
  tube.mesh.F.bottomRows<1>() << 14, n, 15;
  PoseObjective objective(tube.mesh.V, tube.mesh.F, tube.handles, Eigen::VectorXd::Ones(2), 1e3,
                          EnergyKind::kShells, Material{1, 1, StiffnessPaint{}});
  objective.set_transforms(Transforms(2, Eigen::Matrix4d::Identity()));
  NewtonPoint point{objective.rest_positions(), 0, Eigen::VectorXd(3 * (n + 1))};
  point.y(3 * n) += 1e-7;
  point.value = objective(point.y, point.gradient);
  EXPECT_EQ(relax_stretched(objective, point), 0);
}

// A full step that decreased F by more than kExtendAbove times the model's promise is extended
// (α = 2, 4, 8 while F falls). A strip of 3 by 1 quads, its left end held, starts with its right
// half folded back by 175° over the middle of the centre quad: the flap bent away from a saddle,
// where the projected Hessian overestimates the curvature. Full steps there fall F by 1.6 to 2
// times the model's promise, and F keeps falling beyond them: 6 of the 20 iterations are extended.
TEST(SolveFull, AFullStepThatBeatsItsModelIsExtended) {
  const TriangleMesh mesh = grid(3, 1, 2.0, 1.0);
  const Handles held_end = {
      vertices_where(mesh.V, [](const Eigen::Vector3d& x) { return x.x() < -1 + 1e-9; })};
  const double fold = 175 * kPi / 180;
  RowMatrixX3d folded = mesh.V;
  for (Eigen::Index v = 0; v < folded.rows(); ++v) {
    const double x = mesh.V(v, 0);
    if (x > 0) folded.row(v) << x * std::cos(fold), mesh.V(v, 1), x * std::sin(fold);
  }
  const FullSolveResult result =
      solve_full(mesh.V, mesh.F, held_end, Eigen::VectorXd(), {Eigen::Matrix4d::Identity()}, 1e3,
                 FullSolveOptions{EnergyKind::kShells, {1, 1}, 1e-10, 100}, &folded);
  EXPECT_TRUE(result.converged);
  int extended = 0;
  for (size_t i = 0; i < result.history.size(); ++i) {
    const NewtonIteration& it = result.history[i];
    if (!(it.step > 1)) continue;
    ++extended;
    EXPECT_GT(it.ratio, 1.5) << "iteration " << i;
    EXPECT_LT(it.energy, i == 0 ? result.initial_energy : result.history[i - 1].energy)
        << "iteration " << i;
  }
  EXPECT_GE(extended, 1);
  std::printf("folded strip: %d iterations, %d of them extended\n", result.iterations, extended);
}

// Regression (robustness corpus): a handle moved a million diagonals took 1e7 load steps, and a
// move beyond 2^31 tenths of the diagonal overflowed the step count. Load steps now double while
// they are easy (a rigid move, which the predictor follows: the path's 100 steps and the first
// ones' ramp at most), and once the iterations are spent the path jumps to its end (one corner
// pulled away from the other, which 3 iterations do not reach).
TEST(SolveFull, AFarMoveEndsWhenTheIterationsAreSpent) {
  const TriangleMesh mesh = grid(3, 3, 1.0, 1.0);
  const int last = static_cast<int>(mesh.V.rows()) - 1;
  const FullSolveOptions three_iterations{EnergyKind::kShells, {1, 1}, 1e-6, 3};
  for (double distance : {1e6, 1e12}) {
    const Eigen::Matrix4d far = rigid_transform({0, 0, 1}, 0.3, {0, 0, 0}, {distance, 0, 0});
    const FullSolveResult rigid =
        solve_full(mesh.V, mesh.F, {{0, 5}}, Eigen::VectorXd(), {far}, 1e3, three_iterations);
    EXPECT_LE(rigid.steps, 110);
    EXPECT_LE(rigid.iterations, 3);
    EXPECT_TRUE(rigid.positions.allFinite());
    const FullSolveResult pulled =
        solve_full(mesh.V, mesh.F, {{0}, {last}}, Eigen::VectorXd(),
                   {Eigen::Matrix4d::Identity(), far}, 1e3, three_iterations);
    EXPECT_LE(pulled.steps, 50);
    EXPECT_LE(pulled.iterations, 3);
    EXPECT_FALSE(pulled.converged);
    EXPECT_TRUE(pulled.positions.allFinite());
  }
}

// Regression (robustness corpus): a bad mesh is named before the handles that index into it.
TEST(SolveFull, TheMeshIsCheckedBeforeTheHandles) {
  const TriangleMesh mesh = grid(3, 3, 1.0, 1.0);
  RowMatrixX3d V = mesh.V;
  V(4, 1) = std::nan("");
  testing::expect_input_error(
      [&] {
        solve_full(V, mesh.F, {{0}}, Eigen::VectorXd(), {Eigen::Matrix4d::Identity()}, 1e3,
                   FullSolveOptions{EnergyKind::kShells, {1, 1}, 1e-6, 3});
      },
      "V[4]");
  testing::expect_input_error(
      [&] {
        solve_full(RowMatrixX3d(0, 3), RowMatrixX3i(0, 3), {{0}}, Eigen::VectorXd(),
                   {Eigen::Matrix4d::Identity()}, 1e3,
                   FullSolveOptions{EnergyKind::kShells, {1, 1}, 1e-6, 3});
      },
      "V: the mesh has no vertices");
}

TEST(SolveFull, BadInputIsRefused) {
  const SmallTube tube;
  const Eigen::VectorXd none;
  auto solve = [&](const Handles& handles, const Transforms& transforms, double stiffness,
                   double tolerance, int iterations) {
    solve_full(tube.mesh.V, tube.mesh.F, handles, none, transforms, stiffness,
               FullSolveOptions{EnergyKind::kShells, {1.0, 1.0}, tolerance, iterations});
  };
  EXPECT_THROW(solve(tube.handles, {Eigen::Matrix4d::Identity()}, 1.0, 1e-8, 10), InputError);
  EXPECT_THROW(solve({{0, 999}}, {Eigen::Matrix4d::Identity()}, 1.0, 1e-8, 10), InputError);
  EXPECT_THROW(solve(tube.handles, tube.transforms, -1.0, 1e-8, 10), InputError);
  EXPECT_THROW(solve(tube.handles, tube.transforms, 1.0, 0.0, 10), InputError);
  EXPECT_THROW(solve(tube.handles, tube.transforms, 1.0, 1e-8, -1), InputError);
  RowMatrixX3i F = tube.mesh.F;
  F(2, 1) = 1000;
  EXPECT_THROW(solve_full(tube.mesh.V, F, tube.handles, none, tube.transforms, 1.0,
                          FullSolveOptions{EnergyKind::kShells, {1.0, 1.0}, 1e-8, 10}),
               InputError);
}

}  // namespace
}  // namespace modal_deform
