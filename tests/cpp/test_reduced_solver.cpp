#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>

#include "finite_differences.h"
#include "mesh/normalization.h"
#include "mesh/primitives.h"
#include "solve/line_search.h"
#include "solve/reduced_solver.h"
#include "test_posing.h"
#include "util/errors.h"
#include "util/math_constants.h"

namespace modal_deform {
namespace {

using testing::dense_modal_basis;
using testing::expect_slope_matches;
using testing::rigid_transform;
using testing::vertices_where;

// A tube along z, 4 long, held at its bottom ring; the top ring is turned and pushed sideways.
struct Tube {
  TriangleMesh mesh = cylinder(8, 8, 1.0, 4.0);
  Handles handles;
  Transforms transforms;
  Tube() {
    handles = {vertices_where(mesh.V, [](const Eigen::Vector3d& x) { return x.z() < 1e-9; }),
               vertices_where(mesh.V, [](const Eigen::Vector3d& x) { return x.z() > 4 - 1e-9; })};
    transforms = {Eigen::Matrix4d::Identity(),
                  rigid_transform({1, 0, 1}, 0.8, {0, 0, 4}, {1.0, 0, -0.3})};
  }
};

const Basis& tube_basis(int r) {
  static std::map<int, Basis> cache;
  auto it = cache.find(r);
  if (it == cache.end()) it = cache.emplace(r, dense_modal_basis(Tube().mesh, r)).first;
  return it->second;
}

constexpr double kStiffness = 100;

TEST(ReducedSolver, ObjectiveGradientMatchesFiniteDifferences) {
  const Tube tube;
  const Basis& basis = tube_basis(30);
  for (EnergyKind kind : {EnergyKind::kShells, EnergyKind::kArap}) {
    ReducedSolver solver(basis, tube.handles, Eigen::VectorXd(), kStiffness, kind);
    solver.set_transforms(tube.transforms);
    std::srand(11);
    const Eigen::VectorXd q = 0.05 * Eigen::VectorXd::Random(30);
    Eigen::VectorXd gradient(30), ignored(30);
    solver.objective(q, gradient);
    const Eigen::VectorXd d = Eigen::VectorXd::Random(30);
    expect_slope_matches([&](const Eigen::VectorXd& p) { return solver.objective(p, ignored); }, q,
                         d, gradient.dot(d), "reduced objective");
  }
}

TEST(ReducedSolver, DecreasesMonotonicallyToASmallGradient) {
  const Tube tube;
  ReducedSolver solver(tube_basis(40), tube.handles, Eigen::VectorXd(), kStiffness);
  solver.set_transforms(tube.transforms);
  double previous = std::numeric_limits<double>::infinity();
  ReducedSolveStats stats;
  int iterations = 0;
  for (int call = 0; call < 300 && !stats.converged; ++call) {
    stats = solver.solve(1, 1e-10);
    EXPECT_LE(stats.energy, previous);
    previous = stats.energy;
    iterations += stats.iterations;
  }
  ASSERT_TRUE(stats.converged);
  EXPECT_GT(iterations, 5);  // a real nonlinear problem
  EXPECT_LE(stats.gradient_norm, std::cbrt(1e-10) * (1 + stats.energy));
  // The answer: far from rest, handles close to their targets.
  EXPECT_GT(solver.q().norm(), 1.0);
}

int iterations_to_converge(ReducedSolver& solver, double tolerance, int cap) {
  int iterations = 0;
  for (ReducedSolveStats stats; !stats.converged && iterations < cap;
       iterations += stats.iterations)
    stats = solver.solve(cap - iterations, tolerance);
  return iterations;
}

TEST(ReducedSolver, WarmStartBeatsColdStartAndSteepestDescent) {
  const Tube tube;
  const Basis& basis = tube_basis(40);
  ReducedSolver warm(basis, tube.handles, Eigen::VectorXd(), kStiffness, EnergyKind::kShells, true);
  ReducedSolver cold(basis, tube.handles, Eigen::VectorXd(), kStiffness, EnergyKind::kShells,
                     false);
  warm.set_transforms(tube.transforms);
  cold.set_transforms(tube.transforms);
  const int warm_iterations = iterations_to_converge(warm, 1e-8, 1000);
  const int cold_iterations = iterations_to_converge(cold, 1e-8, 1000);
  // Steepest descent: the same line search along −∇f.
  const Objective f = [&cold](const Eigen::VectorXd& q, Eigen::VectorXd& g) {
    return cold.objective(q, g);
  };
  Eigen::VectorXd q = Eigen::VectorXd::Zero(40), g(40), q_new(40), g_new(40);
  double value = f(q, g), value_new;
  const double target = warm.solve(0, 1e-8).energy;
  int descent_iterations = 0;
  while (value > target + 1e-6 * std::abs(target) && descent_iterations < 3000) {
    const Eigen::VectorXd p = -g;
    if (wolfe_line_search(f, q, value, g, p, q_new, value_new, g_new).step == 0) break;
    q.swap(q_new);
    g.swap(g_new);
    value = value_new;
    ++descent_iterations;
  }
  std::printf(
      "iterations to converge (tolerance 1e-8): warm %d, cold %d; steepest descent to the same "
      "energy %d\n",
      warm_iterations, cold_iterations, descent_iterations);
  EXPECT_LE(warm_iterations, cold_iterations);
  EXPECT_GT(descent_iterations, 5 * warm_iterations);
}

TEST(ReducedSolver, StatePersistsAcrossSolves) {
  const Tube tube;
  const Basis& basis = tube_basis(30);
  // Cold starts, which take more than 10 iterations here.
  ReducedSolver once(basis, tube.handles, Eigen::VectorXd(), kStiffness, EnergyKind::kShells,
                     false);
  ReducedSolver twice(basis, tube.handles, Eigen::VectorXd(), kStiffness, EnergyKind::kShells,
                      false);
  once.set_transforms(tube.transforms);
  twice.set_transforms(tube.transforms);
  const ReducedSolveStats ten = once.solve(10, 1e-14);
  const ReducedSolveStats first = twice.solve(5, 1e-14);
  const ReducedSolveStats second = twice.solve(5, 1e-14);
  EXPECT_EQ(ten.iterations, 10);
  EXPECT_EQ(first.iterations + second.iterations, 10);
  EXPECT_EQ(first.evaluations + second.evaluations, ten.evaluations);
  EXPECT_EQ(once.q(), twice.q());
}

TEST(ReducedSolver, MovingHandlesUpdatesTheObjectiveInPlace) {
  const Tube tube;
  ReducedSolver solver(tube_basis(30), tube.handles, Eigen::VectorXd(), kStiffness);
  Eigen::VectorXd gradient(30);
  // Frames of an animation: after each move, BFGS's f(q) is the new objective at the old q.
  for (int frame = 1; frame <= 4; ++frame) {
    solver.set_transforms(
        {Eigen::Matrix4d::Identity(),
         rigid_transform({1, 0, 1}, 0.2 * frame, {0, 0, 4}, {0.25 * frame, 0, 0})});
    const double updated = solver.solve(0, 1e-8).energy;
    EXPECT_NEAR(updated, solver.objective(solver.q(), gradient), 1e-12 * std::abs(updated))
        << "frame " << frame;
    const ReducedSolveStats stats = solver.solve(10, 1e-8);
    EXPECT_LE(stats.energy, updated);
  }
}

TEST(ReducedSolver, ASingleVertexHandleLeavesRotationsFreeAndStillSolves) {
  const Tube tube;
  const Basis& basis = tube_basis(30);
  // One vertex pulled: rotations about it cost nothing at rest, so the rest Hessian is singular.
  ReducedSolver solver(basis, {{tube.handles[1][0]}}, Eigen::VectorXd(), kStiffness);
  solver.set_transforms({rigid_transform({0, 0, 1}, 0, {0, 0, 0}, {0.5, 0.2, 0.3})});
  ReducedSolveStats stats;
  for (int call = 0; call < 100 && !stats.converged; ++call) stats = solver.solve(10, 1e-8);
  EXPECT_TRUE(stats.converged);
  EXPECT_TRUE(solver.q().allFinite());
  Eigen::VectorXf x(3 * basis.num_vertices());
  solver.positions(x);
  const int v = tube.handles[1][0];
  const Eigen::Vector3d moved = x.segment<3>(3 * v).cast<double>() - basis.rest.row(v).transpose();
  EXPECT_LE((moved - Eigen::Vector3d(0.5, 0.2, 0.3)).norm(), 0.05) << moved.transpose();
}

TEST(ReducedSolver, PositionsAreRestPlusUqInTheCallersBuffer) {
  const Tube tube;
  const Basis& basis = tube_basis(30);
  ReducedSolver solver(basis, tube.handles, Eigen::VectorXd(), kStiffness);
  Eigen::VectorXf out = Eigen::VectorXf::Constant(3 * basis.num_vertices(), std::nanf(""));
  const float* buffer = out.data();
  solver.positions(out);
  EXPECT_EQ(out.cast<double>(),
            flatten(basis.rest).cast<float>().cast<double>());  // q = 0: the rest shape
  solver.set_transforms(tube.transforms);
  solver.solve(20, 1e-8);
  solver.positions(out);
  EXPECT_EQ(out.data(), buffer);
  const Eigen::VectorXd expected = flatten(basis.rest) + basis.vectors.cast<double>() * solver.q();
  const double magnitude = flatten(basis.rest).cwiseAbs().maxCoeff() +
                           (expected - flatten(basis.rest)).cwiseAbs().maxCoeff();
  // Read from 16 bits (QuantizedVectors): within the map's tolerance, beside float32's own
  // rounding.
  const double diagonal = bounding_box_diagonal(basis.rest);
  EXPECT_LE((out.cast<double>() - expected).cwiseAbs().maxCoeff(),
            FinePositions::kTolerance * diagonal + 1e-6 * magnitude);
  solver.reset();
  solver.positions(out);
  EXPECT_EQ(out.cast<double>(), flatten(basis.rest).cast<float>().cast<double>());
  Eigen::VectorXf wrong(5);
  EXPECT_THROW(solver.positions(wrong), InputError);
}

TEST(ReducedSolver, ResetReturnsToRestAndSolvesAgainTheSameWay) {
  const Tube tube;
  ReducedSolver solver(tube_basis(30), tube.handles, Eigen::VectorXd(), kStiffness);
  solver.set_transforms(tube.transforms);
  const ReducedSolveStats first = solver.solve(8, 1e-14);
  const Eigen::VectorXd q = solver.q();
  solver.reset();
  EXPECT_TRUE(solver.q().isZero(0));
  const ReducedSolveStats second = solver.solve(8, 1e-14);
  EXPECT_EQ(solver.q(), q);
  EXPECT_EQ(first.energy, second.energy);
}

TEST(ReducedSolver, BadInputIsRefused) {
  const Tube tube;
  const Basis& basis = tube_basis(30);
  const Eigen::VectorXd none;
  EXPECT_THROW(ReducedSolver(basis, tube.handles, none, 0.0), InputError);
  EXPECT_THROW(ReducedSolver(basis, tube.handles, none, std::nan("")), InputError);
  EXPECT_THROW(ReducedSolver(basis, {{0, 1000}}, none, 1.0), InputError);
  EXPECT_THROW(ReducedSolver(basis, tube.handles, Eigen::VectorXd::Ones(3), 1.0), InputError);
  Basis broken = basis;
  broken.ghost_map[3] = 1000;
  EXPECT_THROW(ReducedSolver(broken, tube.handles, none, 1.0), InputError);
  ReducedSolver solver(basis, tube.handles, none, 1.0);
  EXPECT_THROW(solver.set_transforms({Eigen::Matrix4d::Identity()}), InputError);
  EXPECT_THROW(
      solver.set_transforms({Eigen::Matrix4d::Identity(), 2 * Eigen::Matrix4d::Identity()}),
      InputError);
  EXPECT_THROW(solver.solve(-1, 1e-6), InputError);
  EXPECT_THROW(solver.solve(5, 0.0), InputError);
}

}  // namespace
}  // namespace modal_deform
