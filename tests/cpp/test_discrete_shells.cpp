// The discrete shells energy: its value against the paper's formula, every derivative against
// centred differences at rest and at large deformations, invariances, the rest Hessian's kernel,
// degenerate and non-manifold input, weights, threads and bad input.
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "energy/discrete_shells.h"
#include "finite_differences.h"
#include "mesh/mesh_check.h"
#include "mesh/mesh_topology.h"
#include "mesh/normalization.h"
#include "mesh/primitives.h"
#include "test_support.h"
#include "util/errors.h"
#include "util/math_constants.h"

namespace modal_deform {
namespace {

using testing::expect_gradient_matches;
using testing::expect_hessian_matches;
using testing::expect_input_error;
using testing::expect_third_matches;
using testing::normalized;
using testing::random_vector;
using testing::shared_mesh;
using testing::side_by_side;

Eigen::VectorXd flat(const RowMatrixX3d& X) {
  return Eigen::Map<const Eigen::VectorXd>(X.data(), X.size());
}

Eigen::Matrix3d rotation(double angle, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

// The large deformations the derivatives are checked at (meshes scaled to an extent of 10), each
// with a little noise so that no hinge stays exactly flat or symmetric.
RowMatrixX3d with_noise(RowMatrixX3d X, unsigned seed) {
  const Eigen::VectorXd noise = 0.02 * random_vector(X.size(), seed);
  return X + Eigen::Map<const RowMatrixX3d>(noise.data(), X.rows(), 3);
}

RowMatrixX3d stretched(const RowMatrixX3d& V) {
  RowMatrixX3d X = V;
  X.col(0) *= 1.3;
  return with_noise(X, 1);
}

// The half above the median height turned by 90 degrees about a horizontal axis.
RowMatrixX3d part_rotated(const RowMatrixX3d& V) {
  Eigen::VectorXd z = V.col(2);
  std::nth_element(z.data(), z.data() + z.size() / 2, z.data() + z.size());
  const double median = z[z.size() / 2];
  const Eigen::RowVector3d pivot(V.col(0).mean(), V.col(1).mean(), median);
  const Eigen::Matrix3d R = rotation(kPi / 2, Eigen::Vector3d::UnitX());
  RowMatrixX3d X = V;
  for (Eigen::Index i = 0; i < X.rows(); ++i)
    if (V(i, 2) > median) X.row(i) = (V.row(i) - pivot) * R.transpose() + pivot;
  return with_noise(X, 2);
}

// Bent by 90 degrees along z: the line x = 0 goes onto a quarter circle of the same length.
RowMatrixX3d bent(const RowMatrixX3d& V) {
  const double low = V.col(2).minCoeff(), length = V.col(2).maxCoeff() - low;
  const double radius = length / (kPi / 2);
  RowMatrixX3d X = V;
  for (Eigen::Index i = 0; i < X.rows(); ++i) {
    const double angle = (kPi / 2) * (V(i, 2) - low) / length, arm = radius - V(i, 0);
    X(i, 0) = radius - arm * std::cos(angle);
    X(i, 2) = low + arm * std::sin(angle);
  }
  return with_noise(X, 3);
}

struct State {
  std::string name;
  Eigen::VectorXd x;
};

std::vector<State> states(const RowMatrixX3d& V) {
  return {{"rest", flat(V)},
          {"stretched 30%", flat(stretched(V))},
          {"half rotated 90 deg", flat(part_rotated(V))},
          {"bent 90 deg", flat(bent(V))}};
}

// Gradient from value, Hessian from gradient, third contraction from Hessian, batched third
// against single third, at every state.
void check_derivatives(const TriangleMesh& mesh, const std::string& mesh_name) {
  const DiscreteShells energy(mesh.V, mesh.F);
  const Eigen::Index size = mesh.V.size();
  const Eigen::VectorXd d = random_vector(size, 11), u = random_vector(size, 12),
                        w = random_vector(size, 13);
  for (const State& state : states(mesh.V)) {
    const Eigen::VectorXd& x = state.x;
    const std::string where = mesh_name + ", " + state.name;
    expect_gradient_matches(energy, x, d, where);
    expect_hessian_matches(energy, x, d, where);
    expect_third_matches(energy, x, u, w, where);
    const Eigen::VectorXd third = energy.third(x, u, w);

    Eigen::MatrixXd Phi(size, 3);
    Phi << u, w, d;
    const Eigen::MatrixXd batch = energy.third_batch(x, Phi, {{0, 1}, {2, 2}, {1, 0}, {2, 1}});
    EXPECT_LT((batch.col(0) - third).norm(), 1e-12 * third.norm()) << where;
    const Eigen::VectorXd dd = energy.third(x, d, d), dw = energy.third(x, d, w);
    EXPECT_LT((batch.col(1) - dd).norm(), 1e-12 * dd.norm()) << where;
    EXPECT_LT((batch.col(2) - third).norm(), 1e-12 * third.norm()) << where;
    EXPECT_LT((batch.col(3) - dw).norm(), 1e-12 * dw.norm()) << where;
  }
}

TEST(DiscreteShells, DerivativesMatchCentredDifferencesOnTheBunny) {
  check_derivatives(normalized(shared_mesh("bunny.obj.gz")), "bunny");
}

TEST(DiscreteShells, DerivativesMatchCentredDifferencesOnACylinder) {
  check_derivatives(normalized(cylinder(12, 8, 1.0, 4.0)), "cylinder");
}

// A single hinge folded through ±π, where θ wraps: the energy and its derivatives stay smooth.
TEST(DiscreteShells, DerivativesAreSmoothWhereTheAngleWraps) {
  RowMatrixX3d V(4, 3);
  V << 0, 0, 0, 1, 0, 0, 0.4, 1, 0, 0.6, -1, 0;
  RowMatrixX3i F(2, 3);
  F << 0, 1, 2, 1, 0, 3;
  const DiscreteShells energy(V, F);
  RowMatrixX3d X = V;
  // Turn vertex 3 about the edge (the x axis) to 0.001 short of folding onto triangle 0.
  const double angle = kPi - 1e-3;
  X.row(3) << 0.6, -std::cos(angle), -std::sin(angle);
  const Eigen::VectorXd x = flat(X), d = random_vector(12, 5);
  // Steps of 1e-3 cross θ = ±π. The slope is small (sin δ ≈ 1e-3) next to E ≈ 2w, so round-off
  // in E sets in early.
  expect_gradient_matches(energy, x, d, "across the fold", 2e-6);
  expect_hessian_matches(energy, x, d, "across the fold", 1e-7);
}

// A hinge with its opposite vertex 2 at (0.4, t, lift): with no lift the first triangle turns
// over through zero area as t passes 0 (its normal from +z to −z).
Eigen::VectorXd crushed_hinge(double t, double lift = 0) {
  RowMatrixX3d X(4, 3);
  X << 0, 0, 0, 1, 0, 0, 0.4, t, lift, 0.6, -1, 0;
  return flat(X);
}

// Issue 22: a triangle turning over used to turn the dihedral angle by π at once and make E jump
// by up to 2w; the bending term now fades out as either triangle is crushed, so E is continuous
// through the turn and twice continuously differentiable on either side.
TEST(DiscreteShells, BendingFadesOutContinuouslyAsATriangleTurnsOver) {
  RowMatrixX3d V(4, 3);
  V << 0, 0, 0, 1, 0, 0, 0.4, 1, 0, 0.6, -1, 0;
  RowMatrixX3i F(2, 3);
  F << 0, 1, 2, 1, 0, 3;
  const DiscreteShells energy(V, F);
  // E(t) sampled every 1e-5 from t = 0.3 to −0.3: no step changes E by more than its slope allows
  // (at most 3.3e-3, where the fade is steepest; the step across t = 0 changed it by 6.0 = 2w
  // before the fade).
  const double dt = 1e-5;
  double largest_step = 0, previous = energy.value(crushed_hinge(0.3));
  for (double t = 0.3 - dt; t > -0.3; t -= dt) {
    const double value = energy.value(crushed_hinge(t));
    largest_step = std::max(largest_step, std::abs(value - previous));
    previous = value;
  }
  EXPECT_LT(largest_step, 1e-2) << "E jumps along the path";
  // The membrane terms alone at t = ±1e-9 (the hinge faded to nothing): E is even in t there.
  EXPECT_NEAR(energy.value(crushed_hinge(1e-9)), energy.value(crushed_hinge(-1e-9)), 1e-9);

  const Eigen::VectorXd d = random_vector(12, 7), u = random_vector(12, 8);
  for (double t : {0.03, 0.015, -0.015, -0.03}) {  // area ratios 0.032, 0.018: faded
    const Eigen::VectorXd x = crushed_hinge(t, 0.01);
    const std::string where = "crushed hinge at t = " + std::to_string(t);
    expect_gradient_matches(energy, x, d, where);
    expect_hessian_matches(energy, x, d, where);
    expect_third_matches(energy, x, u, d, where);
  }
}

// Turning one triangle of a flat hinge by φ about the edge changes neither lengths nor areas:
// E = ½ · 3‖ē‖²/Ā_e · (2 sin(φ/2))², for φ up to and beyond π.
TEST(DiscreteShells, BendingTermIsThePapersFormula) {
  RowMatrixX3d V(4, 3);
  V << 0, 0, 0, 2, 0, 0, 0.5, 1, 0, 1.5, -0.7, 0;
  RowMatrixX3i F(2, 3);
  F << 0, 1, 2, 1, 0, 3;
  const double bending = 1.7;
  const DiscreteShells energy(V, F, bending, 1.0);
  const double area = 0.5 * 2 * 1 + 0.5 * 2 * 0.7, edge_squared = 4;
  for (double phi : {0.1, 1.0, 2.5, kPi, 3.5, -2.0}) {
    RowMatrixX3d X = V;
    X.row(3) << 1.5, -0.7 * std::cos(phi), -0.7 * std::sin(phi);
    const double expected =
        bending * 0.5 * 3 * edge_squared / area * std::pow(2 * std::sin(phi / 2), 2);
    EXPECT_NEAR(energy.value(flat(X)), expected, 1e-12 * expected) << "phi = " << phi;
  }
}

// Scaling a lone triangle by s: E_L = ½ (s − 1)² Σ ‖ē‖, E_A = ½ (s² − 1)² Ā.
TEST(DiscreteShells, MembraneTermsAreThePapersFormula) {
  RowMatrixX3d V(3, 3);
  V << 0, 0, 0, 3, 0, 0, 1, 2, 0;
  RowMatrixX3i F(1, 3);
  F << 0, 1, 2;
  const double membrane = 0.6, s = 1.3;
  const DiscreteShells energy(V, F, 1.0, membrane);
  const double perimeter = 3 + std::sqrt(8.0) + std::sqrt(5.0), area = 3;
  const double expected =
      membrane * (0.5 * std::pow(s - 1, 2) * perimeter + 0.5 * std::pow(s * s - 1, 2) * area);
  EXPECT_NEAR(energy.value(flat(s * V)), expected, 1e-13 * expected);
  EXPECT_EQ(energy.term_counts().hinges, 0);
}

TEST(DiscreteShells, RestAndRigidMotionsCostNothing) {
  const TriangleMesh bunny = normalized(shared_mesh("bunny.obj.gz"));
  const DiscreteShells energy(bunny.V, bunny.F);
  const Eigen::Index size = bunny.V.size();
  Eigen::VectorXd gradient(size);
  EXPECT_NEAR(energy.value_and_gradient(energy.rest(), gradient), 0.0, 1e-12);
  EXPECT_LT(gradient.lpNorm<Eigen::Infinity>(), 1e-12);

  const Eigen::Matrix3d R = rotation(1.1, Eigen::Vector3d(1, 2, 3));
  const Eigen::RowVector3d t(3, -2, 5);
  const RowMatrixX3d moved = (bunny.V * R.transpose()).rowwise() + t;
  EXPECT_NEAR(energy.value_and_gradient(flat(moved), gradient), 0.0, 1e-10);
  EXPECT_LT(gradient.lpNorm<Eigen::Infinity>(), 1e-10);
}

// E(Rx + t) = E(x), ∇E(Rx + t) = R∇E(x), ∇²E(Rx + t) = R∇²E(x)Rᵀ and the same for the third
// derivative, R acting on every vertex, at a deformed state.
TEST(DiscreteShells, DerivativesRotateWithTheMesh) {
  const TriangleMesh bunny = normalized(shared_mesh("bunny.obj.gz"));
  const DiscreteShells energy(bunny.V, bunny.F);
  const Eigen::Matrix3d R = rotation(2.0, Eigen::Vector3d(-1, 0.5, 2));
  const Eigen::RowVector3d t(1, 7, -3);
  auto rotate = [&R](const Eigen::VectorXd& v) {
    const RowMatrixX3d rows =
        Eigen::Map<const RowMatrixX3d>(v.data(), v.size() / 3, 3) * R.transpose();
    return flat(rows);
  };
  const RowMatrixX3d X = part_rotated(bunny.V);
  const RowMatrixX3d Y = (X * R.transpose()).rowwise() + t;
  const Eigen::VectorXd x = flat(X), y = flat(Y);
  const Eigen::VectorXd v = random_vector(x.size(), 21), u = random_vector(x.size(), 22);
  Eigen::VectorXd gx(x.size()), gy(x.size());
  const double ex = energy.value_and_gradient(x, gx), ey = energy.value_and_gradient(y, gy);
  EXPECT_NEAR(ey, ex, 1e-12 * ex);
  EXPECT_LT((gy - rotate(gx)).norm(), 1e-12 * gx.norm());
  const Eigen::VectorXd hx = energy.hessian(x) * v, hy = energy.hessian(y) * rotate(v);
  EXPECT_LT((hy - rotate(hx)).norm(), 1e-12 * hx.norm());
  const Eigen::VectorXd tx = energy.third(x, u, v), ty = energy.third(y, rotate(u), rotate(v));
  EXPECT_LT((ty - rotate(tx)).norm(), 1e-12 * tx.norm());
}

// The rest Hessian's eigenvalues (dense, so only for small meshes), ascending.
Eigen::VectorXd rest_eigenvalues(const TriangleMesh& mesh) {
  const DiscreteShells energy(mesh.V, mesh.F);
  const Eigen::MatrixXd H = Eigen::MatrixXd(energy.hessian(energy.rest()));
  EXPECT_EQ((H - H.transpose()).norm(), 0.0) << "not exactly symmetric";
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(H, Eigen::EigenvaluesOnly).eigenvalues();
}

// At rest ∇²E = Σ w f'' ∇s∇sᵀ: positive semi-definite, and zero only on the rigid motions of each
// connected component (6 each). The gap to the first non-zero eigenvalue shows the count is clear.
void expect_rigid_kernel(const TriangleMesh& mesh, int components, const std::string& name) {
  const Eigen::VectorXd lambda = rest_eigenvalues(normalized(mesh));
  const double largest = lambda[lambda.size() - 1];
  const int zeros = 6 * components;
  EXPECT_GT(lambda[0], -1e-12 * largest) << name;
  EXPECT_LT(std::abs(lambda[zeros - 1]), 1e-12 * largest) << name;
  EXPECT_GT(lambda[zeros], 1e-6 * largest) << name;
  std::printf("  %-32s |λ_%d| / λ_max = %.1e, λ_%d / λ_max = %.1e\n", name.c_str(), zeros,
              std::abs(lambda[zeros - 1]) / largest, zeros + 1, lambda[zeros] / largest);
}

// A closed, curved, irregular blob: a subdivided box pushed onto a lumpy sphere.
TriangleMesh blob() {
  TriangleMesh mesh = bar(3, 3, 3, 1, 1, 1);
  for (Eigen::Index i = 0; i < mesh.V.rows(); ++i) {
    const Eigen::RowVector3d p = mesh.V.row(i) - Eigen::RowVector3d::Constant(0.5);
    const double radius = 1 + 0.3 * std::sin(3 * p[0]) * std::cos(2 * p[1]) + 0.2 * p[2];
    mesh.V.row(i) = radius * p.normalized();
  }
  return mesh;
}

TEST(DiscreteShells, RestHessianKernelIsSixRigidMotionsPerComponent) {
  expect_rigid_kernel(cylinder(8, 3, 1.0, 3.0), 1, "open cylinder");
  expect_rigid_kernel(bar(1, 1, 3, 1.0, 1.0, 3.0), 1, "closed bar");
  expect_rigid_kernel(grid(4, 3, 2.0, 1.5), 1, "flat grid");
  expect_rigid_kernel(blob(), 1, "closed blob");
  expect_rigid_kernel(
      side_by_side(cylinder(8, 3, 1.0, 3.0), cylinder(8, 3, 1.0, 3.0), Eigen::RowVector3d(5, 0, 0)),
      2, "two disjoint cylinders");
}

// The projected Hessian: the exact one at rest (every term's Hessian is semidefinite there), and
// positive semidefinite where the exact one is indefinite (a crushed, twisted cylinder). The
// membrane terms are projected, which only removes negative parts: the difference to the exact
// Hessian is itself semidefinite. Hinges bent less than 90° take the Gauss–Newton block
// f''∇θ∇θᵀ, which, since θ does not change as the mesh turns, has the pose's infinitesimal
// rotations in its kernel (the exact Hessian away from rest does not).
TEST(DiscreteShells, ProjectedHessianIsSemidefiniteAndExactWhereTermsAre) {
  const TriangleMesh mesh = cylinder(8, 4, 1.0, 3.0);
  const DiscreteShells energy(mesh.V, mesh.F);
  const Eigen::VectorXd rest = energy.rest();
  EXPECT_EQ(Eigen::MatrixXd(energy.projected_hessian(rest)), Eigen::MatrixXd(energy.hessian(rest)));
  const Eigen::VectorXd x = rest + 0.3 * random_vector(rest.size(), 7);
  const Eigen::MatrixXd exact(energy.hessian(x)), projected(energy.projected_hessian(x));
  const double scale = exact.cwiseAbs().maxCoeff();
  EXPECT_EQ(projected, projected.transpose());
  const Eigen::VectorXd exact_eigenvalues =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(exact).eigenvalues();
  ASSERT_LT(exact_eigenvalues(0), -1e-3 * scale) << "the test needs an indefinite exact Hessian";
  EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(projected).eigenvalues()(0),
            -1e-12 * scale);

  const DiscreteShells membrane(mesh.V, mesh.F, 0.0, 1.0);
  const Eigen::MatrixXd membrane_exact(membrane.hessian(x)),
      membrane_projected(membrane.projected_hessian(x));
  EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(membrane_projected - membrane_exact)
                .eigenvalues()(0),
            -1e-12 * scale);

  const DiscreteShells bending(mesh.V, mesh.F, 1.0, 0.0);
  const Eigen::VectorXd bent =
      rest + 0.03 * random_vector(rest.size(), 8);  // hinges bent well below 90°
  const Eigen::MatrixXd bending_exact(bending.hessian(bent)),
      bending_projected(bending.projected_hessian(bent));
  const double bending_scale = bending_exact.cwiseAbs().maxCoeff();
  for (int axis = 0; axis < 3; ++axis) {
    Eigen::VectorXd rotation(bent.size());  // ω × x for ω the axis
    for (Eigen::Index v = 0; v < bent.size() / 3; ++v)
      rotation.segment<3>(3 * v) =
          Eigen::Vector3d::Unit(axis).cross(Eigen::Vector3d(bent.segment<3>(3 * v)));
    EXPECT_LE((bending_projected * rotation).norm(), 1e-10 * bending_scale * rotation.norm())
        << "axis " << axis;
    EXPECT_GE((bending_exact * rotation).norm(), 1e-4 * bending_scale * rotation.norm())
        << "axis " << axis;
  }
}

// What `energy` returns at x is finite everywhere.
void expect_finite_everywhere(const DiscreteShells& energy, const Eigen::VectorXd& x,
                              const std::string& where) {
  const Eigen::Index size = x.size();
  Eigen::VectorXd gradient(size);
  EXPECT_TRUE(std::isfinite(energy.value(x))) << where;
  EXPECT_TRUE(std::isfinite(energy.value_and_gradient(x, gradient))) << where;
  EXPECT_TRUE(gradient.allFinite()) << where;
  const SparseMatrix H = energy.hessian(x);
  EXPECT_TRUE(Eigen::Map<const Eigen::VectorXd>(H.valuePtr(), H.nonZeros()).allFinite()) << where;
  const Eigen::VectorXd u = random_vector(size, 31), w = random_vector(size, 32);
  EXPECT_TRUE(energy.third(x, u, w).allFinite()) << where;
  Eigen::MatrixXd Phi(size, 2);
  Phi << u, w;
  EXPECT_TRUE(energy.third_batch(x, Phi, {{0, 1}, {1, 1}}).allFinite()) << where;
}

// The term counts the rules in discrete_shells.h give, from the topology.
void expect_terms_per_rules(const TriangleMesh& mesh, const DiscreteShells& energy,
                            const std::string& name) {
  const MeshTopology topology = build_topology(mesh.V, mesh.F);
  int triangles = 0, hinges = 0;
  for (int f = 0; f < mesh.F.rows(); ++f) triangles += !is_degenerate_face(mesh.V, mesh.F, f);
  for (const Hinge& hinge : topology.hinges)
    hinges += !is_degenerate_face(mesh.V, mesh.F, hinge.faces[0]) &&
              !is_degenerate_face(mesh.V, mesh.F, hinge.faces[1]);
  EXPECT_EQ(energy.term_counts().triangles, triangles) << name;
  EXPECT_EQ(energy.term_counts().hinges, hinges) << name;
}

// Newton reassembles each iteration's Hessian into the last one's storage: the matrix is the one
// hessian(x) returns, whatever it held before, and no new storage is taken.
TEST(DiscreteShells, HessianIntoAnEarlierHessianReusesItsStorage) {
  const TriangleMesh mesh = cylinder(8, 4, 1.0, 3.0);
  const DiscreteShells energy(mesh.V, mesh.F);
  const Eigen::VectorXd x = energy.rest() + 0.3 * random_vector(energy.rest().size(), 7);
  SparseMatrix H = energy.hessian(energy.rest() + 0.1 * random_vector(energy.rest().size(), 8));
  const double* values = H.valuePtr();
  for (const bool projected : {false, true}) {
    energy.hessian_into(x, projected, H);
    EXPECT_EQ(H.valuePtr(), values);
    const SparseMatrix expected = projected ? energy.projected_hessian(x) : energy.hessian(x);
    EXPECT_EQ(Eigen::MatrixXd(H), Eigen::MatrixXd(expected)) << (projected ? "projected" : "exact");
  }
}

TEST(DiscreteShells, SharedDragonsGiveFiniteResults) {
  for (const char* file : {"dragon_vrip_res4.ply.gz", "dragon_vrip_res3.ply.gz"}) {
    const TriangleMesh dragon = normalized(shared_mesh(file));
    const DiscreteShells energy(dragon.V, dragon.F);
    expect_terms_per_rules(dragon, energy, file);
    expect_finite_everywhere(energy, energy.rest(), std::string(file) + " at rest");
    expect_finite_everywhere(energy, flat(stretched(dragon.V)), std::string(file) + " stretched");
  }
}

// The non-manifold fan of test_mesh.cpp (4 triangles around edge 0-1) with a degenerate triangle
// on edge 1-2 (vertex 6 on that edge), a triangle with a repeated index, and a triangle with a
// zero-length edge (vertex 7 on vertex 5).
TriangleMesh awkward_mesh() {
  TriangleMesh mesh;
  mesh.V.resize(8, 3);
  mesh.V << 0, 0, 0, 1, 0, 0, 0.5, 1, 0, 0.5, -1, 0, 0.5, 0, 1, 0.5, 0.7, 0.7, 0.75, 0.5, 0, 0.5,
      0.7, 0.7;
  mesh.F.resize(7, 3);
  mesh.F << 0, 1, 2, 1, 0, 3, 0, 1, 4, 0, 1, 5, 1, 2, 6, 2, 2, 3, 5, 7, 0;
  return mesh;
}

TEST(DiscreteShells, DegenerateAndNonManifoldInputFollowTheRules) {
  const TriangleMesh mesh = awkward_mesh();
  const DiscreteShells energy(mesh.V, mesh.F);
  // 4 good triangles; 4 hinges around the non-manifold edge (those on edges 1-2 and 0-5 have a
  // degenerate triangle); 9 fan edges + 2-6, 6-1, 7-0 (5-7 has zero length).
  EXPECT_EQ(energy.term_counts().triangles, 4);
  EXPECT_EQ(energy.term_counts().hinges, 4);
  EXPECT_EQ(energy.term_counts().edges, 12);
  expect_terms_per_rules(mesh, energy, "awkward mesh");
  Eigen::VectorXd gradient(mesh.V.size());
  EXPECT_NEAR(energy.value_and_gradient(energy.rest(), gradient), 0.0, 1e-14);
  EXPECT_LT(gradient.lpNorm<Eigen::Infinity>(), 1e-14);
  expect_finite_everywhere(energy, energy.rest(), "awkward mesh at rest");
  const Eigen::VectorXd x = flat(stretched(mesh.V)), d = random_vector(x.size(), 41);
  expect_finite_everywhere(energy, x, "awkward mesh stretched");
  // The terms that exist are differentiated consistently.
  expect_gradient_matches(energy, x, d, "awkward mesh", 1e-7);
}

TEST(DiscreteShells, CollapsedElementsKeepEverythingFinite) {
  const TriangleMesh tube = normalized(cylinder(8, 3, 1.0, 3.0));
  const DiscreteShells energy(tube.V, tube.F);
  // Vertex 1 onto vertex 0: an edge of zero length and two triangles of zero area.
  RowMatrixX3d X = tube.V;
  X.row(1) = X.row(0);
  expect_finite_everywhere(energy, flat(X), "two vertices merged");
  // Vertex 9 onto the middle of edge 0-1: triangles around it flat, normals zero.
  X = tube.V;
  X.row(9) = 0.5 * (X.row(0) + X.row(1));
  expect_finite_everywhere(energy, flat(X), "vertex on an edge");
  // Everything in one point.
  X = tube.V.row(0).replicate(X.rows(), 1);
  const Eigen::VectorXd point = flat(X);
  expect_finite_everywhere(energy, point, "all vertices in one point");
  // Only the membrane terms remain (every hinge has collapsed); their values are the exact ones.
  double membrane = 0;
  for (int f = 0; f < tube.F.rows(); ++f) {
    const Eigen::Vector3d a = tube.V.row(tube.F(f, 0)), b = tube.V.row(tube.F(f, 1)),
                          c = tube.V.row(tube.F(f, 2));
    const double area = 0.5 * (b - a).cross(c - a).norm();
    membrane += 0.5 * area;  // ½ (0 − Ā)² / Ā
  }
  for (const auto& [a, b] : build_topology(tube.V, tube.F).edges)
    membrane += 0.5 * (tube.V.row(a) - tube.V.row(b)).norm();
  EXPECT_NEAR(energy.value(point), membrane, 1e-12 * membrane);
}

TEST(DiscreteShells, WeightsScaleTheirTermsLinearly) {
  const TriangleMesh bunny = normalized(shared_mesh("bunny.obj.gz"));
  const DiscreteShells bending(bunny.V, bunny.F, 1.0, 0.0), membrane(bunny.V, bunny.F, 0.0, 1.0),
      both(bunny.V, bunny.F, 2.5, 0.3);
  const Eigen::VectorXd x = flat(bent(bunny.V));
  const Eigen::VectorXd u = random_vector(x.size(), 51), w = random_vector(x.size(), 52);
  const Eigen::Index size = x.size();
  Eigen::VectorXd gb(size), gm(size), g(size);
  const double eb = bending.value_and_gradient(x, gb), em = membrane.value_and_gradient(x, gm);
  const double e = both.value_and_gradient(x, g);
  EXPECT_GT(eb, 0);
  EXPECT_GT(em, 0);
  EXPECT_NEAR(e, 2.5 * eb + 0.3 * em, 1e-13 * e);
  EXPECT_LT((g - (2.5 * gb + 0.3 * gm)).norm(), 1e-13 * g.norm());
  const Eigen::VectorXd h = both.hessian(x) * u, hb = bending.hessian(x) * u,
                        hm = membrane.hessian(x) * u;
  EXPECT_LT((h - (2.5 * hb + 0.3 * hm)).norm(), 1e-13 * h.norm());
  const Eigen::VectorXd t = both.third(x, u, w), tb = bending.third(x, u, w),
                        tm = membrane.third(x, u, w);
  EXPECT_LT((t - (2.5 * tb + 0.3 * tm)).norm(), 1e-13 * t.norm());
}

// Painted stiffness (stiffness_paint.h): all weights 1 is max_stiffness times the material, all 0
// the material itself, and a painted part counts only in the elements touching it.
TEST(DiscreteShells, PaintedStiffnessScalesEachElementByItsVerticesMeanWeight) {
  const TriangleMesh tube = cylinder(8, 6, 1.0, 3.0);
  const Eigen::Index n = tube.V.rows();
  const DiscreteShells plain(tube.V, tube.F, 1.5, 0.5);
  const DiscreteShells stiff(tube.V, tube.F, 1.5, 0.5, {Eigen::VectorXd::Ones(n), 40.0});
  const DiscreteShells zero(tube.V, tube.F, 1.5, 0.5, {Eigen::VectorXd::Zero(n), 40.0});
  const Eigen::VectorXd x = flat(bent(tube.V));
  EXPECT_NEAR(stiff.value(x), 40.0 * plain.value(x), 1e-12 * stiff.value(x));
  EXPECT_EQ(zero.value(x), plain.value(x));
  // Vertex 0 painted: only the terms it is in stiffen; moving a vertex far from it costs as before.
  Eigen::VectorXd weights = Eigen::VectorXd::Zero(n);
  weights[0] = 1.0;
  const DiscreteShells one(tube.V, tube.F, 1.5, 0.5, {weights, 40.0});
  Eigen::VectorXd near = plain.rest(), far = plain.rest();
  near[0] += 0.1;
  far[3 * (n - 1)] += 0.1;
  EXPECT_EQ(one.value(far), plain.value(far));
  EXPECT_GT(one.value(near), 5.0 * plain.value(near));
  EXPECT_LT(one.value(near), 40.0 * plain.value(near));
  expect_input_error(
      [&] { DiscreteShells(tube.V, tube.F, 1, 1, {Eigen::VectorXd::Zero(n - 1), 2.0}); },
      "stiffness_weights: expected one weight per vertex");
  weights[4] = -1e-3;
  expect_input_error([&] { DiscreteShells(tube.V, tube.F, 1, 1, {weights, 2.0}); },
                     "stiffness_weights[4]");
  expect_input_error([&] { DiscreteShells(tube.V, tube.F, 1, 1, {Eigen::VectorXd(), 0.9}); },
                     "max_stiffness");
}

// Each vertex sums its contributions in element order however many threads share the work.
TEST(DiscreteShells, ResultsDoNotDependOnTheNumberOfThreads) {
  const TriangleMesh dragon = normalized(shared_mesh("dragon_vrip_res4.ply.gz"));
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const DiscreteShells serial(dragon.V, dragon.F);
  omp_set_num_threads(2);
  const DiscreteShells parallel(dragon.V, dragon.F);  // over 40k terms: split in 2
  const Eigen::VectorXd x = flat(part_rotated(dragon.V));
  const Eigen::Index size = x.size();
  // The gradient takes its own path on one part (terms side by side, lanes.h), its fallback for
  // collapsed and faded terms too: here every 50th face's third vertex is moved onto its first
  // (collapsed) or to 5% of its height over the opposite edge (its hinges faded).
  RowMatrixX3d crushed = part_rotated(dragon.V);
  for (int f = 0; f < dragon.F.rows(); f += 50) {
    const Eigen::RowVector3d a = crushed.row(dragon.F(f, 0)), b = crushed.row(dragon.F(f, 1));
    crushed.row(dragon.F(f, 2)) =
        f % 100 ? a : 0.95 * (0.5 * (a + b)) + 0.05 * crushed.row(dragon.F(f, 2));
  }
  for (const Eigen::VectorXd& at : {x, flat(crushed)}) {
    Eigen::VectorXd gs(size), gp(size);
    const double es = serial.value_and_gradient(at, gs), ep = parallel.value_and_gradient(at, gp);
    EXPECT_NEAR(es, ep, 1e-12 * es);
    EXPECT_EQ(gs, gp);
  }
  const SparseMatrix hs = serial.hessian(x), hp = parallel.hessian(x);
  EXPECT_EQ(Eigen::Map<const Eigen::VectorXd>(hs.valuePtr(), hs.nonZeros()),
            Eigen::Map<const Eigen::VectorXd>(hp.valuePtr(), hp.nonZeros()));
  Eigen::MatrixXd Phi(size, 2);
  Phi << random_vector(size, 61), random_vector(size, 62);
  EXPECT_EQ(serial.third(x, Phi.col(0), Phi.col(1)), parallel.third(x, Phi.col(0), Phi.col(1)));
  EXPECT_EQ(serial.third_batch(x, Phi, {{0, 1}}), parallel.third_batch(x, Phi, {{0, 1}}));
  omp_set_num_threads(threads);
}

TEST(DiscreteShells, BadInputIsRefusedWithItsName) {
  const TriangleMesh tube = cylinder(6, 2, 1.0, 2.0);
  expect_input_error([&] { DiscreteShells(tube.V, tube.F, -1.0); }, "bending");
  expect_input_error([&] { DiscreteShells(tube.V, tube.F, 1.0, std::nan("")); }, "membrane");
  RowMatrixX3i bad = tube.F;
  bad(3, 1) = 99;
  expect_input_error([&] { DiscreteShells(tube.V, bad); }, "F[3]");

  const DiscreteShells energy(tube.V, tube.F);
  const Eigen::Index size = tube.V.size();
  Eigen::VectorXd x = energy.rest(), gradient(size);
  expect_input_error([&] { energy.value(Eigen::VectorXd::Zero(size - 1)); }, "X: expected");
  x[7] = std::nan("");  // vertex 2
  expect_input_error([&] { energy.value(x); }, "X[2]: vertex 2");
  expect_input_error([&] { energy.value_and_gradient(x, gradient); }, "X[2]");
  expect_input_error([&] { energy.hessian(x); }, "X[2]");
  expect_input_error([&] { energy.third(energy.rest(), x, energy.rest()); }, "U[2]");
  Eigen::VectorXd short_gradient(size - 3);
  expect_input_error([&] { energy.value_and_gradient(energy.rest(), short_gradient); }, "gradient");
  Eigen::MatrixXd Phi = Eigen::MatrixXd::Ones(size, 3);
  expect_input_error([&] { energy.third_batch(energy.rest(), Phi, {{0, 1}, {2, 3}}); }, "pairs[1]");
  expect_input_error([&] { energy.third_batch(energy.rest(), Phi.topRows(size - 1), {{0, 1}}); },
                     "Phi");
  Phi(4, 2) = INFINITY;
  expect_input_error([&] { energy.third_batch(energy.rest(), Phi, {{0, 1}}); }, "Phi[4, 2]");
}

}  // namespace
}  // namespace modal_deform
