#include <gtest/gtest.h>

#include <map>

#include "mesh/primitives.h"
#include "solve/inbetween.h"
#include "solve/reduced_solver.h"
#include "test_posing.h"
#include "test_support.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

using testing::dense_modal_basis;
using testing::expect_input_error;
using testing::rigid_transform;
using testing::vertices_where;

// A tube along z, 4 long, its rings at each end handles.
struct Tube {
  TriangleMesh mesh = cylinder(8, 8, 1.0, 4.0);
  Handles handles;
  Tube() {
    handles = {vertices_where(mesh.V, [](const Eigen::Vector3d& x) { return x.z() < 1e-9; }),
               vertices_where(mesh.V, [](const Eigen::Vector3d& x) { return x.z() > 4 - 1e-9; })};
  }
};

const Basis& tube_basis() {
  static const Basis basis = dense_modal_basis(Tube().mesh, 16);
  return basis;
}

const Eigen::Matrix4d kIdentity = Eigen::Matrix4d::Identity();

// The top ring turned and pushed sideways at frame 4, back at rest at 8; the bottom held.
std::vector<InbetweenKey> swing_keys() {
  return {{0, {kIdentity, kIdentity}},
          {4, {kIdentity, rigid_transform({0, 0, 1}, 0.2, {0, 0, 4}, {0.1, 0, 0})}},
          {8, {kIdentity, kIdentity}}};
}

Eigen::VectorXf positions(Inbetween& inbetween, int frame) {
  Eigen::VectorXf out(3 * tube_basis().num_vertices());
  inbetween.positions(frame, out);
  return out;
}

// How far the mass centroid of the handle's vertices at X is from where T puts it.
double centroid_miss(const std::vector<int>& handle, const Eigen::VectorXf& X,
                     const Eigen::Matrix4d& T) {
  const Basis& basis = tube_basis();
  Eigen::Vector3d miss = Eigen::Vector3d::Zero();
  double mass = 0;
  for (int v : handle) {
    miss += basis.mass[v] *
            (X.segment<3>(3 * v).cast<double>() -
             T.topLeftCorner<3, 3>() * basis.rest.row(v).transpose() - T.topRightCorner<3, 1>());
    mass += basis.mass[v];
  }
  return miss.norm() / mass;
}

TEST(Inbetween, MeetsTheKeysAsCloselyAsPosing) {
  const Tube tube;
  Inbetween inbetween(tube_basis(), tube.handles, Eigen::VectorXd(), swing_keys(), {});
  const InbetweenStats stats = inbetween.solve();
  EXPECT_TRUE(stats.converged);
  EXPECT_LT(stats.control, stats.initial_control);
  const InbetweenKey key = swing_keys()[1];
  const Transforms transforms = {*key.transforms[0], *key.transforms[1]};
  ReducedSolver posing(tube_basis(), tube.handles, Eigen::VectorXd(), kDefaultPull);
  posing.set_transforms(transforms);
  posing.solve(1000, 1e-8);
  Eigen::VectorXf posed(3 * tube_basis().num_vertices());
  posing.positions(posed);
  // The basis (16 modes, no rigid motions) reaches neither key exactly: both miss by about 1e-3.
  for (int h = 0; h < 2; ++h)
    EXPECT_LE(centroid_miss(tube.handles[h], positions(inbetween, key.frame), transforms[h]),
              1.05 * centroid_miss(tube.handles[h], posed, transforms[h]) + 1e-6);
}

TEST(Inbetween, FramesAreTheSameBitsHoweverReached) {
  const Tube tube;
  Inbetween one(tube_basis(), tube.handles, Eigen::VectorXd(), swing_keys(), {});
  Inbetween two(tube_basis(), tube.handles, Eigen::VectorXd(), swing_keys(), {});
  one.solve();
  const Eigen::VectorXf late = positions(one, 20), early = positions(one, 3);
  EXPECT_EQ(positions(two, 3), early);  // solves on demand
  EXPECT_EQ(positions(two, 20), late);
  one.solve();
  EXPECT_EQ(positions(one, 20), late);
}

TEST(Inbetween, AfterTheLastKeyIsSimulation) {
  const Tube tube;
  InbetweenOptions options;
  std::vector<InbetweenKey> keys = swing_keys();
  keys[2].transforms[0].reset();  // the bottom's last key is frame 4's
  Inbetween inbetween(tube_basis(), tube.handles, Eigen::VectorXd(), keys, options);
  Eigen::VectorXd q, v;
  inbetween.state(8, q, v);
  ReducedDynamics simulation(tube_basis(), tube.handles, Eigen::VectorXd(), options.simulation);
  simulation.set_state(q, v, {kIdentity, kIdentity});
  for (int frame = 9; frame < 15; ++frame) {
    simulation.step({kIdentity, kIdentity});
    inbetween.state(frame, q, v);
    EXPECT_EQ(q, simulation.q());
    EXPECT_EQ(v, simulation.v());
  }
}

TEST(Inbetween, RefusesBadKeys) {
  const Tube tube;
  const auto make = [&](std::vector<InbetweenKey> keys) {
    return [&tube, keys] { Inbetween(tube_basis(), tube.handles, Eigen::VectorXd(), keys, {}); };
  };
  Eigen::Matrix4d sheared = kIdentity;
  sheared(0, 1) = 0.5;
  Eigen::Matrix4d infinite = kIdentity;
  infinite(1, 3) = std::numeric_limits<double>::infinity();
  std::vector<InbetweenKey> many;
  for (int f = 0; f < 1000; ++f) many.push_back({f, {kIdentity, kIdentity}});
  expect_input_error(make({}), "at least one key");
  expect_input_error(make({{2, {kIdentity, kIdentity}}, {2, {kIdentity, std::nullopt}}}),
                     "two keys at frame 2");
  expect_input_error(make({{-3, {kIdentity, kIdentity}}}), "outside [0, ");
  expect_input_error(make(many), "at most");
  expect_input_error(make({{0, {kIdentity}}}), "expected 2 transforms");
  expect_input_error(make({{0, {kIdentity, sheared}}}), "handle 1: the 3 by 3 block");
  expect_input_error(make({{0, {kIdentity, infinite}}}), "handle 1 has non-finite");
  expect_input_error(make({{0, {std::nullopt, std::nullopt}}}), "keys no handle");
  expect_input_error(make({{0, {kIdentity, kIdentity}}, {20000, {kIdentity, kIdentity}}}),
                     "spans more than");
  Inbetween inbetween(tube_basis(), tube.handles, Eigen::VectorXd(), swing_keys(), {});
  Eigen::VectorXd q, v;
  expect_input_error([&] { inbetween.state(-1, q, v); }, "frame: -1");
}

}  // namespace
}  // namespace modal_deform
