#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "finite_differences.h"
#include "solve/handle_term.h"
#include "test_posing.h"
#include "test_support.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

using testing::expect_input_error;
using testing::expect_slope_matches;
using testing::rigid_transform;

// μs⁴ Σ_h w_h Σ_{i∈h} m_i ‖x̄_i + U_i q − R_h x̄_i − t_h‖², summed over the handle vertices.
double direct_handle_term(const RowMatrixX3d& rest, const Eigen::VectorXd& mass,
                          const RowMatrixXf& U, const Handles& handles,
                          const Eigen::VectorXd& weights, const Transforms& T, double coefficient,
                          const Eigen::VectorXd& q) {
  const Eigen::VectorXd displacement = U.cast<double>() * q;
  double sum = 0;
  for (size_t h = 0; h < handles.size(); ++h)
    for (int v : handles[h]) {
      const Eigen::Vector3d x = rest.row(v).transpose() + displacement.segment<3>(3 * v);
      const Eigen::Vector3d target =
          T[h].topLeftCorner<3, 3>() * rest.row(v).transpose() + T[h].topRightCorner<3, 1>();
      sum += coefficient * weights[h] * mass[v] * (x - target).squaredNorm();
    }
  return sum;
}

// The rows of a dense basis U (3#V by r) at each vertex.
VertexRows rows_of(const RowMatrixXf& U) {
  return [&U](int v) { return U.middleRows<3>(3 * v).cast<double>().eval(); };
}

// The reduced term of `setup`-like arguments: the fine term restricted to x̄ + U q.
ReducedHandleTerm reduced(const RowMatrixX3d& rest, const Eigen::VectorXd& mass,
                          const RowMatrixXf& U, const Handles& handles,
                          const Eigen::VectorXd& weights, double coefficient) {
  return ReducedHandleTerm(HandleTerm(rest, mass, handles, weights, coefficient), rows_of(U),
                           U.cols());
}

struct Handled {
  RowMatrixX3d rest;
  Eigen::VectorXd mass;
  RowMatrixXf U;
  Handles handles{{0, 3, 5, 7}, {7, 8, 11}, {2}};  // vertex 7 in two handles
  Eigen::VectorXd weights = Eigen::Vector3d(1.0, 0.5, 2.0);
  Transforms transforms;
  double coefficient = 3.5;

  Handled() {
    std::srand(7);
    rest = 50 * RowMatrixX3d::Random(12, 3);
    rest.col(0).array() += 1000;  // far from the origin: the centring must keep c exact
    mass = Eigen::VectorXd::Random(12).cwiseAbs();
    U = RowMatrixXf::Random(36, 5);
    transforms = {rigid_transform({1, 2, 3}, 0.7, {1000, 0, 0}, {3, -2, 1}),
                  rigid_transform({0, 0, 1}, -2.9, {1010, 5, 0}, {0, 0, 0}),
                  Eigen::Matrix4d::Identity()};
  }
};

TEST(ReducedHandleTerm, EqualsTheSumOverHandleVertices) {
  const Handled setup;
  ReducedHandleTerm term =
      reduced(setup.rest, setup.mass, setup.U, setup.handles, setup.weights, setup.coefficient);
  term.set_transforms(setup.transforms);
  for (int trial = 0; trial < 3; ++trial) {
    const Eigen::VectorXd q = 10 * Eigen::VectorXd::Random(5);
    const double expected =
        direct_handle_term(setup.rest, setup.mass, setup.U, setup.handles, setup.weights,
                           setup.transforms, setup.coefficient, q);
    Eigen::VectorXd gradient(5);
    EXPECT_NEAR(term.value_and_gradient(q, gradient), expected, 1e-10 * expected);
    const Eigen::VectorXd d = Eigen::VectorXd::Random(5);
    expect_slope_matches(
        [&](const Eigen::VectorXd& p) {
          return direct_handle_term(setup.rest, setup.mass, setup.U, setup.handles, setup.weights,
                                    setup.transforms, setup.coefficient, p);
        },
        q, d, gradient.dot(d), "reduced handle term");
    // ∇E_C(q) − ∇E_C(0) = 2A q.
    Eigen::VectorXd gradient0(5);
    term.value_and_gradient(Eigen::VectorXd::Zero(5), gradient0);
    EXPECT_LE((term.hessian() * q - (gradient - gradient0)).norm(), 1e-10 * gradient.norm());
  }
}

// The fine term is the same sum at any positions x; its gradient is exact (the term is quadratic)
// and its Hessian diagonal is 2 c w m per coordinate; it adds to the gradient it is given.
TEST(HandleTerm, OnTheFineMeshEqualsTheSumAndItsDerivatives) {
  const Handled setup;
  HandleTerm term(setup.rest, setup.mass, setup.handles, setup.weights, setup.coefficient);
  term.set_transforms(setup.transforms);
  const Eigen::VectorXd q = 10 * Eigen::VectorXd::Random(5);
  const Eigen::VectorXd x = flatten(setup.rest) + setup.U.cast<double>() * q;
  const double expected = direct_handle_term(setup.rest, setup.mass, setup.U, setup.handles,
                                             setup.weights, setup.transforms, setup.coefficient, q);
  const Eigen::VectorXd offset = Eigen::VectorXd::Random(36);
  Eigen::VectorXd gradient = offset;
  EXPECT_NEAR(term.add_value_and_gradient(x, gradient), expected, 1e-10 * expected);
  gradient -= offset;
  const Eigen::VectorXd d = Eigen::VectorXd::Random(36);
  expect_slope_matches(
      [&](const Eigen::VectorXd& y) {
        Eigen::VectorXd unused(36);
        return term.add_value_and_gradient(y, unused);
      },
      x, d, gradient.dot(d), "handle term");
  // Vertex 7 is in handles 0 and 1 (weights 1 and 0.5); vertex 1 in none.
  const Eigen::VectorXd diagonal = term.hessian_diagonal(12);
  EXPECT_NEAR(diagonal[21], 2 * setup.coefficient * 1.5 * setup.mass[7], 1e-12);
  EXPECT_EQ(diagonal[3], 0.0);
  // Restricted to x̄ + U q it is the reduced term.
  ReducedHandleTerm restricted(term, rows_of(setup.U), setup.U.cols());
  restricted.set_transforms(setup.transforms);
  Eigen::VectorXd reduced_gradient(5);
  EXPECT_NEAR(restricted.value_and_gradient(q, reduced_gradient), expected, 1e-10 * expected);
  EXPECT_LE((reduced_gradient - setup.U.cast<double>().transpose() * gradient).norm(),
            1e-8 * gradient.norm());
}

TEST(ReducedHandleTerm, LargeHandlesAreSummedInBlocks) {
  std::srand(5);
  const int n = 2500;  // more vertices than one block of the Σ m UᵀU accumulation
  const RowMatrixX3d rest = RowMatrixX3d::Random(n, 3);
  const Eigen::VectorXd mass = Eigen::VectorXd::Random(n).cwiseAbs();
  const RowMatrixXf U = RowMatrixXf::Random(3 * n, 4);
  Handles handles(1);
  for (int v = 0; v < n; ++v) handles[0].push_back(v);
  const Eigen::VectorXd weights = Eigen::VectorXd::Ones(1);
  const Transforms transforms = {rigid_transform({0, 1, 1}, 1.2, {0, 0, 0}, {1, 0, 0})};
  ReducedHandleTerm term = reduced(rest, mass, U, handles, weights, 2.0);
  term.set_transforms(transforms);
  const Eigen::VectorXd q = Eigen::Vector4d(0.3, -1, 2, 0.5);
  Eigen::VectorXd gradient(4);
  const double expected = direct_handle_term(rest, mass, U, handles, weights, transforms, 2.0, q);
  EXPECT_NEAR(term.value_and_gradient(q, gradient), expected, 1e-10 * expected);
}

TEST(ReducedHandleTerm, ZeroAtRestWithIdentityTransformsAndPositiveAfterAMove) {
  const Handled setup;
  ReducedHandleTerm term =
      reduced(setup.rest, setup.mass, setup.U, setup.handles, setup.weights, setup.coefficient);
  Eigen::VectorXd gradient(5);
  EXPECT_EQ(term.value_and_gradient(Eigen::VectorXd::Zero(5), gradient), 0.0);
  EXPECT_EQ(gradient.norm(), 0.0);
  term.set_transforms(setup.transforms);
  EXPECT_GT(term.value_and_gradient(Eigen::VectorXd::Zero(5), gradient), 0.0);
  // Translating everything rigidly by the translation each handle asks for zeroes that handle.
  Transforms same(3, rigid_transform({0, 0, 1}, 0, {0, 0, 0}, {1, 2, 3}));
  RowMatrixXf translation = RowMatrixXf::Zero(36, 3);
  for (int v = 0; v < 12; ++v) translation.block<3, 3>(3 * v, 0).setIdentity();
  ReducedHandleTerm translated =
      reduced(setup.rest, setup.mass, translation, setup.handles, setup.weights, setup.coefficient);
  translated.set_transforms(same);
  Eigen::VectorXd g3(3);
  EXPECT_NEAR(translated.value_and_gradient(Eigen::Vector3d(1, 2, 3), g3), 0.0, 1e-9);
  EXPECT_LE(g3.norm(), 1e-9);
}

TEST(HandleTerm, HandlesAreValidated) {
  const Eigen::VectorXd none;
  expect_input_error([&] { checked_handle_weights({}, none, 10); }, "no handle");
  expect_input_error([&] { checked_handle_weights({{1}, {}}, none, 10); }, "handles[1] is empty");
  expect_input_error([&] { checked_handle_weights({{1, 10}}, none, 10); }, "handles[0][1] = 10");
  expect_input_error([&] { checked_handle_weights({{1, -1}}, none, 10); }, "handles[0][1] = -1");
  expect_input_error([&] { checked_handle_weights({{2}, {1, 4, 1}}, none, 10); },
                     "handles[1] lists vertex 1 twice");
  expect_input_error([&] { checked_handle_weights({{1}, {2}}, Eigen::VectorXd::Ones(3), 10); },
                     "weights");
  expect_input_error([&] { checked_handle_weights({{1}, {2}}, Eigen::Vector2d(1, -1), 10); },
                     "weights[1]");
  EXPECT_EQ(checked_handle_weights({{1}, {1, 2}}, none, 10),
            Eigen::Vector2d(1, 1));  // overlap is fine
  EXPECT_EQ(checked_handle_weights({{1}, {2}}, Eigen::Vector2d(0, 3), 10), Eigen::Vector2d(0, 3));
}

TEST(HandleTerm, TransformsMustBeRigid) {
  const Eigen::Matrix4d I = Eigen::Matrix4d::Identity();
  EXPECT_NO_THROW(check_transforms({I, rigid_transform({1, 1, 0}, 2.0, {1, 2, 3}, {4, 5, 6})}, 2));
  expect_input_error([&] { check_transforms({I}, 2); }, "expected 2");
  Eigen::Matrix4d scaled = I;
  scaled(1, 1) = 1.5;
  expect_input_error([&] { check_transforms({I, scaled}, 2); }, "transforms[1]");
  Eigen::Matrix4d mirrored = I;
  mirrored(2, 2) = -1;
  expect_input_error([&] { check_transforms({mirrored}, 1); }, "reflection");
  Eigen::Matrix4d projective = I;
  projective(3, 0) = 0.1;
  expect_input_error([&] { check_transforms({projective}, 1); }, "last row");
  Eigen::Matrix4d nan = I;
  nan(0, 3) = std::nan("");
  expect_input_error([&] { check_transforms({nan}, 1); }, "non-finite");
}

// Regression (fuzz_bake_and_pose): a translation of -1.7e308 passed, and the full solve returned
// an infinite energy. Translations are held to the coordinates the energies take.
TEST(HandleTerm, TranslationsBeyondTheCoordinateRangeAreRefused) {
  Eigen::Matrix4d far = Eigen::Matrix4d::Identity();
  far(1, 3) = -1.7e308;
  expect_input_error([&] { check_transforms({Eigen::Matrix4d::Identity(), far}, 2); },
                     "transforms[1]: the translation (0, -1.7e+308, 0) is beyond 1e+15");
  far(1, 3) = -1e15;
  EXPECT_NO_THROW(check_transforms({far}, 1));
}

}  // namespace
}  // namespace modal_deform
