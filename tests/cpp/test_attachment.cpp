#include <gtest/gtest.h>

#include <random>

#include "mesh/primitives.h"
#include "reduction/attachment.h"
#include "test_bake_meshes.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

using testing::head_with_eyes;
using testing::side_by_side;

// The displacements x ↦ A x + t (3n, interleaved) of the rows of V.
Eigen::VectorXd affine_motion(const RowMatrixX3d& V, const Eigen::Matrix3d& A,
                              const Eigen::Vector3d& t) {
  Eigen::VectorXd u(3 * V.rows());
  for (Eigen::Index i = 0; i < V.rows(); ++i) u.segment<3>(3 * i) = A * V.row(i).transpose() + t;
  return u;
}

Eigen::Matrix3d skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d S;
  S << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return S;
}

// Extends the motion of the simulated vertices and compares with the motion of all vertices.
double extension_error(const Attachment& attachment, const RowMatrixX3d& V,
                       const Eigen::Matrix3d& A, const Eigen::Vector3d& t) {
  const Eigen::VectorXd all = affine_motion(V, A, t);
  Eigen::VectorXd simulated(3 * attachment.simulated.size());
  for (size_t s = 0; s < attachment.simulated.size(); ++s)
    simulated.segment<3>(3 * static_cast<Eigen::Index>(s)) =
        all.segment<3>(3 * attachment.simulated[s]);
  return (extend_to_attached(attachment, simulated) - all).cwiseAbs().maxCoeff() /
         all.cwiseAbs().maxCoeff();
}

TEST(Attachment, SmallComponentsFollowTheMeshAffinely) {
  const TriangleMesh mesh = head_with_eyes();
  const Attachment attachment = attach(mesh.V, mesh.F);
  const int head =
      6 * 7 * 7 - 12 * 5 - 8 * 2;  // bar(6, 6, 6): 6 faces of 7 x 7 vertices, shared edges once
  ASSERT_EQ(static_cast<int>(attachment.simulated.size()), head);
  EXPECT_EQ(attachment.num_components, 1);
  EXPECT_EQ(attachment.num_attached_components, 2);
  ASSERT_EQ(attachment.followers.size(), 2u);  // one per eye
  EXPECT_EQ(attachment.followers[0].vertices.size() + attachment.followers[1].vertices.size(),
            static_cast<size_t>(mesh.V.rows() - head));
  for (int s = 0; s < head; ++s) EXPECT_EQ(attachment.simulated[static_cast<size_t>(s)], s);
  EXPECT_EQ(attachment.faces.rows(), 6 * 6 * 6 * 2);
  // The eyes sit in front of a corner region of the head: not flat, and at least 16 vertices.
  for (const auto& follower : attachment.followers) {
    EXPECT_EQ(follower.normal, Eigen::Vector3d::Zero());
    EXPECT_GE(follower.anchors.size(), 16u);
  }
  const Eigen::Matrix3d A =
      (Eigen::Matrix3d() << 0.3, -0.2, 0.1, 0.05, -0.4, 0.2, 0.7, 0.1, 0.0).finished();
  EXPECT_LT(extension_error(attachment, mesh.V, A, Eigen::Vector3d(1, -2, 0.5)), 1e-12);
  EXPECT_LT(extension_error(attachment, mesh.V, skew(Eigen::Vector3d(0.2, -1, 0.4)),
                            Eigen::Vector3d(0, 0, 1)),
            1e-12);
}

TEST(Attachment, DebrisOverAFlatSheetTurnsWithIt) {
  // A flat grid with a speck floating above it: its neighbourhood is coplanar, so the triangle
  // rule applies; linearised rigid motions and in-plane affine motions still carry over.
  const TriangleMesh sheet = grid(10, 10, 2.0, 2.0);
  TriangleMesh speck = grid(1, 1, 0.05, 0.05);
  speck.V.col(2).setConstant(0.3);
  const TriangleMesh mesh = side_by_side(sheet, speck, Eigen::RowVector3d(0.2, -0.1, 0.0));
  const Attachment attachment = attach(mesh.V, mesh.F);
  ASSERT_EQ(attachment.followers.size(), 1u);
  EXPECT_EQ(attachment.followers[0].vertices.size(), 4u);
  EXPECT_NEAR(std::abs(attachment.followers[0].normal.z()), 1.0, 1e-12);
  EXPECT_LT(extension_error(attachment, mesh.V, skew(Eigen::Vector3d(0.5, 0.3, -0.2)),
                            Eigen::Vector3d(1, 2, 3)),
            1e-12);
  const Eigen::Matrix3d in_plane =
      (Eigen::Matrix3d() << 0.3, -0.2, 0, 0.5, 0.1, 0, 0, 0, 0).finished();
  EXPECT_LT(extension_error(attachment, mesh.V, in_plane, Eigen::Vector3d(1, 0, 0)), 1e-12);
}

TEST(Attachment, UnreferencedAndMasslessVerticesAreAttached) {
  TriangleMesh mesh = bar(3, 3, 3, 1.0, 1.0, 1.0);
  const auto n = static_cast<int>(mesh.V.rows());
  // An unreferenced vertex, and one only on a degenerate face (collinear with two others).
  mesh.V.conservativeResize(n + 2, 3);
  mesh.V.row(n) << 0.5, 0.5, 3.0;
  mesh.V.row(n + 1) = 0.5 * (mesh.V.row(0) + mesh.V.row(1));
  mesh.F.conservativeResize(mesh.F.rows() + 1, 3);
  mesh.F.row(mesh.F.rows() - 1) << 0, 1, n + 1;
  const Attachment attachment = attach(mesh.V, mesh.F);
  EXPECT_EQ(static_cast<int>(attachment.simulated.size()), n);
  ASSERT_EQ(attachment.followers.size(), 2u);
  EXPECT_EQ(attachment.followers[0].vertices, std::vector<int>{n});
  EXPECT_EQ(attachment.followers[1].vertices, std::vector<int>{n + 1});
  EXPECT_EQ(attachment.submesh_index[n], -1);
  EXPECT_EQ(attachment.faces.rows(), mesh.F.rows() - 1);  // the degenerate face is not simulated
  EXPECT_LT(extension_error(attachment, mesh.V, skew(Eigen::Vector3d(1, 2, 3)),
                            Eigen::Vector3d(-1, 0, 1)),
            1e-12);
}

TEST(Attachment, DoubledTrianglesCountOnceAndABlobHangingByAVertexIsAttached) {
  // A box with what scans hang on their surfaces: a fin (a triangle laid twice, both ways round,
  // on a box edge and a vertex of its own), a pair of doubled triangles on one box vertex, and a
  // small closed tetrahedron joined to the box at one vertex. One copy of the fin is simulated,
  // welded to the box at the edge; the pair and the blob, free to turn about their vertex (zero
  // modes), follow the box, each as one body.
  TriangleMesh mesh = bar(3, 3, 3, 1.0, 1.0, 1.0);
  const auto n = static_cast<int>(mesh.V.rows());
  const Eigen::Index box_faces = mesh.F.rows();
  const int a = mesh.F(0, 0), b = mesh.F(0, 1), pin = 5, root = 9;
  mesh.V.conservativeResize(n + 6, 3);
  mesh.V.row(n) = 0.5 * (mesh.V.row(a) + mesh.V.row(b)) + Eigen::RowVector3d(0.05, 0.05, -0.3);
  for (int k = 0; k < 3; ++k)
    mesh.V.row(n + 1 + k) = mesh.V.row(pin) + 0.1 * Eigen::RowVector3d(k == 0, k == 1, k == 2) +
                            Eigen::RowVector3d(0.05, 0.05, 0.05);
  mesh.V.row(n + 4) = mesh.V.row(root) + Eigen::RowVector3d(0.2, 0.1, 0.0);
  mesh.V.row(n + 5) = mesh.V.row(root) + Eigen::RowVector3d(0.1, 0.2, 0.1);
  mesh.F.conservativeResize(box_faces + 8, 3);
  mesh.F.bottomRows(8) << a, b, n, b, a, n,                                          // the fin
      pin, n + 1, n + 2, pin, n + 2, n + 3, pin, n + 3, n + 1, n + 1, n + 3, n + 2,  // the blob
      root, n + 4, n + 5, n + 5, n + 4, root;                                        // the pair
  const Attachment attachment = attach(mesh.V, mesh.F);
  EXPECT_EQ(static_cast<int>(attachment.simulated.size()), n + 1);
  EXPECT_GE(attachment.submesh_index[n], 0);
  EXPECT_EQ(attachment.num_components, 1);
  EXPECT_EQ(attachment.num_attached_components, 2);
  ASSERT_EQ(attachment.followers.size(), 2u);
  EXPECT_EQ(attachment.followers[0].vertices, (std::vector<int>{n + 1, n + 2, n + 3}));
  EXPECT_EQ(attachment.followers[1].vertices, (std::vector<int>{n + 4, n + 5}));
  EXPECT_EQ(attachment.faces.rows(), box_faces + 1);
  EXPECT_LT(extension_error(attachment, mesh.V, skew(Eigen::Vector3d(1, -2, 0.5)),
                            Eigen::Vector3d(0, 1, 2)),
            1e-12);
}

TEST(Attachment, LargePiecesJoinedAtAVertexAreOneComponent) {
  // Two sheets sharing one corner: both simulated, one component (its rigid motions move both;
  // turning one about the corner is a zero mode of the bake).
  const TriangleMesh sheet = grid(4, 4, 1.0, 1.0);
  const auto n = static_cast<int>(sheet.V.rows());
  Eigen::Index corner = 0, other = 0;
  (sheet.V.rowwise() - Eigen::RowVector3d(1.0, 1.0, 0.0)).rowwise().squaredNorm().minCoeff(&corner);
  sheet.V.rowwise().squaredNorm().minCoeff(&other);
  TriangleMesh mesh;
  mesh.V.resize(2 * n, 3);
  mesh.V << sheet.V, (sheet.V.rowwise() + Eigen::RowVector3d(1.0, 1.0, 0.0));
  mesh.F.resize(2 * sheet.F.rows(), 3);
  mesh.F << sheet.F, (sheet.F.array() + n).matrix();
  for (Eigen::Index f = sheet.F.rows(); f < mesh.F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (mesh.F(f, k) == n + other) mesh.F(f, k) = static_cast<int>(corner);
  const Attachment attachment = attach(mesh.V, mesh.F);
  EXPECT_EQ(static_cast<int>(attachment.simulated.size()),
            2 * n - 1);  // the second corner unreferenced
  EXPECT_EQ(attachment.num_components, 1);
  EXPECT_EQ(attachment.faces.rows(), mesh.F.rows());
  ASSERT_EQ(attachment.followers.size(), 1u);
  EXPECT_EQ(attachment.followers[0].vertices, std::vector<int>{n + static_cast<int>(other)});
}

TEST(Attachment, ComponentsOfSimilarSizeAreAllSimulated) {
  const TriangleMesh tube = cylinder(12, 6, 0.5, 2.0);
  const TriangleMesh mesh = side_by_side(tube, tube, Eigen::RowVector3d(3, 0, 0));
  const Attachment attachment = attach(mesh.V, mesh.F);
  EXPECT_EQ(attachment.num_components, 2);
  EXPECT_TRUE(attachment.followers.empty());
  EXPECT_EQ(attachment.component[0], 0);
  EXPECT_EQ(attachment.component[static_cast<Eigen::Index>(attachment.simulated.size()) - 1], 1);
}

TEST(Attachment, RefusesAMeshWithoutArea) {
  RowMatrixX3d V(3, 3);
  V << 0, 0, 0, 1, 0, 0, 2, 0, 0;
  const RowMatrixX3i F = (RowMatrixX3i(1, 3) << 0, 1, 2).finished();
  EXPECT_THROW(attach(V, F), InputError);
  Attachment attachment;
  attachment.simulated = {0, 1};
  attachment.submesh_index = Eigen::VectorXi::Zero(3);
  EXPECT_THROW(extend_to_attached(attachment, Eigen::MatrixXd::Zero(5, 1)), InputError);
}

}  // namespace
}  // namespace modal_deform
