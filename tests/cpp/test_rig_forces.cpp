#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>

#include "solve/rig_forces.h"
#include "test_support.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

using testing::expect_input_error;

// A random basis of 10 vertices and 4 dimensions (RigForces reads rest, mass, vectors and scale).
Basis random_basis() {
  std::srand(11);
  Basis basis;
  basis.rest = RowMatrixX3d::Random(10, 3);
  basis.mass = Eigen::VectorXd::Random(10).array().abs() + 0.1;
  basis.vectors = RowMatrixXf::Random(30, 4);
  basis.scale = 1.7;
  return basis;
}

// Each vertex on bones i % 3 and (i + 1) % 3 of 4 (the last has no vertex).
SkinningWeights weights(int num_vertices) {
  SkinningWeights W(num_vertices, 4);
  for (int i = 0; i < num_vertices; ++i) {
    const double t = (i + 1.0) / (num_vertices + 1);
    W.insert(i, i % 3) = t;
    W.insert(i, (i + 1) % 3) = 1 - t;
  }
  W.makeCompressed();
  return W;
}

Transforms random_bones(unsigned seed) {
  std::srand(seed);
  Transforms bones(4, Eigen::Matrix4d::Identity());
  for (Eigen::Matrix4d& B : bones)
    B.topRows<3>() =
        Eigen::Matrix<double, 3, 4>::Random() + 2 * Eigen::Matrix<double, 3, 4>::Identity();
  return bones;
}

TEST(RigForces, IsTheProjectionOfEachBonesAccelerationPulledBackByItsFrame) {
  const Basis basis = random_basis();
  const SkinningWeights W = weights(basis.num_vertices());
  const RigForces forces(basis, W);
  const Transforms previous = random_bones(1), current = random_bones(2), next = random_bones(3);
  const double dt = 1.0 / 24;
  Eigen::VectorXd g;
  forces.acceleration(previous, current, next, dt, g);
  // −s⁴ Σ_i m_i U_iᵀ Σ_b W_ib L_b⁻¹ B̈_b x̄_i, vertex by vertex.
  Eigen::VectorXd expected = Eigen::VectorXd::Zero(basis.dimension());
  for (int i = 0; i < basis.num_vertices(); ++i) {
    const Eigen::Vector4d point(basis.rest(i, 0), basis.rest(i, 1), basis.rest(i, 2), 1);
    Eigen::Vector3d felt = Eigen::Vector3d::Zero();
    for (SkinningWeights::InnerIterator it(W, i); it; ++it) {
      const int b = static_cast<int>(it.col());
      const Eigen::Vector4d acceleration =
          (next[b] - 2 * current[b] + previous[b]) * point / (dt * dt);
      felt += it.value() * current[b].topLeftCorner<3, 3>().inverse() * acceleration.head<3>();
    }
    expected -= std::pow(basis.scale, 4) * basis.mass[i] * basis.vertex_rows(i).transpose() * felt;
  }
  EXPECT_LE((g - expected).norm(), 1e-10 * expected.norm());
  // A still rig: exactly zero.
  forces.acceleration(current, current, current, dt, g);
  EXPECT_TRUE((g.array() == 0).all());
}

TEST(RigForces, RefusesABoneScaledToAlmostNothingThatMoves) {
  const Basis basis = random_basis();
  const RigForces forces(basis, weights(basis.num_vertices()));
  const double dt = 1.0 / 24;
  Transforms tiny = random_bones(2);
  tiny[1].topLeftCorner<3, 3>() *= 1e-100;  // well conditioned, so not singular
  Eigen::VectorXd g;
  forces.acceleration(tiny, tiny, tiny, dt, g);  // still: nothing to pull back
  EXPECT_TRUE((g.array() == 0).all());
  Transforms moved = tiny;
  moved[1](0, 3) += 0.1;
  expect_input_error([&] { forces.acceleration(tiny, tiny, moved, dt, g); },
                     "bones[1]: its motion pulled back into its frame is beyond");
  // Scaled by 1e-6, the same motion is taken: a large but representable pull-back.
  Transforms small = random_bones(2);
  small[1].topLeftCorner<3, 3>() *= 1e-6;
  Transforms small_moved = small;
  small_moved[1](0, 3) += 0.1;
  forces.acceleration(small, small, small_moved, dt, g);
  EXPECT_TRUE(g.allFinite());
  EXPECT_GT(g.norm(), 0);
}

TEST(RigForces, RefusesBadWeightsAndBones) {
  const Basis basis = random_basis();
  const int n = basis.num_vertices();
  SkinningWeights W = weights(n);
  expect_input_error([&] { check_skinning_weights(W, n + 1); }, "one row each");
  SkinningWeights heavy = W * 1.1;
  expect_input_error([&] { check_skinning_weights(heavy, n); }, "sum to");
  SkinningWeights negative = W;
  negative.coeffRef(2, 2) = -0.1;
  expect_input_error([&] { check_skinning_weights(negative, n); }, "negative");
  SkinningWeights unweighted = W;
  for (SkinningWeights::InnerIterator it(unweighted, 5); it; ++it) it.valueRef() = 0;
  expect_input_error([&] { check_skinning_weights(unweighted, n); }, "vertex 5 is weighted to no");
  check_skinning_weights(W, n);  // bone 3 has no vertex: fine

  Transforms bones = random_bones(4);
  check_bone_matrices(bones, 4);
  expect_input_error([&] { check_bone_matrices(bones, 5); }, "expected 5");
  Transforms singular = bones;
  singular[1].col(0).head<3>().setZero();
  expect_input_error([&] { check_bone_matrices(singular, 4); }, "singular");
  Transforms projective = bones;
  projective[2](3, 1) = 0.5;
  expect_input_error([&] { check_bone_matrices(projective, 4); }, "affine");
  Transforms infinite = bones;
  infinite[0](0, 3) = std::numeric_limits<double>::infinity();
  expect_input_error([&] { check_bone_matrices(infinite, 4); }, "non-finite");
  Transforms enormous = bones;
  enormous[3](1, 3) = 2e15;  // beyond kMaxCoordinate: its second difference times fps² overflows
  expect_input_error([&] { check_bone_matrices(enormous, 4); }, "bones[3]: an entry is beyond");
  enormous[3](1, 3) = 1;
  enormous[3](2, 2) = -1e300;
  expect_input_error([&] { check_bone_matrices(enormous, 4); }, "bones[3]: an entry is beyond");
}

}  // namespace
}  // namespace modal_deform
