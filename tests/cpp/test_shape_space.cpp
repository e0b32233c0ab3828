#include <gtest/gtest.h>

#include <cmath>

#include "bake/bake.h"
#include "energy/discrete_shells.h"
#include "mesh/primitives.h"
#include "solve/shape_space.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

// The bar bent in the x-z plane into an arc of `angle` radians (its centre line keeps its length).
RowMatrixX3d bent(const RowMatrixX3d& V, double angle, double length) {
  const double R = length / angle;
  RowMatrixX3d X = V;
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    const double rho = R - (V(i, 0) - 0.5), phi = V(i, 2) / R;
    X(i, 0) = 0.5 + R - rho * std::cos(phi);
    X(i, 2) = rho * std::sin(phi);
  }
  return X;
}

// The blended energy equals Σ_j c_j E_j up to a constant: its gradient is theirs at any x.
TEST(ShapeSpace, BlendedRestsGiveTheWeightedSumOfEnergies) {
  const TriangleMesh bar = modal_deform::bar(2, 2, 6, 1, 1, 4);
  const RowMatrixX3d key = bent(bar.V, 1.2, 4.0);
  const DiscreteShells rest(bar.V, bar.F), at_key(key, bar.F);
  DiscreteShells blended(bar.V, bar.F);
  const std::vector<const DiscreteShells*> rests{&rest, &at_key};
  const std::vector<DiscreteShells::TermMatch> matches{blended.match_terms(rest),
                                                       blended.match_terms(at_key)};
  for (const double w : {0.0, 0.3, 1.0, 1.7}) {
    blended.blend_rests(rests, matches, {1 - w, w});
    const Eigen::VectorXd x =
        flatten(bent(bar.V, 0.7, 4.0)) + 0.01 * Eigen::VectorXd::Ones(3 * bar.V.rows());
    Eigen::VectorXd g(x.size()), g0(x.size()), g1(x.size());
    blended.value_and_gradient(x, g);
    rest.value_and_gradient(x, g0);
    at_key.value_and_gradient(x, g1);
    const Eigen::VectorXd expected = (1 - w) * g0 + w * g1;
    EXPECT_LT((g - expected).norm(), 1e-10 * (1 + expected.norm())) << "w = " << w;
  }
}

TEST(ShapeSpace, WeightsZeroAndOneGiveTheBasisAndTheKey) {
  const TriangleMesh bar = modal_deform::bar(4, 4, 16, 1, 1, 4);
  Progress progress;
  const Basis basis = bake(bar.V, bar.F, BakeOptions{}, progress);
  const RowMatrixX3d key = bent(bar.V, M_PI / 2, 4.0);
  ShapeSpace space(basis, {key});
  Eigen::VectorXf out(3 * bar.V.rows());
  space.blend(Eigen::VectorXd::Zero(1), out);
  EXPECT_LT((out.cast<double>() - flatten(bar.V)).cwiseAbs().maxCoeff(), 4e-4);
  space.blend(Eigen::VectorXd::Ones(1), out);
  EXPECT_LT((out.cast<double>() - flatten(key)).cwiseAbs().maxCoeff(), 4e-4);
  space.blend(Eigen::VectorXd::Constant(1, 0.5), out);
  EXPECT_TRUE(space.stats().converged);
  const Eigen::VectorXf first = out;
  space.blend(Eigen::VectorXd::Constant(1, 0.5), out);
  EXPECT_EQ(first, out);
  EXPECT_THROW(space.blend(Eigen::VectorXd::Constant(1, std::nan("")), out), InputError);
  EXPECT_THROW(ShapeSpace(basis, {key.topRows(10)}), InputError);
  EXPECT_THROW(ShapeSpace(basis, {}), InputError);
}

}  // namespace
}  // namespace modal_deform
