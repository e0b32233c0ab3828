// How close the reduced answer comes to the full-space reference on the Botsch–Sorkine test
// shapes, with the paper's 67-dimensional basis (20 modes, rigid motions included, and 47 modal
// derivatives) and a 1000-vertex ghost, against linear modes alone of the same dimension.
//
// Each pose is reached in steps (an animation): the reference continues Newton from the previous
// step's answer, the reduced solver from its last q and inverse Hessian. Errors are vertex RMS
// distances relative to the reference's bounding-box diagonal; the measured values are printed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <string>

#include "mesh/primitives.h"
#include "reduction/bake.h"
#include "solve/full_solver.h"
#include "solve/reduced_solver.h"
#include "test_posing.h"

namespace modal_deform {
namespace {

using testing::rigid_transform;
using testing::vertices_where;

constexpr double kPi = 3.14159265358979323846;
constexpr double kStiffness = 1000;

struct Scenario {
  TriangleMesh mesh;
  Handles handles;
  std::function<Transforms(double)> at;  // the transforms at a fraction t ∈ [0, 1] of the motion
  int steps;
};

struct Errors {
  double derivatives, linear;
};

Eigen::Matrix4d translation(const Eigen::Vector3d& t) {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topRightCorner<3, 1>() = t;
  return T;
}

// The end of a rod along z (length L, axis through `axis`) after bending it by `angle` into a
// circular arc in the y-z plane and twisting it by `twist` about its own axis.
Eigen::Matrix4d rod_end(double L, const Eigen::Vector3d& axis, double angle, double twist) {
  const Eigen::Matrix4d turn = rigid_transform({0, 0, 1}, twist, axis, {0, 0, 0});
  if (angle == 0) return turn;
  const Eigen::Matrix4d bend = rigid_transform({-1, 0, 0}, angle, axis + Eigen::Vector3d(0, L / angle, 0), {0, 0, 0});
  return bend * translation({0, 0, -L}) * turn;
}

// The two end rings (or faces) of a mesh along z from 0 to L.
Handles rod_ends(const RowMatrixX3d& V, double L) {
  return {vertices_where(V, [](const Eigen::Vector3d& x) { return x.z() < 1e-9; }),
          vertices_where(V, [L](const Eigen::Vector3d& x) { return x.z() > L - 1e-9; })};
}

RowMatrixX3d reduced_positions(const ReducedSolver& solver, int n) {
  Eigen::VectorXf x(3 * n);
  solver.positions(x);
  return Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>>(x.data(), n, 3).cast<double>();
}

double relative_rms(const RowMatrixX3d& X, const RowMatrixX3d& reference) {
  const double diagonal = (reference.colwise().maxCoeff() - reference.colwise().minCoeff()).norm();
  return std::sqrt((X - reference).rowwise().squaredNorm().mean()) / diagonal;
}

// Bases of a scenario's mesh, baked once per mesh: modal derivatives and linear modes.
const Basis& basis(const std::string& mesh_name, const TriangleMesh& mesh, bool derivatives) {
  static std::map<std::string, Basis> cache;
  const std::string key = mesh_name + (derivatives ? " 20+47" : " 67");
  auto it = cache.find(key);
  if (it == cache.end()) {
    Progress quiet;
    const BakeOptions options{derivatives ? 20 : 67, derivatives ? 47 : 0, 1000, "shells", 1.0, 1.0};
    it = cache.emplace(key, bake(mesh.V, mesh.F, options, quiet)).first;
  }
  return it->second;
}

Errors pose(const std::string& name, const std::string& mesh_name, const Scenario& s, EnergyKind energy) {
  const int n = static_cast<int>(s.mesh.V.rows());
  RowMatrixX3d reference = s.mesh.V;
  for (int step = 1; step <= s.steps; ++step) {
    const FullSolveResult full =
        solve_full(s.mesh.V, s.mesh.F, s.handles, Eigen::VectorXd(), s.at(double(step) / s.steps), kStiffness, energy,
                   1.0, 1.0, 1e-9, 100, &reference);
    EXPECT_TRUE(full.converged) << name << ", step " << step;
    reference = full.positions;
  }
  double error[2];
  for (int b = 0; b < 2; ++b) {
    ReducedSolver solver(basis(mesh_name, s.mesh, b == 0), s.handles, Eigen::VectorXd(), kStiffness, energy);
    for (int step = 1; step <= s.steps; ++step) {
      solver.set_transforms(s.at(double(step) / s.steps));
      ReducedSolveStats stats;
      for (int call = 0; call < 20 && !stats.converged; ++call) stats = solver.solve(20, 1e-10);
      EXPECT_TRUE(stats.converged) << name << ", step " << step;
    }
    error[b] = relative_rms(reduced_positions(solver, n), reference);
  }
  std::printf("%-40s vertex RMS / diagonal: modal derivatives %.2f%%, linear modes %.2f%%\n", name.c_str(),
              100 * error[0], 100 * error[1]);
  return {error[0], error[1]};
}

Scenario bumpy_plane_lift() {
  Scenario s{bumpy_plane(40, 10, 12, 1.0), {}, {}, 3};
  s.handles = {
      vertices_where(s.mesh.V, [](const Eigen::Vector3d& x) { return x.head<2>().cwiseAbs().maxCoeff() > 5 - 1e-9; }),
      vertices_where(s.mesh.V, [](const Eigen::Vector3d& x) { return x.head<2>().norm() < 1; })};
  s.at = [](double t) { return Transforms{Eigen::Matrix4d::Identity(), translation({0, 0, 3 * t})}; };
  return s;
}

Scenario cylinder_bend_and_twist() {
  Scenario s{cylinder(32, 60, 1.0, 8.0), {}, {}, 6};
  s.handles = rod_ends(s.mesh.V, 8);
  s.at = [](double t) {
    return Transforms{Eigen::Matrix4d::Identity(), rod_end(8, {0, 0, 0}, t * kPi / 3, t * kPi / 2)};
  };
  return s;
}

Scenario bar(double bend, double twist) {
  Scenario s{modal_deform::bar(6, 6, 60, 1, 1, 10), {}, {}, 6};
  s.handles = rod_ends(s.mesh.V, 10);
  s.at = [bend, twist](double t) {
    return Transforms{Eigen::Matrix4d::Identity(), rod_end(10, {0.5, 0.5, 0}, t * bend, t * twist)};
  };
  return s;
}

// A lift of 30% of the width with the border held: a local bump that 14 free-plate modes and
// their derivatives resolve worse than 61 modes do (measured 3.5% against 0.9%): the plane bends
// without large rotations, where derivatives add little and spatial resolution is what counts.
TEST(PosingAccuracy, BumpyPlaneLiftedInTheMiddle) {
  const Errors e = pose("bumpy plane lifted by 30%", "plane", bumpy_plane_lift(), EnergyKind::kShells);
  EXPECT_LE(e.derivatives, 0.04);
}

TEST(PosingAccuracy, CylinderBentAndTwistedByItsEndRings) {
  const Errors e =
      pose("cylinder bent by 60 and twisted by 90 deg", "cylinder", cylinder_bend_and_twist(), EnergyKind::kShells);
  EXPECT_LE(e.derivatives, 0.02);
  EXPECT_GE(e.linear, 1.3 * e.derivatives);
}

TEST(PosingAccuracy, BarBentBy90Degrees) {
  const Errors e = pose("bar bent by 90 deg", "bar", bar(kPi / 2, 0), EnergyKind::kShells);
  EXPECT_LE(e.derivatives, 0.02);
  EXPECT_GE(e.linear, 1.3 * e.derivatives);
}

// Below 90 degrees the reference twists straight; between 90 and 120 it buckles sideways (its
// middle leaves the axis by 0.8, then 1.3 bar widths at 180), which no 67-dimensional space
// spanned at rest follows.
TEST(PosingAccuracy, BarTwistedBy90And180Degrees) {
  const Errors quarter = pose("bar twisted by 90 deg", "bar", bar(0, kPi / 2), EnergyKind::kShells);
  EXPECT_LE(quarter.derivatives, 0.02);
  EXPECT_GE(quarter.linear, 1.5 * quarter.derivatives);
  const Errors half = pose("bar twisted by 180 deg (reference buckled)", "bar", bar(0, kPi), EnergyKind::kShells);
  EXPECT_LE(half.derivatives, 0.09);
  EXPECT_GE(half.linear, 1.3 * half.derivatives);
}

// ARAP as the objective of both solvers, in the shells basis: further from its reference
// (measured 3.4%, linear modes 4.6%), as the basis was not made for it.
TEST(PosingAccuracy, ArapInTheShellsBasis) {
  const Errors e =
      pose("ARAP: cylinder bent by 60, twisted by 90 deg", "cylinder", cylinder_bend_and_twist(), EnergyKind::kArap);
  EXPECT_LE(e.derivatives, 0.04);
  EXPECT_GE(e.linear, 1.2 * e.derivatives);
}

}  // namespace
}  // namespace modal_deform
