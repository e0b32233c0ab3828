#include <gtest/gtest.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "energy/discrete_shells.h"
#include "mesh/primitives.h"
#include "reduction/cubature.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

// The bar (x, y in [0, 1], z in [0, 4]) bent in the x-z plane into an arc of `angle` radians.
RowMatrixX3d bent(const RowMatrixX3d& V, double angle) {
  const double R = 4.0 / angle;
  RowMatrixX3d X = V;
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    const double rho = R - (V(i, 0) - 0.5), phi = V(i, 2) / R;
    X(i, 0) = 0.5 + R - rho * std::cos(phi);
    X(i, 2) = rho * std::sin(phi);
  }
  return X;
}

// The bar twisted about its axis by `angle` radians over its length.
RowMatrixX3d twisted(const RowMatrixX3d& V, double angle) {
  RowMatrixX3d X = V;
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    const double t = angle * V(i, 2) / 4, x = V(i, 0) - 0.5, y = V(i, 1) - 0.5;
    X(i, 0) = 0.5 + std::cos(t) * x - std::sin(t) * y;
    X(i, 1) = 0.5 + std::sin(t) * x + std::cos(t) * y;
  }
  return X;
}

// The reduced gradient Uᵀ Σ_t ω_t ∇E_t of weighted terms from their rows of term_gradients.
Eigen::VectorXd weighted_reduced_gradient(const Eigen::MatrixXd& U,
                                          const std::vector<std::array<int, 4>>& vertices,
                                          const RowMatrixXd& gradients,
                                          const std::vector<int>& terms,
                                          const std::vector<double>& weights) {
  Eigen::VectorXd g = Eigen::VectorXd::Zero(U.rows());
  for (size_t i = 0; i < terms.size(); ++i)
    for (int m = 0; m < 4 && vertices[terms[i]][m] >= 0; ++m)
      g.segment<3>(3 * vertices[terms[i]][m]) +=
          weights[i] * gradients.row(terms[i]).segment<3>(3 * m).transpose();
  return U.transpose() * g;
}

// Blends of a bar's rest, a bent key and a twisted key (each a rest of the blended shells energy,
// DiscreteShells::blend_rests) at points near the linear blend of the shapes, in the subspace of
// smooth fields and the keys' displacements: a cubature fitted to 100 such blends reproduces the
// reduced gradient of the full energy on 12 others within 10% (2% on its training blends, the
// fit's tolerance; 7% measured, 14% with 24 training blends, 5% with 300), with far fewer terms
// than the mesh has, and the energy of its terms alone (DiscreteShells::select_terms) has that
// gradient.
TEST(Cubature, ReproducesTheReducedGradientOnHeldOutBlends) {
  const TriangleMesh bar = modal_deform::bar(4, 4, 16, 1, 1, 4);
  const Eigen::Index n = bar.V.rows();
  const RowMatrixX3d bend = bent(bar.V, M_PI / 2), twist = twisted(bar.V, M_PI);
  const Eigen::VectorXd rest = flatten(bar.V);
  // The subspace: polynomial fields up to degree 2 along the bar, and the keys' displacements.
  Eigen::MatrixXd U(3 * n, 0);
  const auto add = [&](const Eigen::VectorXd& column) {
    U.conservativeResize(Eigen::NoChange, U.cols() + 1);
    U.col(U.cols() - 1) = column;
  };
  for (int c = 0; c < 3; ++c)
    for (int power = 0; power <= 2; ++power)
      for (int across = 0; across < 3; ++across) {
        Eigen::VectorXd column = Eigen::VectorXd::Zero(3 * n);
        for (Eigen::Index v = 0; v < n; ++v)
          column[3 * v + c] = std::pow(bar.V(v, 2) / 4, power) *
                              (across == 0 ? 1.0 : bar.V(v, across - 1) - 0.5);
        add(column);
      }
  add(flatten(bend) - rest);
  add(flatten(twist) - rest);
  U = Eigen::HouseholderQR<Eigen::MatrixXd>(U).householderQ() *
      Eigen::MatrixXd::Identity(3 * n, U.cols());

  const DiscreteShells at_rest(bar.V, bar.F), at_bend(bend, bar.F), at_twist(twist, bar.F);
  DiscreteShells blended(bar.V, bar.F);
  const std::vector<const DiscreteShells*> rests{&at_rest, &at_bend, &at_twist};
  const std::vector<DiscreteShells::TermMatch> matches{
      blended.match_terms(at_rest), blended.match_terms(at_bend), blended.match_terms(at_twist)};
  const std::vector<std::array<int, 4>> vertices = blended.term_vertices();
  std::mt19937 random(7);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  // A blend: the weights c of the rests drawn and set on `blended`, and a point near the linear
  // blend of the shapes.
  const auto blend = [&](std::vector<double>& c) {
    const double w1 = uniform(random), w2 = uniform(random);
    c = {1 - w1 - w2, w1, w2};
    blended.blend_rests(rests, matches, c);
    Eigen::VectorXd noise(U.cols());
    for (Eigen::Index j = 0; j < noise.size(); ++j) noise[j] = 0.05 * normal(random);
    return Eigen::VectorXd((1 - w1 - w2) * rest + w1 * flatten(bend) + w2 * flatten(twist) +
                           U * noise);
  };
  std::vector<double> c;
  std::vector<CubatureSample> samples;
  std::vector<Eigen::VectorXd> targets;
  for (int b = 0; b < 100; ++b) {
    const Eigen::VectorXd x = blend(c);
    Eigen::VectorXd g(3 * n);
    blended.value_and_gradient(x, g);
    samples.push_back({blended.term_gradients(x), 1.0 / (U.transpose() * g).norm()});
  }
  const CubatureFit fit = fit_cubature(U, vertices, samples, {1000, 0.02});
  const Cubature& cubature = fit.cubature;
  const int total = static_cast<int>(vertices.size());
  EXPECT_LE(fit.residual, 0.02);
  ASSERT_FALSE(cubature.terms.empty());
  EXPECT_LT(static_cast<int>(cubature.terms.size()), total / 3);
  for (size_t i = 0; i < cubature.terms.size(); ++i) {
    EXPECT_GT(cubature.weights[i], 0);
    if (i > 0) {
      EXPECT_GT(cubature.terms[i], cubature.terms[i - 1]);
    }
  }
  // On the training blends: the fit's residual, over all of them at once.
  double residual = 0, target = 0;
  for (const CubatureSample& sample : samples) {
    std::vector<int> all(static_cast<size_t>(total));
    std::iota(all.begin(), all.end(), 0);
    const Eigen::VectorXd full = weighted_reduced_gradient(
        U, vertices, sample.term_gradients, all, std::vector<double>(all.size(), 1.0));
    const Eigen::VectorXd approximate = weighted_reduced_gradient(
        U, vertices, sample.term_gradients, cubature.terms, cubature.weights);
    residual += (sample.scale * (approximate - full)).squaredNorm();
    target += (sample.scale * full).squaredNorm();
  }
  EXPECT_LE(std::sqrt(residual / target), 0.02 + 1e-9);

  // Held out: the selected terms' energy on their vertices against the full energy.
  std::vector<int> selected_vertices;
  for (int t : cubature.terms)
    for (int v : vertices[t])
      if (v >= 0) selected_vertices.push_back(v);
  std::sort(selected_vertices.begin(), selected_vertices.end());
  selected_vertices.erase(std::unique(selected_vertices.begin(), selected_vertices.end()),
                          selected_vertices.end());
  const Eigen::Index m = static_cast<Eigen::Index>(selected_vertices.size());
  Eigen::MatrixXd Us(3 * m, U.cols());
  for (Eigen::Index i = 0; i < m; ++i)
    Us.middleRows<3>(3 * i) = U.middleRows<3>(3 * selected_vertices[i]);
  const DiscreteShells selected_rest =
      at_rest.select_terms(cubature.terms, cubature.weights, selected_vertices);
  const DiscreteShells selected_bend =
      at_bend.select_terms(cubature.terms, cubature.weights, selected_vertices);
  const DiscreteShells selected_twist =
      at_twist.select_terms(cubature.terms, cubature.weights, selected_vertices);
  DiscreteShells selected =
      at_rest.select_terms(cubature.terms, cubature.weights, selected_vertices);
  const std::vector<const DiscreteShells*> selected_rests{&selected_rest, &selected_bend,
                                                          &selected_twist};
  const std::vector<DiscreteShells::TermMatch> selected_matches{
      selected.match_terms(selected_rest), selected.match_terms(selected_bend),
      selected.match_terms(selected_twist)};
  double worst = 0;
  for (int b = 0; b < 12; ++b) {
    const Eigen::VectorXd x = blend(c);
    selected.blend_rests(selected_rests, selected_matches, c);
    Eigen::VectorXd g(3 * n), xs(3 * m), gs(3 * m);
    blended.value_and_gradient(x, g);
    const Eigen::VectorXd full = U.transpose() * g;
    for (Eigen::Index i = 0; i < m; ++i) xs.segment<3>(3 * i) = x.segment<3>(3 * selected_vertices[i]);
    selected.value_and_gradient(xs, gs);
    const Eigen::VectorXd approximate = Us.transpose() * gs;
    worst = std::max(worst, (approximate - full).norm() / full.norm());
  }
  EXPECT_LT(worst, 0.1);
  EXPECT_THROW(at_rest.select_terms({total}, {1.0}, selected_vertices), InputError);
  EXPECT_THROW(at_rest.select_terms({0}, {-1.0}, selected_vertices), InputError);
  EXPECT_THROW(at_rest.select_terms({0, 0}, {1.0, 1.0}, selected_vertices), InputError);
}

}  // namespace
}  // namespace modal_deform
