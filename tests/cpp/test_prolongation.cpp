// The multiresolution bake (issue 15): the prolongation from a proxy to the fine mesh, the bake
// on a proxy, and the solver reading it.
#include <gtest/gtest.h>

#include "bake/bake.h"
#include "mesh/normalization.h"
#include "mesh/primitives.h"
#include "reduction/prolongation.h"
#include "solve/reduced_solver.h"
#include "test_posing.h"
#include "test_support.h"

namespace modal_deform {
namespace {

using testing::expect_input_error;
using testing::rigid_transform;
using testing::vertices_where;

// A fine grid of 20 by 20 quads on the plane z = 0 and a proxy of 5 by 5 on the same square;
// each fine vertex collapses onto its nearest proxy vertex.
struct Grids {
  TriangleMesh fine = grid(20, 20, 1.0, 1.0);
  TriangleMesh proxy = grid(5, 5, 1.0, 1.0);
  Eigen::VectorXi cluster;
  Grids() {
    cluster.resize(fine.V.rows());
    for (Eigen::Index i = 0; i < fine.V.rows(); ++i)
      (proxy.V.rowwise() - fine.V.row(i)).rowwise().squaredNorm().minCoeff(&cluster[i]);
  }
};

TEST(Prolongation, WeightsAreBarycentricAndReproduceFinePointsOnTheProxy) {
  const Grids g;
  const Prolongation P = prolongation_to_proxy(g.fine.V, g.proxy.V, g.proxy.F, g.cluster);
  ASSERT_EQ(P.size(), g.fine.V.rows());
  for (Eigen::Index i = 0; i < P.size(); ++i) {
    EXPECT_GE(P.weights.row(i).minCoeff(), 0.0f);
    EXPECT_NEAR(P.weights.row(i).sum(), 1.0f, 1e-6f);
    Eigen::RowVector3d x = Eigen::RowVector3d::Zero();
    for (int k = 0; k < 3; ++k) x += double(P.weights(i, k)) * g.proxy.V.row(P.vertices(i, k));
    EXPECT_LT((x - g.fine.V.row(i)).norm(), 1e-6) << "fine vertex " << i;
  }
}

TEST(Prolongation, PositionsAreRestPlusTheInterpolatedDisplacement) {
  const Grids g;
  const Prolongation P = prolongation_to_proxy(g.fine.V, g.proxy.V, g.proxy.F, g.cluster);
  // A displacement linear in the rest position reaches the fine vertices exactly (they lie on
  // the proxy), up to float rounding.
  const Eigen::Matrix3d A =
      (Eigen::Matrix3d() << 0.1, -0.2, 0.0, 0.3, 0.05, 0.0, -0.4, 0.2, 0.0).finished();
  const Eigen::VectorXf d = flatten(RowMatrixX3d(g.proxy.V * A.transpose())).cast<float>();
  Eigen::VectorXf out(3 * g.fine.V.rows());
  prolongate_positions(P, flatten(g.fine.V).cast<float>().eval().data(), d.data(), out.data());
  const RowMatrixX3d expected = g.fine.V + g.fine.V * A.transpose();
  EXPECT_LT((out.cast<double>() - flatten(expected)).cwiseAbs().maxCoeff(), 1e-6);
  // Without the rest, the interpolated displacement alone.
  prolongate_positions(P, nullptr, d.data(), out.data());
  EXPECT_LT(
      (out.cast<double>() - flatten(RowMatrixX3d(g.fine.V * A.transpose()))).cwiseAbs().maxCoeff(),
      1e-6);
}

TEST(Prolongation, DetailOffTheProxyStaysInTheRestFrame) {
  Grids g;
  g.fine.V.col(2) =
      0.01 * (7.0 * g.fine.V.col(0)).array().sin().matrix();  // detail the proxy lacks
  const Prolongation P = prolongation_to_proxy(g.fine.V, g.proxy.V, g.proxy.F, g.cluster);
  const Eigen::VectorXf d =
      Eigen::VectorXf::Constant(3 * g.proxy.V.rows(), 0.25f);  // a translation
  Eigen::VectorXf out(3 * g.fine.V.rows());
  prolongate_positions(P, flatten(g.fine.V).cast<float>().eval().data(), d.data(), out.data());
  EXPECT_LT(
      (out.cast<double>() - (flatten(g.fine.V).array() + 0.25).matrix()).cwiseAbs().maxCoeff(),
      1e-6);
}

TEST(Prolongation, BadClusterIsRefused) {
  Grids g;
  g.cluster[5] = static_cast<int>(g.proxy.V.rows());
  expect_input_error([&] { prolongation_to_proxy(g.fine.V, g.proxy.V, g.proxy.F, g.cluster); },
                     "cluster[5]");
  expect_input_error(
      [&] { prolongation_to_proxy(g.fine.V, g.proxy.V, g.proxy.F, g.cluster.head(3)); }, "cluster");
}

// A bumpy plane of about 6,400 vertices baked on a proxy of 800, and the same bake without one.
struct ProxyBake {
  TriangleMesh mesh = bumpy_plane(80, 10.0, 6, 0.4);
  BakeOptions options;
  Basis basis;
  ProxyBake() {
    options.modes = 12;
    options.derivatives = 10;
    options.ghost = 200;
    options.proxy_above = 1000;
    options.proxy = 800;
    Progress progress;
    basis = bake(mesh.V, mesh.F, options, progress);
  }
};

const ProxyBake& proxy_bake() {
  static const ProxyBake bake;
  return bake;
}

TEST(BakeOnProxy, KeepsTheFineMeshAndTheProxysVectors) {
  const ProxyBake& b = proxy_bake();
  const Basis& basis = b.basis;
  ASSERT_TRUE(basis.on_proxy());
  const Eigen::Index n = b.mesh.V.rows();
  EXPECT_EQ(basis.rest, b.mesh.V);
  EXPECT_EQ(basis.mass.size(), n);
  EXPECT_EQ(basis.prolongation.size(), n);
  EXPECT_EQ(basis.ghost_map.size(), n);
  EXPECT_LE(basis.num_basis_vertices(), 800 * 11 / 10);
  EXPECT_GE(basis.num_basis_vertices(), 800 * 9 / 10);
  EXPECT_EQ(basis.vectors.rows(), 3 * basis.num_basis_vertices());
  EXPECT_EQ(basis.dimension(), 22);
  EXPECT_GT(basis.timings.at("proxy"), 0.0);
  EXPECT_GT(basis.timings.at("prolongation"), 0.0);
  // What is kept per fine vertex beyond rest, mass and ghost map: 24 bytes of prolongation
  // instead of 12 r bytes of dense basis.
  const double stored = double(basis.vectors.size()) * sizeof(float) + 24.0 * double(n);
  EXPECT_LT(stored, 0.25 * 12.0 * basis.dimension() * double(n));
  EXPECT_NO_THROW(validate_basis(basis));
}

TEST(BakeOnProxy, SmallerMeshesAreBakedAsTheyAre) {
  const TriangleMesh mesh = bumpy_plane(20, 10.0, 3, 0.4);
  BakeOptions options;
  options.modes = 10;
  options.derivatives = 4;
  options.ghost = 100;
  options.proxy_above = static_cast<int>(mesh.V.rows());
  options.proxy = 200;
  Progress progress;
  const Basis basis = bake(mesh.V, mesh.F, options, progress);
  EXPECT_FALSE(basis.on_proxy());
  EXPECT_EQ(basis.vectors.rows(), 3 * mesh.V.rows());
  options.proxy_above = 300;
  options.proxy = 3;  // fewer than a mesh needs
  expect_input_error([&] { bake(mesh.V, mesh.F, options, progress); },
                     "proxy: expected at least 4, got 3");
  options.proxy = 400;  // more than proxy_above
  expect_input_error([&] { bake(mesh.V, mesh.F, options, progress); }, "proxy: expected between");
  options.proxy_above = -1;
  expect_input_error([&] { bake(mesh.V, mesh.F, options, progress); }, "proxy_above");
}

TEST(BakeOnProxy, ReportsTheProxyAndProlongationStages) {
  const TriangleMesh mesh = bumpy_plane(40, 10.0, 3, 0.4);
  BakeOptions options;
  options.modes = 10;
  options.derivatives = 4;
  options.ghost = 100;
  options.proxy_above = 400;
  options.proxy = 400;
  std::vector<std::string> stages;
  Progress progress(
      [&stages](const std::string& stage, double) {
        if (stages.empty() || stages.back() != stage) stages.push_back(stage);
        return true;
      },
      0.0);
  bake(mesh.V, mesh.F, options, progress);
  ASSERT_FALSE(stages.empty());
  EXPECT_EQ(stages.front(), "proxy");
  EXPECT_EQ(stages.back(), "prolongation");
}

// The solver on a proxy basis poses like the same basis made dense (P U, one row per fine
// vertex): the handle term and positions go through the prolongation correctly.
TEST(BakeOnProxy, SolverAgreesWithTheDenseProlongatedBasis) {
  const ProxyBake& b = proxy_bake();
  Basis dense = b.basis;
  dense.prolongation = Prolongation{};
  dense.vectors.resize(3 * dense.num_vertices(), dense.dimension());
  for (int v = 0; v < dense.num_vertices(); ++v)
    dense.vectors.middleRows<3>(3 * v) = b.basis.vertex_rows(v).cast<float>();
  validate_basis(dense);

  const Handles handles{
      vertices_where(b.mesh.V, [](const Eigen::Vector3d& x) { return x.x() < -4.0; }),
      vertices_where(b.mesh.V, [](const Eigen::Vector3d& x) { return x.x() > 4.0; })};
  const Transforms transforms{Eigen::Matrix4d::Identity(),
                              rigid_transform({0, 1, 0}, 0.5, {4.5, 0, 0}, {0, 0, 1})};
  ReducedSolver on_proxy(b.basis, handles, Eigen::VectorXd(), 1000.0);
  ReducedSolver made_dense(dense, handles, Eigen::VectorXd(), 1000.0);
  on_proxy.set_transforms(transforms);
  made_dense.set_transforms(transforms);
  on_proxy.solve(30, 1e-9);
  made_dense.solve(30, 1e-9);
  EXPECT_LT((on_proxy.q() - made_dense.q()).norm(), 1e-6 * made_dense.q().norm());
  Eigen::VectorXf x(3 * b.mesh.V.rows()), y(3 * b.mesh.V.rows());
  on_proxy.positions(x);
  made_dense.positions(y);
  // Each map is within its 16-bit tolerance of the float32 one (reduced_solver.h), which agree.
  const double map_tolerance = FinePositions::kTolerance * bounding_box_diagonal(b.mesh.V);
  EXPECT_LT((x - y).cwiseAbs().maxCoeff(), 2 * map_tolerance + 1e-5);
  EXPECT_GT((x.cast<double>() - flatten(b.mesh.V)).cwiseAbs().maxCoeff(), 0.1);  // it did move
}

TEST(BakeOnProxy, BadStoredProlongationIsRefused) {
  const Basis& good = proxy_bake().basis;
  Basis bad = good;
  bad.prolongation.vertices(7, 1) = good.num_basis_vertices();
  expect_input_error([&] { validate_basis(bad); }, "prolongation vertices[7]");
  bad = good;
  bad.prolongation.weights(3, 0) += 0.5f;
  expect_input_error([&] { validate_basis(bad); }, "prolongation weights[3]");
  bad = good;
  bad.prolongation.weights(2, 2) = std::numeric_limits<float>::quiet_NaN();
  expect_input_error([&] { validate_basis(bad); }, "prolongation weights");
  bad = good;
  bad.prolongation.vertices.conservativeResize(10, 3);
  expect_input_error([&] { validate_basis(bad); }, "prolongation has");
  bad = good;
  bad.vectors.conservativeResize(bad.vectors.rows() - 1, Eigen::NoChange);
  expect_input_error([&] { validate_basis(bad); }, "vectors has");
}

}  // namespace
}  // namespace modal_deform
