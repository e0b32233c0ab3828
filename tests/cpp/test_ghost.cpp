#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "mesh/edge_collapse.h"
#include "mesh/mass.h"
#include "mesh/mesh_check.h"
#include "mesh/mesh_topology.h"
#include "mesh/primitives.h"
#include "mesh/union_find.h"
#include "reduction/ghost.h"
#include "test_support.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

using testing::expect_input_error;
using testing::shared_mesh;

Eigen::Vector3d face_normal(const RowMatrixX3d& V, const RowMatrixX3i& F, int f) {
  const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
  return (b - a).cross(c - a);
}

// 4√3·area / Σ edge²: 1 for an equilateral triangle, 0 for a degenerate one.
double face_quality(const RowMatrixX3d& V, const RowMatrixX3i& F, int f) {
  const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
  return 2 * std::sqrt(3.0) * (b - a).cross(c - a).norm() /
         ((b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm());
}

std::array<int, 3> sorted_triple(int a, int b, int c) {
  std::array<int, 3> t{a, b, c};
  std::sort(t.begin(), t.end());
  return t;
}

// What every ghost must be, whatever the input: each fine vertex on one ghost vertex, each ghost
// vertex the mass-weighted centroid of its fine vertices (plain mean without mass), a triangle
// mesh without degenerate or duplicate faces, and no face flipped: the area-weighted normal of
// the fine faces that map onto a ghost face (their three vertices in its three clusters) agrees
// in sign with the ghost face's normal. No needles either: a ghost face is at least as good as
// kMinFaceQuality or as the worst fine face mapping onto it.
void expect_valid_ghost(const TriangleMesh& fine, const Eigen::VectorXd& mass, const Ghost& ghost) {
  const int n = static_cast<int>(fine.V.rows()), g = static_cast<int>(ghost.V.rows());
  ASSERT_EQ(ghost.map.size(), n);
  ASSERT_GT(g, 0);
  ASSERT_TRUE(ghost.V.allFinite());
  std::vector<int> size(g, 0);
  std::vector<double> cluster_mass(g, 0.0);
  for (int i = 0; i < n; ++i) {
    ASSERT_TRUE(ghost.map[i] >= 0 && ghost.map[i] < g)
        << "fine vertex " << i << " maps to " << ghost.map[i];
    ++size[ghost.map[i]];
    cluster_mass[ghost.map[i]] += mass[i];
  }
  for (int s = 0; s < g; ++s)
    ASSERT_GT(size[s], 0) << "ghost vertex " << s << " has no fine vertex";

  RowMatrixX3d centroid = RowMatrixX3d::Zero(g, 3);
  for (int i = 0; i < n; ++i) {
    const int s = ghost.map[i];
    const double w = cluster_mass[s] > 0 ? mass[i] / cluster_mass[s] : 1.0 / size[s];
    centroid.row(s) += w * fine.V.row(i);
  }
  const double extent = (fine.V.colwise().maxCoeff() - fine.V.colwise().minCoeff()).maxCoeff();
  EXPECT_LE((centroid - ghost.V).cwiseAbs().maxCoeff(), 1e-12 * extent);

  ASSERT_GT(ghost.F.rows(), 0);
  ASSERT_GE(ghost.F.minCoeff(), 0);
  ASSERT_LT(ghost.F.maxCoeff(), g);
  std::map<std::array<int, 3>, int> face_of;
  for (int f = 0; f < ghost.F.rows(); ++f) {
    EXPECT_FALSE(is_degenerate_face(ghost.V, ghost.F, f)) << "ghost face " << f;
    EXPECT_TRUE(
        face_of.emplace(sorted_triple(ghost.F(f, 0), ghost.F(f, 1), ghost.F(f, 2)), f).second)
        << "duplicate ghost face " << f;
  }
  std::vector<Eigen::Vector3d> ancestors(ghost.F.rows(), Eigen::Vector3d::Zero());
  std::vector<double> worst_ancestor(ghost.F.rows(), 1.0);
  for (int f = 0; f < fine.F.rows(); ++f) {
    const auto it = face_of.find(
        sorted_triple(ghost.map[fine.F(f, 0)], ghost.map[fine.F(f, 1)], ghost.map[fine.F(f, 2)]));
    if (it == face_of.end()) continue;
    ancestors[it->second] += face_normal(fine.V, fine.F, f);
    worst_ancestor[it->second] =
        std::min(worst_ancestor[it->second], face_quality(fine.V, fine.F, f));
  }
  int flipped = 0, needles = 0;
  for (int f = 0; f < ghost.F.rows(); ++f) {
    flipped += !(face_normal(ghost.V, ghost.F, f).dot(ancestors[f]) > 0);
    needles +=
        face_quality(ghost.V, ghost.F, f) < std::min(kMinFaceQuality, worst_ancestor[f]) - 1e-6;
  }
  EXPECT_EQ(flipped, 0) << "of " << ghost.F.rows() << " ghost faces";
  EXPECT_EQ(needles, 0) << "of " << ghost.F.rows() << " ghost faces";
}

// On a clean mesh and a ghost that still resolves its shape a stronger test holds: the normal of
// each ghost face agrees in sign with the area-weighted normal of all fine faces whose vertices
// lie in its three clusters (including those collapsed away inside them). It does not hold on
// the dragons, whose decimation left faces folded back over their neighbours.
void expect_agrees_with_region_normals(const TriangleMesh& fine, const Ghost& ghost) {
  std::vector<std::vector<int>> faces_around(ghost.V.rows());
  for (int f = 0; f < ghost.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) faces_around[ghost.F(f, k)].push_back(f);
  std::vector<Eigen::Vector3d> region(ghost.F.rows(), Eigen::Vector3d::Zero());
  for (int f = 0; f < fine.F.rows(); ++f) {
    const std::set<int> clusters{ghost.map[fine.F(f, 0)], ghost.map[fine.F(f, 1)],
                                 ghost.map[fine.F(f, 2)]};
    for (int h : faces_around[*clusters.begin()]) {
      bool inside = true;
      for (int s : clusters)
        inside &= ghost.F(h, 0) == s || ghost.F(h, 1) == s || ghost.F(h, 2) == s;
      if (inside) region[h] += face_normal(fine.V, fine.F, f);
    }
  }
  for (int f = 0; f < ghost.F.rows(); ++f)
    EXPECT_GT(face_normal(ghost.V, ghost.F, f).dot(region[f]), 0) << "ghost face " << f;
}

int euler_characteristic(const TriangleMesh& mesh) {
  const MeshTopology topology = build_topology(mesh.V, mesh.F);
  return static_cast<int>(mesh.V.rows() - topology.unreferenced_vertices.size()) -
         static_cast<int>(topology.edges.size()) + static_cast<int>(mesh.F.rows());
}

int count_boundary_loops(const TriangleMesh& mesh) {
  const MeshTopology topology = build_topology(mesh.V, mesh.F);
  UnionFind loops(static_cast<int>(mesh.V.rows()));
  std::set<int> on_boundary;
  for (int e : topology.boundary_edges) {
    loops.unite(topology.edges[e][0], topology.edges[e][1]);
    on_boundary.insert(topology.edges[e][0]);
  }
  std::set<int> roots;
  for (int v : on_boundary) roots.insert(loops.find(v));
  return static_cast<int>(roots.size());
}

std::vector<char> boundary_vertices(const TriangleMesh& mesh) {
  const MeshTopology topology = build_topology(mesh.V, mesh.F);
  std::vector<char> on_boundary(mesh.V.rows(), 0);
  for (int e : topology.boundary_edges)
    on_boundary[topology.edges[e][0]] = on_boundary[topology.edges[e][1]] = 1;
  return on_boundary;
}

// Simplifies a manifold mesh and checks validity, the target, and that topology and boundary
// are kept: same Euler characteristic, components and boundary loops, and the ghost's boundary
// vertices are exactly the clusters of the fine boundary vertices.
void expect_topology_kept(const TriangleMesh& fine, int target) {
  SCOPED_TRACE(::testing::Message() << "target " << target);
  const Eigen::VectorXd mass = lumped_mass(fine.V, fine.F);
  const Ghost ghost = ghost_mesh(fine.V, fine.F, mass, target);
  expect_valid_ghost(fine, mass, ghost);
  EXPECT_EQ(ghost.V.rows(), target);
  const TriangleMesh coarse{ghost.V, ghost.F};
  EXPECT_EQ(euler_characteristic(coarse), euler_characteristic(fine));
  EXPECT_EQ(build_topology(coarse.V, coarse.F).num_components,
            build_topology(fine.V, fine.F).num_components);
  EXPECT_EQ(build_topology(coarse.V, coarse.F).nonmanifold_edges.size(), 0u);
  EXPECT_EQ(count_boundary_loops(coarse), count_boundary_loops(fine));
  const std::vector<char> fine_boundary = boundary_vertices(fine),
                          coarse_boundary = boundary_vertices(coarse);
  for (int i = 0; i < fine.V.rows(); ++i)
    ASSERT_EQ(fine_boundary[i], coarse_boundary[ghost.map[i]]) << "fine vertex " << i;
}

TriangleMesh two_cylinders() {
  return testing::side_by_side(cylinder(24, 20, 1.0, 4.0), cylinder(16, 30, 0.5, 6.0),
                               Eigen::RowVector3d(3, 0, 0));
}

// A bumpy plane with what scans contain: coincident vertices (zero-area faces), a face with a
// repeated index, a duplicate face, two faces cancelled by an opposite copy, and unreferenced
// vertices.
TriangleMesh messy_plane() {
  const TriangleMesh plane = bumpy_plane(30, 10.0, 6, 1.0);
  const int n = static_cast<int>(plane.V.rows()), m = static_cast<int>(plane.F.rows());
  auto at = [](int i, int j) { return j * 31 + i; };
  TriangleMesh mesh;
  mesh.V.resize(n + 2, 3);
  mesh.V << plane.V, Eigen::RowVector3d(20, 20, 20), Eigen::RowVector3d(-3, 0, 0);
  for (int j : {5, 12, 20}) mesh.V.row(at(10, j)) = mesh.V.row(at(11, j));
  mesh.F.resize(m + 4, 3);
  mesh.F.topRows(m) = plane.F;
  mesh.F.row(m) << at(7, 7), at(7, 7), at(8, 7);
  mesh.F.row(m + 1) = plane.F.row(100);
  mesh.F.row(m + 2) << plane.F(200, 0), plane.F(200, 2), plane.F(200, 1);
  mesh.F.row(m + 3) << plane.F(300, 1), plane.F(300, 0), plane.F(300, 2);
  return mesh;
}

// Each shape at a moderate target and at a small one, where only the link condition and the
// boundary rule stand between the collapse and a changed topology or a pulled-in boundary.
TEST(Ghost, BunnyStaysAClosedGenusZeroSurface) {
  for (int target : {300, 20}) expect_topology_kept(shared_mesh("bunny.obj.gz"), target);
}

TEST(Ghost, GridStaysADiscWithItsBoundary) {
  for (int target : {150, 12}) expect_topology_kept(grid(30, 30, 10.0, 10.0), target);
}

TEST(Ghost, CylinderKeepsBothRims) {
  for (int target : {200, 12}) expect_topology_kept(cylinder(32, 30, 1.0, 6.0), target);
}

TEST(Ghost, TwoCylindersStayTwoComponents) {
  for (int target : {250, 24}) expect_topology_kept(two_cylinders(), target);
}

TEST(Ghost, BumpyPlaneKeepsItsBoundary) {
  for (int target : {300, 12}) expect_topology_kept(bumpy_plane(40, 10.0, 12, 1.0), target);
}

TEST(Ghost, FacesAgreeWithTheNormalsOfTheRegionTheyCover) {
  const std::vector<std::pair<TriangleMesh, int>> cases{{shared_mesh("bunny.obj.gz"), 300},
                                                        {cylinder(32, 30, 1.0, 6.0), 200},
                                                        {bumpy_plane(40, 10.0, 12, 1.0), 300}};
  for (const auto& [mesh, target] : cases)
    expect_agrees_with_region_normals(
        mesh, ghost_mesh(mesh.V, mesh.F, lumped_mass(mesh.V, mesh.F), target));
}

// A region bake's proxy: a bumpy plane split by the line x = 0 into sides that never merge, and
// the vertices on either side of the line merge only along it, so every cluster that holds one of
// them has its centroid one column off the line, as the fine vertices there have. (Without the
// rule along the line, at this target clusters reach across the line and away from it.)
TEST(Ghost, SidesStayApartAndTheLineBetweenThemStays) {
  const TriangleMesh plane = bumpy_plane(40, 10.0, 12, 1.0);
  const Eigen::VectorXd mass = lumped_mass(plane.V, plane.F);
  const double column = 10.0 / 40;
  std::vector<char> sides(static_cast<size_t>(plane.V.rows()));
  for (Eigen::Index i = 0; i < plane.V.rows(); ++i)
    sides[static_cast<size_t>(i)] = plane.V(i, 0) > 1e-9;
  const Ghost ghost = ghost_mesh(plane.V, plane.F, mass, 150, nullptr, sides);
  expect_valid_ghost(plane, mass, ghost);
  EXPECT_LE(ghost.V.rows(), 160);
  const auto g = static_cast<size_t>(ghost.V.rows());
  std::vector<std::set<char>> cluster_sides(g);
  std::vector<char> on_line(g, 0);
  for (Eigen::Index i = 0; i < plane.V.rows(); ++i) {
    cluster_sides[static_cast<size_t>(ghost.map[i])].insert(sides[static_cast<size_t>(i)]);
    if (std::abs(plane.V(i, 0)) < 1e-9 || std::abs(plane.V(i, 0) - column) < 1e-9)
      on_line[static_cast<size_t>(ghost.map[i])] = 1;
  }
  int line_clusters = 0;
  for (size_t c = 0; c < g; ++c) {
    EXPECT_EQ(cluster_sides[c].size(), 1u) << "ghost vertex " << c << " holds both sides";
    if (!on_line[c]) continue;
    ++line_clusters;
    const double x = ghost.V(static_cast<Eigen::Index>(c), 0);
    EXPECT_TRUE(std::abs(x) < 1e-9 || std::abs(x - column) < 1e-9)
        << "ghost vertex " << c << " at x " << x;
  }
  EXPECT_GT(line_clusters, 4);
  EXPECT_THROW(ghost_mesh(plane.V, plane.F, mass, 150, nullptr, std::vector<char>(3, 0)),
               InputError);
}

class GhostOfDragon : public ::testing::TestWithParam<std::pair<std::string, int>> {};

TEST_P(GhostOfDragon, IsValidAndReachesTheTarget) {
  const auto& [file, target] = GetParam();
  const TriangleMesh& dragon = shared_mesh(file);
  const Eigen::VectorXd mass = lumped_mass(dragon.V, dragon.F);
  const Ghost ghost = ghost_mesh(dragon.V, dragon.F, mass, target);
  expect_valid_ghost(dragon, mass, ghost);
  EXPECT_LE(ghost.V.rows(), target + target / 20);
  EXPECT_TRUE(build_topology(ghost.V, ghost.F).unreferenced_vertices.empty());
}

INSTANTIATE_TEST_SUITE_P(Scans, GhostOfDragon,
                         ::testing::Values(std::make_pair("dragon_vrip_res4.ply.gz", 500),
                                           std::make_pair("dragon_vrip_res4.ply.gz", 2000),
                                           std::make_pair("dragon_vrip_res3.ply.gz", 1000)));

TEST(Ghost, MessyInputGivesACleanGhost) {
  const TriangleMesh mesh = messy_plane();
  const MeshReport report = check_mesh(mesh.V, mesh.F);
  for (const auto& finding : report.findings) {
    if (finding.name == "degenerate_faces" || finding.name == "duplicate_faces" ||
        finding.name == "unreferenced_vertices") {
      ASSERT_GT(finding.count, 0) << finding.name;
    }
  }
  const Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
  for (int target : {600, 100}) {
    const Ghost ghost = ghost_mesh(mesh.V, mesh.F, mass, target);
    expect_valid_ghost(mesh, mass, ghost);
    EXPECT_EQ(ghost.V.rows(), target);
  }
}

// A 30 by 30 grid of side 1 with a fin of no thickness standing on its middle row: 3 rows of
// quads, 0.003 high each (a tenth of the grid's spacing), on the same vertices on both sides, cut
// along one diagonal on the front and the other on the back. So
// tests/support/subdivision.split_edges cuts the two copies of a scan's double-sheet face, and so
// the dragon refined to 3.2M vertices is full of them. (#V = 961 grid vertices, then the fin's, row
// after row.)
TriangleMesh grid_with_a_fin(int* first_fin_vertex) {
  const TriangleMesh plane = grid(30, 30, 1.0, 1.0);
  constexpr int kColumns = 31, kRows = 3;
  constexpr double kHeight = 0.003;
  const auto base = [](int i) { return 15 * kColumns + i; };  // the middle row of the grid
  const int n = static_cast<int>(plane.V.rows());
  const auto fin = [&](int i, int r) { return r == 0 ? base(i) : n + (r - 1) * kColumns + i; };
  TriangleMesh mesh;
  mesh.V.resize(n + kRows * kColumns, 3);
  mesh.V.topRows(n) = plane.V;
  for (int r = 1; r <= kRows; ++r)
    for (int i = 0; i < kColumns; ++i)
      mesh.V.row(fin(i, r)) = plane.V.row(base(i)) + Eigen::RowVector3d(0, 0, r * kHeight);
  std::vector<int> faces(plane.F.data(), plane.F.data() + plane.F.size());
  for (int r = 0; r < kRows; ++r)
    for (int i = 0; i + 1 < kColumns; ++i) {
      const int a = fin(i, r), b = fin(i + 1, r), c = fin(i + 1, r + 1), d = fin(i, r + 1);
      faces.insert(faces.end(), {a, b, c, a, c, d});  // the front, cut along ac
      faces.insert(faces.end(), {a, d, b, b, d, c});  // the back, reversed, cut along bd
    }
  mesh.F =
      Eigen::Map<const RowMatrixX3i>(faces.data(), static_cast<Eigen::Index>(faces.size() / 3), 3);
  *first_fin_vertex = n;
  return mesh;
}

// The fin's two sides become copies of each other's faces only as its vertices merge: they must
// cancel then, as copies in the input do. Refused as duplicates, they left every fin vertex a
// cluster of its own (93 of 93 here), and the 3.2M dragon's 50k proxy 2,310 single fine vertices
// whose tiny elements made K − σM impossible to factor (issue 23).
TEST(Ghost, ASheetOfNoThicknessCutTwoWaysCollapsesAndCancels) {
  int first_fin_vertex = 0;
  const TriangleMesh mesh = grid_with_a_fin(&first_fin_vertex);
  ASSERT_GT(build_topology(mesh.V, mesh.F).nonmanifold_edges.size(), 0u);
  const Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
  const Ghost ghost = ghost_mesh(mesh.V, mesh.F, mass, 150);
  expect_valid_ghost(mesh, mass, ghost);
  EXPECT_EQ(ghost.V.rows(), 150);
  std::vector<int> size(ghost.V.rows(), 0);
  for (Eigen::Index i = 0; i < ghost.map.size(); ++i) ++size[ghost.map[i]];
  int alone = 0;
  for (Eigen::Index i = first_fin_vertex; i < mesh.V.rows(); ++i) alone += size[ghost.map[i]] == 1;
  EXPECT_EQ(alone, 0) << "of " << mesh.V.rows() - first_fin_vertex
                      << " fin vertices are clusters of their own";
}

TEST(Ghost, UnreferencedVerticesJoinTheNearestGhostVertex) {
  const TriangleMesh mesh = messy_plane();
  const Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
  const Ghost ghost = ghost_mesh(mesh.V, mesh.F, mass, 100);
  for (Eigen::Index i : {mesh.V.rows() - 2, mesh.V.rows() - 1}) {
    Eigen::Index nearest;
    (ghost.V.rowwise() - mesh.V.row(i)).rowwise().squaredNorm().minCoeff(&nearest);
    EXPECT_EQ(ghost.map[i], nearest) << "fine vertex " << i;
  }
}

// A bake error on a proxy names the fine vertex nearest to the proxy vertex (bake.cpp): one that
// collapsed onto it, and none of those nearer.
TEST(Ghost, NearestFineVertexIsTheClosestOfThoseCollapsedOntoIt) {
  const TriangleMesh plane = bumpy_plane(30, 10.0, 6, 1.0);
  const Ghost ghost = ghost_mesh(plane.V, plane.F, lumped_mass(plane.V, plane.F), 50);
  for (int g = 0; g < ghost.V.rows(); ++g) {
    const int nearest = nearest_fine_vertex(ghost, plane.V, g);
    ASSERT_EQ(ghost.map[nearest], g);
    const double distance = (plane.V.row(nearest) - ghost.V.row(g)).norm();
    for (Eigen::Index i = 0; i < plane.V.rows(); ++i)
      if (ghost.map[i] == g) {
        ASSERT_LE(distance, (plane.V.row(i) - ghost.V.row(g)).norm()) << "ghost vertex " << g;
      }
  }
  expect_input_error([&] { nearest_fine_vertex(ghost, plane.V, static_cast<int>(ghost.V.rows())); },
                     "g");
  expect_input_error([&] { nearest_fine_vertex(ghost, plane.V.topRows(10), 0); }, "fine_V");
}

TEST(Ghost, ClustersWithoutMassUseThePlainMean) {
  const TriangleMesh plane = bumpy_plane(20, 10.0, 4, 1.0);
  Eigen::VectorXd mass = lumped_mass(plane.V, plane.F);
  for (int i = 0; i < mass.size(); ++i)
    if (plane.V(i, 0) < 0) mass[i] = 0;  // half the plane weighs nothing
  const Ghost ghost = ghost_mesh(plane.V, plane.F, mass, 60);
  expect_valid_ghost(plane, mass, ghost);
}

TEST(Ghost, TargetOfAtLeastTheVertexCountGivesTheMeshItself) {
  const TriangleMesh& dragon = shared_mesh("dragon_vrip_res4.ply.gz");
  const Eigen::VectorXd mass = lumped_mass(dragon.V, dragon.F);
  const Ghost ghost = ghost_mesh(dragon.V, dragon.F, mass, static_cast<int>(dragon.V.rows()));
  EXPECT_EQ(ghost.V, dragon.V);
  EXPECT_EQ(ghost.F, dragon.F);
  EXPECT_EQ(ghost.map,
            Eigen::VectorXi::LinSpaced(dragon.V.rows(), 0, static_cast<int>(dragon.V.rows()) - 1));
}

// The 6 rigid motions of the fine mesh as columns: translations along x, y, z and linearised
// rotations ω × x about the axes.
Eigen::MatrixXd rigid_motions(const RowMatrixX3d& V) {
  Eigen::MatrixXd U = Eigen::MatrixXd::Zero(3 * V.rows(), 6);
  for (Eigen::Index i = 0; i < V.rows(); ++i)
    for (int axis = 0; axis < 3; ++axis) {
      U(3 * i + axis, axis) = 1.0;
      U.block<3, 1>(3 * i, 3 + axis) = Eigen::Vector3d::Unit(axis).cross(V.row(i).transpose());
    }
  return U;
}

TEST(Ghost, RestrictionOfARigidMotionIsThatRigidMotion) {
  std::vector<std::pair<TriangleMesh, int>> cases{{shared_mesh("dragon_vrip_res4.ply.gz"), 700},
                                                  {messy_plane(), 120}};
  for (const auto& [mesh, target] : cases) {
    Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
    mass.head(mass.size() / 3).setZero();  // some clusters without mass too
    const Ghost ghost = ghost_mesh(mesh.V, mesh.F, mass, target);
    const Eigen::MatrixXd restricted = restrict_to_ghost(ghost, mass, rigid_motions(mesh.V));
    const Eigen::MatrixXd expected = rigid_motions(ghost.V);
    ASSERT_EQ(restricted.rows(), 3 * ghost.V.rows());
    const double extent = (mesh.V.colwise().maxCoeff() - mesh.V.colwise().minCoeff()).maxCoeff();
    EXPECT_LE((restricted - expected).cwiseAbs().maxCoeff(), 1e-13 * std::max(1.0, extent));
  }
}

TEST(Ghost, RestrictionIsTheMassWeightedMeanPerCoordinate) {
  // Three fine vertices on ghost vertex 0 (masses 1, 3, 0), one on ghost vertex 1 (mass 0).
  Eigen::VectorXi map(4);
  map << 0, 1, 0, 0;
  Eigen::VectorXd mass(4);
  mass << 1, 0, 3, 0;
  Eigen::MatrixXd U(12, 2);
  for (int i = 0; i < 12; ++i) U.row(i) << i, i * i;
  const Eigen::MatrixXd R = restrict_to_ghost(map, 2, mass, U);
  ASSERT_EQ(R.rows(), 6);
  for (int c = 0; c < 3; ++c) {
    EXPECT_DOUBLE_EQ(R(c, 0), (1.0 * c + 3.0 * (6 + c)) / 4.0);
    EXPECT_DOUBLE_EQ(R(c, 1), (1.0 * c * c + 3.0 * (6 + c) * (6 + c)) / 4.0);
    EXPECT_DOUBLE_EQ(R(3 + c, 0), 3 + c);
  }
}

TEST(Ghost, PaintedStiffnessRestrictsToTheMassWeightedMeanWeight) {
  Eigen::VectorXi map(4);
  map << 0, 1, 0, 0;
  Eigen::VectorXd mass(4), weights(4);
  mass << 1, 0, 3, 0;
  weights << 0.2, 0.7, 1.0, 0.0;
  const StiffnessPaint coarse = restrict_to_ghost(map, 2, mass, StiffnessPaint{weights, 30.0});
  ASSERT_EQ(coarse.weights.size(), 2);
  EXPECT_DOUBLE_EQ(coarse.weights[0], (0.2 + 3.0) / 4.0);
  EXPECT_DOUBLE_EQ(coarse.weights[1], 0.7);
  EXPECT_EQ(coarse.max_stiffness, 30.0);
  EXPECT_EQ(restrict_to_ghost(map, 2, mass, StiffnessPaint{}).weights.size(), 0);
  expect_input_error([&] { restrict_to_ghost(map, 2, mass, StiffnessPaint{weights.head(3), 2.0}); },
                     "stiffness_weights");
}

TEST(Ghost, ProgressIsReportedOftenAndCancelStopsIt) {
  const TriangleMesh& dragon = shared_mesh("dragon_vrip_res3.ply.gz");
  const Eigen::VectorXd mass = lumped_mass(dragon.V, dragon.F);
  std::vector<double> fractions;
  Progress every_report(
      [&](const std::string& stage, double fraction) {
        EXPECT_EQ(stage, "ghost");
        fractions.push_back(fraction);
        return true;
      },
      0.0);
  ghost_mesh(dragon.V, dragon.F, mass, 1000, &every_report);
  ASSERT_GE(fractions.size(), 50u);  // at most kReportInterval heap pops apart
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_EQ(fractions.back(), 1.0);

  int calls = 0;
  Progress cancel_third([&](const std::string&, double) { return ++calls < 3; }, 0.0);
  EXPECT_THROW(ghost_mesh(dragon.V, dragon.F, mass, 1000, &cancel_third), Cancelled);
  EXPECT_EQ(calls, 3);
}

TEST(Ghost, BadInputIsRefusedNamingIt) {
  const TriangleMesh mesh = grid(4, 4, 1.0, 1.0);
  const Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
  expect_input_error([&] { ghost_mesh(mesh.V, mesh.F, mass, 3); }, "target");
  expect_input_error([&] { ghost_mesh(mesh.V, mesh.F, mass.head(5), 10); }, "mass: expected 25");
  Eigen::VectorXd negative = mass;
  negative[7] = -1;
  expect_input_error([&] { ghost_mesh(mesh.V, mesh.F, negative, 10); }, "mass[7]");
  RowMatrixX3i folded(2, 3);
  folded << 0, 1, 2, 0, 2, 1;
  expect_input_error([&] { ghost_mesh(mesh.V, folded, mass, 10); }, "F: no triangle");

  Eigen::VectorXi map = Eigen::VectorXi::Zero(25);
  expect_input_error([&] { restrict_to_ghost(map, 1, mass, Eigen::MatrixXd::Zero(74, 2)); },
                     "U: expected 75");
  map[4] = 2;
  expect_input_error([&] { restrict_to_ghost(map, 2, mass, Eigen::MatrixXd::Zero(75, 2)); },
                     "map[4]");
  map[4] = 0;
  expect_input_error([&] { restrict_to_ghost(map, 2, mass, Eigen::MatrixXd::Zero(75, 2)); },
                     "ghost vertex 1");
  Eigen::MatrixXd U = Eigen::MatrixXd::Zero(75, 2);
  U(9, 1) = std::numeric_limits<double>::infinity();
  expect_input_error([&] { restrict_to_ghost(map, 1, mass, U); }, "U[9, 1]");
}

}  // namespace
}  // namespace modal_deform
