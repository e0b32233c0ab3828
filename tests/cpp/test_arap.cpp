#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "energy/arap.h"
#include "finite_differences.h"
#include "mesh/cotangent_weights.h"
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
using testing::normalized;
using testing::random_vector;
using testing::shared_mesh;
using testing::side_by_side;

using Deformation = std::function<Eigen::Vector3d(const Eigen::Vector3d&)>;

Eigen::VectorXd deformed(const RowMatrixX3d& V, const Deformation& map) {
  Eigen::VectorXd x(3 * V.rows());
  for (Eigen::Index i = 0; i < V.rows(); ++i) x.segment<3>(3 * i) = map(V.row(i).transpose());
  return x;
}

// The large deformations of the brief, for a mesh scaled to a longest bounding-box edge of 10:
// the half above the centre turned by 90 degrees as a whole, a 30% stretch, a 90-degree bend
// along z, and the mirror image.
std::vector<std::pair<std::string, Eigen::VectorXd>> large_deformations(const RowMatrixX3d& V) {
  const Eigen::Vector3d lo = V.colwise().minCoeff(), hi = V.colwise().maxCoeff();
  const Eigen::Vector3d centre = (lo + hi) / 2;
  const double length = hi.z() - lo.z();
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
  return {
      {"upper half turned", deformed(V,
                                     [&](const Eigen::Vector3d& p) -> Eigen::Vector3d {
                                       return p.y() > centre.y()
                                                  ? Eigen::Vector3d(centre + turn * (p - centre))
                                                  : p;
                                     })},
      {"stretched 30%",
       deformed(
           V, [](const Eigen::Vector3d& p) { return Eigen::Vector3d(1.3 * p.x(), p.y(), p.z()); })},
      {"bent 90 degrees",
       deformed(V,
                [&](const Eigen::Vector3d& p) {
                  const double radius = length / (kPi / 2), angle = (p.z() - lo.z()) / radius;
                  const double r = radius - (p.x() - centre.x());
                  return Eigen::Vector3d(centre.x() + radius - r * std::cos(angle), p.y(),
                                         lo.z() + r * std::sin(angle));
                })},
      {"mirrored",
       deformed(V, [](const Eigen::Vector3d& p) { return Eigen::Vector3d(-p.x(), p.y(), p.z()); })},
  };
}

std::vector<std::pair<std::string, TriangleMesh>> test_shapes() {
  return {{"bunny", normalized(shared_mesh("bunny.obj.gz"))},
          {"cylinder", normalized(cylinder(16, 12, 1.0, 4.0))}};
}

TEST(CotangentWeights, RightTrianglesOfAGrid) {
  // Unit squares split along a diagonal: axis edges face 45-degree angles, diagonals 90 degrees.
  const TriangleMesh mesh = grid(3, 2, 3.0, 2.0);
  const MeshTopology topology = build_topology(mesh.V, mesh.F);
  const Eigen::VectorXd weights = cotangent_weights(mesh.V, mesh.F, topology);
  for (size_t e = 0; e < topology.edges.size(); ++e) {
    const Eigen::RowVector3d edge =
        mesh.V.row(topology.edges[e][1]) - mesh.V.row(topology.edges[e][0]);
    const bool diagonal = std::abs(edge.x()) > 0.5 && std::abs(edge.y()) > 0.5;
    const bool boundary = topology.num_edge_faces(static_cast<int>(e)) == 1;
    EXPECT_NEAR(weights[e], diagonal ? 0.0 : boundary ? 0.5 : 1.0, 1e-14) << "edge " << e;
  }
}

TEST(CotangentWeights, DegenerateFacesAddNothingAndSliversAreClamped) {
  RowMatrixX3d V(6, 3);
  V << 0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0, 0.5, 1e-9, 0, 3, 3, 3;
  RowMatrixX3i F(4, 3);
  // Collinear (zero area), a repeated index, an ordinary triangle, and a sliver 1e-9 high.
  F << 0, 1, 2, 0, 0, 3, 0, 1, 3, 1, 0, 4;
  const MeshTopology topology = build_topology(V, F);
  const Eigen::VectorXd weights = cotangent_weights(V, F, topology);
  ASSERT_TRUE(weights.allFinite());
  const std::map<std::array<int, 2>, double> expected{
      {{1, 2}, 0.0},                        // only in the collinear face
      {{1, 3}, 0.0},                        // right angle at vertex 0
      {{0, 3}, 0.5},                        // 45 degrees at vertex 1
      {{0, 1}, 0.5 * (1 - kMaxCotangent)},  // 45 degrees at vertex 3, the sliver's ~180 at vertex 4
      {{0, 4}, 0.5 * kMaxCotangent},        // the sliver's ~0 at vertex 1
  };
  size_t checked = 0;
  for (size_t e = 0; e < topology.edges.size(); ++e) {
    const auto it = expected.find(topology.edges[e]);
    if (it == expected.end()) continue;
    ++checked;
    EXPECT_NEAR(weights[e], it->second, 1e-9) << "edge " << it->first[0] << "-" << it->first[1];
  }
  EXPECT_EQ(checked, expected.size());
}

TEST(Arap, ZeroAtRestAndAfterRigidMotions) {
  for (const auto& [name, mesh] : test_shapes()) {
    SCOPED_TRACE(name);
    const Arap energy(mesh.V, mesh.F);
    const Eigen::Matrix3d rotation =
        Eigen::AngleAxisd(2.0, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
    const Eigen::VectorXd moved = deformed(mesh.V, [&](const Eigen::Vector3d& p) {
      return Eigen::Vector3d(rotation * p + Eigen::Vector3d(3, -1, 7));
    });
    for (const Eigen::VectorXd& x : {energy.rest(), moved}) {
      EXPECT_LT(std::abs(energy.value(x)), 1e-20);
      Eigen::VectorXd gradient(x.size());
      EXPECT_LT(std::abs(energy.value_and_gradient(x, gradient)), 1e-20);
      EXPECT_LT(gradient.lpNorm<Eigen::Infinity>(), 1e-11);
    }
  }
}

// Regression (fuzz_mesh_entry_points): a triangle scaled by 5e-324 (collapsed to denormals) gave
// f_ωω eigenvalues too small to invert and an infinite Hessian; so did any cell collapsed far
// below its rest size.
TEST(Arap, HessianOfACollapsedMeshIsFinite) {
  const TriangleMesh triangle = mesh_from_buffers({0, 0, -1.984375, 1, 0, 0, 0, 1, 0}, {0, 2, 1});
  const Arap energy(triangle.V, triangle.F);
  for (double scale : {5e-324, 1e-300, 1e-160, 0.0}) {
    const Eigen::VectorXd x = scale * energy.rest();
    const SparseMatrix H = energy.hessian(x);
    EXPECT_TRUE(Eigen::Map<const Eigen::VectorXd>(H.valuePtr(), H.nonZeros()).allFinite()) << scale;
  }
}

TEST(Arap, MirrorImageCostsMoreThanAStretch) {
  // Without the reflection fix each cell would fit its mirror image exactly (E = 0).
  for (const auto& [name, mesh] : test_shapes()) {
    SCOPED_TRACE(name);
    const Arap energy(mesh.V, mesh.F);
    const auto deformations = large_deformations(mesh.V);
    const double stretched = energy.value(deformations[1].second),
                 mirrored = energy.value(deformations[3].second);
    EXPECT_GT(stretched, 1.0);
    EXPECT_GT(mirrored, stretched);
  }
}

TEST(Arap, GradientMatchesFiniteDifferences) {
  for (const auto& [name, mesh] : test_shapes()) {
    const Arap energy(mesh.V, mesh.F);
    const Eigen::VectorXd d = random_vector(energy.rest().size(), 7);
    expect_gradient_matches(energy, energy.rest(), d, name + " at rest");
    for (const auto& [deformation, x] : large_deformations(mesh.V)) {
      expect_gradient_matches(energy, x, d, name + " " + deformation);
      Eigen::VectorXd gradient(x.size());
      EXPECT_DOUBLE_EQ(energy.value_and_gradient(x, gradient), energy.value(x));
    }
  }
}

TEST(Arap, HessianMatchesFiniteDifferencesOfTheGradient) {
  for (const auto& [name, mesh] : test_shapes()) {
    const Arap energy(mesh.V, mesh.F);
    const Eigen::VectorXd d = random_vector(energy.rest().size(), 11);
    expect_hessian_matches(energy, energy.rest(), d, name + " at rest");
    for (const auto& [deformation, x] : large_deformations(mesh.V))
      expect_hessian_matches(energy, x, d, name + " " + deformation);
  }
}

TEST(Arap, LargeMeshesRunInParallelWithTheSameDerivatives) {
  // 23k vertices: above the threshold for threads, and full of obtuse and non-manifold triangles.
  // Its slivers are short, so the steps are too. (Bent by 90 degrees, a few cells of the dragons
  // come within 1e-4 of a jump of their best rotation, where E has a kink: stretched instead.)
  const TriangleMesh mesh = normalized(shared_mesh("dragon_vrip_res3.ply.gz"));
  const Arap energy(mesh.V, mesh.F);
  const Eigen::VectorXd x = large_deformations(mesh.V)[1].second;
  expect_gradient_matches(energy, x, random_vector(x.size(), 7), "dragon stretched", 1e-6, 1e-4);
  expect_hessian_matches(energy, x, random_vector(x.size(), 11), "dragon stretched", 1e-6, 1e-4);
}

// Eigenvalues of the rest Hessian, checked for symmetry first.
Eigen::VectorXd rest_hessian_eigenvalues(const TriangleMesh& mesh) {
  const Arap energy(mesh.V, mesh.F);
  const Eigen::MatrixXd H = Eigen::MatrixXd(energy.hessian(energy.rest()));
  EXPECT_LT((H - H.transpose()).norm(), 1e-13 * H.norm());
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(H, Eigen::EigenvaluesOnly).eigenvalues();
}

TEST(Arap, RestHessianIsPsdWithSixZeroModesPerComponent) {
  // A grid jittered in its plane has obtuse triangles, so some weights are clamped. (A perfect grid
  // of right triangles would not do: its diagonals have weight cot 90° = 0 and the twist u_z = xy
  // then costs nothing, a seventh zero mode of the cotangent energy itself.)
  TriangleMesh jittered = grid(5, 5, 1.0, 1.0);
  const Eigen::VectorXd jitter = random_vector(2 * jittered.V.rows(), 3);
  for (Eigen::Index v = 0; v < jittered.V.rows(); ++v)
    jittered.V.row(v).head<2>() += 0.05 * jitter.segment<2>(2 * v);
  const std::vector<std::tuple<std::string, TriangleMesh, int>> cases{
      {"cylinder", cylinder(8, 3, 1.0, 3.0), 1},
      {"bar", bar(2, 2, 3, 1.0, 1.0, 3.0), 1},
      {"bumpy plane", bumpy_plane(6, 10.0, 3, 2.0), 1},
      {"jittered grid", jittered, 1},
      {"cylinder and bar",
       side_by_side(cylinder(8, 3, 1.0, 3.0), bar(2, 2, 3, 1.0, 1.0, 3.0),
                    Eigen::RowVector3d(20, 0, 0)),
       2},
  };
  for (const auto& [name, mesh, components] : cases) {
    SCOPED_TRACE(name);
    const Eigen::VectorXd eigenvalues = rest_hessian_eigenvalues(mesh);
    const double largest = eigenvalues.maxCoeff();
    EXPECT_GT(eigenvalues.minCoeff(), -1e-12 * largest);
    EXPECT_EQ((eigenvalues.array().abs() < 1e-9 * largest).count(), 6 * components);
    // The seventh eigenvalue is clearly apart from zero.
    EXPECT_GT(eigenvalues[6 * components], 1e-5 * largest);
  }
}

TEST(Arap, ObtuseTrianglesKeepTheRestStateTheMinimum) {
  // Vertex 1's cell: raw weights ½ cot 5.7° = 5 (edge to 0) and ½ cot 168.6° ≈ −2.5 (edge to 2)
  // give an indefinite covariance, whose best rotation at rest turns by 180 degrees (E < 0).
  RowMatrixX3d V(3, 3);
  V << 0, 0.1, 0, -1, 0, 0, 1, 0, 0;
  RowMatrixX3i F(1, 3);
  F << 0, 1, 2;
  const Arap triangle(V, F);
  EXPECT_LT(std::abs(triangle.value(triangle.rest())), 1e-20);
  const Eigen::VectorXd eigenvalues =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(
          Eigen::MatrixXd(triangle.hessian(triangle.rest())), Eigen::EigenvaluesOnly)
          .eigenvalues();
  EXPECT_GT(eigenvalues.minCoeff(), -1e-12 * eigenvalues.maxCoeff());
  EXPECT_EQ((eigenvalues.array().abs() < 1e-9 * eigenvalues.maxCoeff()).count(), 6);

  // With raw cotangent weights 201 cells of this dragon would not fit the identity at rest.
  const TriangleMesh dragon = normalized(shared_mesh("dragon_vrip_res4.ply.gz"));
  const Arap energy(dragon.V, dragon.F);
  Eigen::VectorXd gradient(energy.rest().size());
  EXPECT_LT(std::abs(energy.value_and_gradient(energy.rest(), gradient)), 1e-20);
  EXPECT_LT(gradient.lpNorm<Eigen::Infinity>(), 1e-11);
}

TEST(Arap, DegenerateTrianglesAndLooseVerticesStayFinite) {
  // A fan around vertex 0, plus a collinear face, a repeated index, a 1e-9 sliver, a face with
  // two vertices in one place (8 on 1) and an unreferenced vertex (7).
  RowMatrixX3d V(9, 3);
  V << 0, 0, 0, 1, 0, 0, 0.3, 1, 0.2, -1, 0.2, 0, 0.5, -1, 0.1, 2, 0, 0, 0.5, 1e-9, 0, 5, 5, 5, 1,
      0, 0;
  RowMatrixX3i F(8, 3);
  F << 0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 1, 0, 1, 5, 2, 2, 3, 0, 6, 1, 1, 8, 2;
  const Arap energy(V, F);
  EXPECT_LT(std::abs(energy.value(energy.rest())), 1e-20);
  const Eigen::VectorXd x = energy.rest() + 0.2 * random_vector(energy.rest().size(), 5);
  Eigen::VectorXd gradient(x.size());
  EXPECT_TRUE(std::isfinite(energy.value_and_gradient(x, gradient)));
  EXPECT_TRUE(gradient.allFinite());
  EXPECT_EQ(gradient.segment<3>(21), Eigen::Vector3d::Zero());
  const SparseMatrix H = energy.hessian(x);
  EXPECT_TRUE(Eigen::MatrixXd(H).allFinite());
  EXPECT_EQ(Eigen::MatrixXd(H).middleRows<3>(21).norm(), 0.0);
  expect_gradient_matches(energy, x, random_vector(x.size(), 7), "degenerate fan");
  expect_hessian_matches(energy, x, random_vector(x.size(), 11), "degenerate fan");
}

TEST(Arap, SharedDragonsGiveFiniteValues) {
  for (const char* file :
       {"dragon_vrip_res4.ply.gz", "dragon_vrip_res3.ply.gz", "dragon_vrip_res2.ply.gz"}) {
    SCOPED_TRACE(file);
    const TriangleMesh mesh = normalized(shared_mesh(file));
    const Arap energy(mesh.V, mesh.F);
    for (const auto& [name, x] : large_deformations(mesh.V)) {
      Eigen::VectorXd gradient(x.size());
      const double value = energy.value_and_gradient(x, gradient);
      EXPECT_TRUE(std::isfinite(value) && value > 0) << name;
      EXPECT_TRUE(gradient.allFinite()) << name;
    }
    if (mesh.V.rows() < 50000) {
      const SparseMatrix H = energy.hessian(large_deformations(mesh.V)[0].second);
      EXPECT_TRUE(Eigen::Map<const Eigen::VectorXd>(H.valuePtr(), H.nonZeros()).allFinite());
    }
  }
}

TEST(Arap, ThirdDerivativePointsToTheShellsEnergy) {
  const TriangleMesh mesh = cylinder(6, 2, 1.0, 2.0);
  const Arap energy(mesh.V, mesh.F);
  try {
    energy.third(energy.rest(), energy.rest(), energy.rest());
    FAIL() << "third() returned";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("shells"), std::string::npos) << error.what();
  }
}

TEST(Arap, BadPositionsAreNamed) {
  const TriangleMesh mesh = cylinder(6, 2, 1.0, 2.0);
  const Arap energy(mesh.V, mesh.F);
  Eigen::VectorXd x = energy.rest();
  x[3 * 5 + 1] = std::numeric_limits<double>::infinity();
  Eigen::VectorXd gradient(x.size());
  for (const auto& call : std::vector<std::function<void()>>{
           [&] { energy.value(x); }, [&] { energy.value_and_gradient(x, gradient); },
           [&] { energy.hessian(x); }}) {
    try {
      call();
      FAIL() << "a non-finite position was accepted";
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find("X[5]"), std::string::npos) << error.what();
    }
  }
  EXPECT_THROW(energy.value(energy.rest().head(9)), InputError);
  Eigen::VectorXd short_gradient(3);
  EXPECT_THROW(energy.value_and_gradient(energy.rest(), short_gradient), InputError);
  RowMatrixX3i F = mesh.F;
  F(2, 1) = 99;
  EXPECT_THROW(Arap(mesh.V, F), InputError);
}

}  // namespace
}  // namespace modal_deform
