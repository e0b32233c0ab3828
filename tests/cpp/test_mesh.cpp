#include <gtest/gtest.h>

#include <set>

#include "mesh/closest_point.h"
#include "mesh/mass.h"
#include "mesh/mesh_check.h"
#include "mesh/mesh_topology.h"
#include "mesh/primitives.h"
#include "test_support.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

using testing::shared_mesh;

int count_of(const MeshReport& report, const std::string& name) {
  for (const auto& finding : report.findings)
    if (finding.name == name) return finding.count;
  ADD_FAILURE() << "no finding " << name;
  return -1;
}

TEST(Mesh, BunnyIsClosedManifoldAndConnected) {
  const TriangleMesh& bunny = shared_mesh("bunny.obj.gz");
  ASSERT_EQ(bunny.V.rows(), 1839);
  ASSERT_EQ(bunny.F.rows(), 3674);
  const MeshReport report = check_mesh(bunny.V, bunny.F);
  EXPECT_EQ(report.num_components, 1);
  EXPECT_EQ(count_of(report, "boundary_edges"), 0);
  EXPECT_EQ(count_of(report, "nonmanifold_edges"), 0);
  EXPECT_EQ(count_of(report, "unreferenced_vertices"), 0);
  // A closed manifold genus-0 surface: V - E + F = 2, and every edge is a hinge.
  EXPECT_EQ(report.num_vertices - report.num_edges + report.num_faces, 2);
  EXPECT_EQ(build_topology(bunny.V, bunny.F).hinges.size(), size_t(report.num_edges));
}

TEST(Mesh, DragonDefectsAreReported) {
  const TriangleMesh& dragon = shared_mesh("dragon_vrip_res4.ply.gz");
  const MeshReport report = check_mesh(dragon.V, dragon.F);
  EXPECT_EQ(report.num_vertices, 5205);
  EXPECT_EQ(report.num_faces, 11102);
  EXPECT_EQ(count_of(report, "nonmanifold_edges"), 803);
  EXPECT_EQ(count_of(report, "unreferenced_vertices"), 2);
}

TEST(Mesh, NonManifoldEdgeGetsOneHingePerNeighbouringPair) {
  // Three triangles around the edge 0-1, and a fourth folded in between two of them.
  RowMatrixX3d V(6, 3);
  V << 0, 0, 0, 1, 0, 0, 0.5, 1, 0, 0.5, -1, 0, 0.5, 0, 1, 0.5, 0.7, 0.7;
  RowMatrixX3i F(4, 3);
  F << 0, 1, 2, 1, 0, 3, 0, 1, 4, 0, 1, 5;
  const MeshTopology topology = build_topology(V, F);
  ASSERT_EQ(topology.nonmanifold_edges.size(), 1u);
  std::set<std::pair<int, int>> pairs;
  for (const Hinge& hinge : topology.hinges) {
    if (hinge.edge != topology.nonmanifold_edges[0]) continue;
    const int a = hinge.vertices[2], b = hinge.vertices[3];
    pairs.insert({std::min(a, b), std::max(a, b)});
  }
  // About the x axis the opposite vertices lie at 0 (vertex 2), 45 (5), 90 (4) and 180 (3) degrees.
  const std::set<std::pair<int, int>> expected{{2, 5}, {4, 5}, {3, 4}, {2, 3}};
  EXPECT_EQ(pairs, expected);
}

TEST(Mesh, EdgesAreNumberedInOrderOfFirstAppearance) {
  // Face 1 repeats an index (no edges); face 2 shares its side 0-2 with face 0.
  RowMatrixX3d V(5, 3);
  V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 2, 2, 0;
  RowMatrixX3i F(3, 3);
  F << 4, 2, 0, 1, 1, 3, 0, 2, 3;
  const MeshTopology topology = build_topology(V, F);
  const std::vector<std::array<int, 2>> expected{{2, 4}, {0, 2}, {0, 4}, {2, 3}, {0, 3}};
  EXPECT_EQ(topology.edges, expected);
  EXPECT_EQ(topology.face_edges.row(1), Eigen::RowVector3i(-1, -1, -1));
  EXPECT_EQ(topology.face_edges.row(2), Eigen::RowVector3i(1, 3, 4));
  EXPECT_EQ(topology.num_edge_faces(1), 2);
}

TEST(Mesh, HingeRunsAlongItsFirstFace) {
  const TriangleMesh mesh = grid(3, 2, 1.0, 1.0);
  const MeshTopology topology = build_topology(mesh.V, mesh.F);
  for (const Hinge& hinge : topology.hinges) {
    const int f = hinge.faces[0];
    bool found = false;
    for (int k = 0; k < 3; ++k)
      found |= mesh.F(f, k) == hinge.vertices[0] && mesh.F(f, (k + 1) % 3) == hinge.vertices[1] &&
               mesh.F(f, (k + 2) % 3) == hinge.vertices[2];
    EXPECT_TRUE(found) << "hinge of edge " << hinge.edge;
  }
}

TEST(Mesh, BowtieVertexIsNonManifold) {
  RowMatrixX3d V(5, 3);
  V << 0, 0, 0, 1, 0, 0, 1, 1, 0, -1, 0, 0, -1, -1, 0;
  RowMatrixX3i F(2, 3);
  F << 0, 1, 2, 0, 3, 4;
  const MeshTopology topology = build_topology(V, F);
  EXPECT_EQ(topology.nonmanifold_vertices, std::vector<int>{0});
  EXPECT_EQ(topology.num_components, 1);
}

TEST(Mesh, PrimitivesHaveTheExpectedTopology) {
  const TriangleMesh bar_mesh = bar(3, 2, 8, 1, 1, 4);
  const MeshReport closed = check_mesh(bar_mesh.V, bar_mesh.F);
  EXPECT_EQ(count_of(closed, "boundary_edges"), 0);
  EXPECT_EQ(count_of(closed, "nonmanifold_edges"), 0);
  EXPECT_EQ(closed.num_vertices - closed.num_edges + closed.num_faces, 2);

  const TriangleMesh tube = cylinder(16, 5, 1.0, 3.0);
  const MeshReport open = check_mesh(tube.V, tube.F);
  EXPECT_EQ(open.num_vertices, 16 * 6);
  EXPECT_EQ(count_of(open, "boundary_edges"), 32);
  EXPECT_EQ(open.num_vertices - open.num_edges + open.num_faces, 0);
}

TEST(Mesh, BarFacesPointOutwards) {
  const TriangleMesh mesh = bar(2, 3, 4, 1.0, 2.0, 3.0);
  // Divergence theorem: the signed volume equals the box volume only if every face points out.
  double volume = 0;
  for (int f = 0; f < mesh.F.rows(); ++f) {
    const Eigen::Vector3d a = mesh.V.row(mesh.F(f, 0)), b = mesh.V.row(mesh.F(f, 1)),
                          c = mesh.V.row(mesh.F(f, 2));
    volume += a.dot(b.cross(c)) / 6.0;
  }
  EXPECT_NEAR(volume, 6.0, 1e-12);
}

TEST(Mesh, MassSumsToTheSurfaceArea) {
  const TriangleMesh mesh = grid(4, 3, 2.0, 1.5);
  const Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
  EXPECT_NEAR(mass.sum(), 3.0, 1e-12);
  EXPECT_GT(mass.minCoeff(), 0.0);
}

TEST(Mesh, ValidationNamesTheProblem) {
  RowMatrixX3d V(3, 3);
  V << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  RowMatrixX3i F(1, 3);
  F << 0, 1, 3;
  try {
    validate_mesh(V, F);
    FAIL() << "index 3 was accepted";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("F[0]"), std::string::npos) << error.what();
  }
  F << 0, 1, 2;
  V(1, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(validate_mesh(V, F), InputError);
}

TEST(Mesh, DegenerateFacesAreFound) {
  RowMatrixX3d V(4, 3);
  V << 0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0;
  RowMatrixX3i F(3, 3);
  F << 0, 1, 2, 0, 1, 3, 0, 0, 3;
  const MeshReport report = check_mesh(V, F);
  EXPECT_EQ(count_of(report, "degenerate_faces"), 2);
}

}  // namespace
}  // namespace modal_deform

namespace modal_deform {
namespace {

// Inside, beyond an edge, beyond a corner, and on triangles that are a segment or a point.
TEST(ClosestPoint, InsideOnEdgesAtCornersAndOnDegenerateTriangles) {
  const Eigen::Vector3d a(0, 0, 0), b(2, 0, 0), c(0, 2, 0);
  EXPECT_TRUE(
      closest_point_barycentric({0.5, 0.5, 3}, a, b, c).isApprox(Eigen::Vector3d(0.5, 0.25, 0.25)));
  EXPECT_TRUE(
      closest_point_barycentric({1, -1, 0}, a, b, c).isApprox(Eigen::Vector3d(0.5, 0.5, 0)));
  EXPECT_TRUE(closest_point_barycentric({2, 2, 1}, a, b, c).isApprox(Eigen::Vector3d(0, 0.5, 0.5)));
  EXPECT_TRUE(closest_point_barycentric({3, -1, 0}, a, b, c).isApprox(Eigen::Vector3d(0, 1, 0)));
  EXPECT_TRUE(closest_point_barycentric({-1, -1, -1}, a, b, c).isApprox(Eigen::Vector3d(1, 0, 0)));
  const Eigen::Vector3d on_segment =
      closest_point_barycentric({1, 1, 0}, a, b, Eigen::Vector3d(1, 0, 0));
  EXPECT_TRUE((on_segment[0] * a + on_segment[1] * b + on_segment[2] * Eigen::Vector3d(1, 0, 0))
                  .isApprox(Eigen::Vector3d(1, 0, 0)));
  EXPECT_NEAR(on_segment.sum(), 1, 1e-15);
  EXPECT_TRUE(closest_point_barycentric({1, 1, 1}, a, a, a).isApprox(Eigen::Vector3d(1, 0, 0)));
}

}  // namespace
}  // namespace modal_deform
