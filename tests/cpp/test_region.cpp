#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "energy/discrete_shells.h"
#include "mesh/mass.h"
#include "mesh/primitives.h"
#include "reduction/region.h"
#include "test_support.h"

namespace modal_deform {
namespace {

using testing::expect_input_error;

// One free vertex in the middle of a grid: the submesh is its two rings of faces, free vertex
// first, and its energy changes as the whole grid's does when that vertex moves (the bending
// terms across the first ring's outer edges included).
TEST(Region, OneVertexHoldsEveryTermThatMovesIt) {
  const TriangleMesh grid_mesh = grid(8, 8, 1.0, 1.0);
  const Eigen::VectorXd mass = lumped_mass(grid_mesh.V, grid_mesh.F);
  const int middle = 4 * 9 + 4;
  const Eigen::VectorXi region = Eigen::VectorXi::Constant(1, middle);
  const RegionMesh mesh = region_mesh(grid_mesh.F, mass, region);
  ASSERT_EQ(mesh.num_free, 1);
  EXPECT_EQ(mesh.vertices[0], middle);
  EXPECT_TRUE(std::is_sorted(mesh.vertices.begin() + 1, mesh.vertices.end()));
  RowMatrixX3d V(mesh.vertices.size(), 3);
  for (size_t i = 0; i < mesh.vertices.size(); ++i)
    V.row(static_cast<Eigen::Index>(i)) = grid_mesh.V.row(mesh.vertices[i]);
  const DiscreteShells whole(grid_mesh.V, grid_mesh.F), sub(V, mesh.faces);
  Eigen::VectorXd x = whole.rest(), y = sub.rest();
  x.segment<3>(3 * middle) += Eigen::Vector3d(0.02, -0.01, 0.05);
  y.head<3>() += Eigen::Vector3d(0.02, -0.01, 0.05);
  EXPECT_NEAR(sub.value(y), whole.value(x), 1e-12 * whole.value(x));
  const auto all = Eigen::VectorXi::LinSpaced(static_cast<int>(mass.size()), 0,
                                              static_cast<int>(mass.size()) - 1);
  expect_input_error([&] { region_mesh(grid_mesh.F, mass, all); }, "region: it holds every vertex");
  expect_input_error([&] { region_mesh(grid_mesh.F, mass, Eigen::Vector2i(3, 3)); },
                     "region[1] = 3 is there twice");
}

}  // namespace
}  // namespace modal_deform
