#include "reduction/cubature.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <cstdio>
#include <cstdlib>

#include "util/errors.h"

namespace modal_deform {
namespace {

// Terms a round of the greedy fit adds at most: one correlation sweep serves several terms, and
// the NNLS solve drops those that turn out redundant.
const int kTermsPerRound = std::getenv("MD_CUB_BATCH") ? std::atoi(std::getenv("MD_CUB_BATCH")) : 4;
// Rounds per term of the budget at most: a term that NNLS drops may come back, and the rounds
// stop even when dropping and adding cycle.
constexpr int kRoundsPerTerm = 4;

int vertex_count(const std::array<int, 4>& vertices) {
  return static_cast<int>(std::find(vertices.begin(), vertices.end(), -1) - vertices.begin());
}

// Lawson–Hanson non-negative least squares on the normal equations: x ≥ 0 minimising
// ½ xᵀ G x − hᵀ x (G = AᵀA, h = Aᵀb), from the feasible x given (a warm start) with the
// coordinates `joined` (s) tried first.
void nnls(const Eigen::MatrixXd& G, const Eigen::VectorXd& h, const std::vector<char>& joined,
          Eigen::VectorXd& x) {
  const Eigen::Index s = h.size();
  // A relative ridge keeps the passive set's system solvable when columns are near-dependent.
  const double ridge = 1e-13 * std::max(G.diagonal().maxCoeff(), 1e-300);
  // The passive set starts as the support of x and the coordinates that just joined (x = 0).
  std::vector<char> passive(static_cast<size_t>(s));
  for (Eigen::Index i = 0; i < s; ++i) passive[i] = x[i] > 0 || joined[i];
  const double tolerance = 1e-12 * std::max(h.cwiseAbs().maxCoeff(), 1e-300);
  for (Eigen::Index round = 0; round < 3 * s + 10; ++round) {
    // x the least-squares solution on the passive set, moved back inside x ≥ 0 where it leaves.
    for (Eigen::Index inner = 0; inner <= s; ++inner) {
      std::vector<Eigen::Index> P;
      for (Eigen::Index i = 0; i < s; ++i)
        if (passive[i]) P.push_back(i);
      if (P.empty()) break;
      Eigen::MatrixXd GP = G(P, P);
      GP.diagonal().array() += ridge;
      const Eigen::VectorXd z = GP.ldlt().solve(h(P));
      if (z.minCoeff() > 0) {
        x.setZero();
        x(P) = z;
        break;
      }
      // The longest step towards z that keeps x ≥ 0; the coordinate that stops it leaves.
      double alpha = 2;  // above every ratio, which lies in [0, 1]
      size_t stop = 0;
      for (size_t i = 0; i < P.size(); ++i) {
        if (z[i] > 0) continue;
        const double ratio = x[P[i]] > z[i] ? x[P[i]] / (x[P[i]] - z[i]) : 0;
        if (ratio < alpha) {
          alpha = ratio;
          stop = i;
        }
      }
      for (size_t i = 0; i < P.size(); ++i) {
        double& xi = x[P[i]];
        xi += alpha * (z[i] - xi);
        if (xi <= 0 || i == stop) {
          xi = 0;
          passive[P[i]] = 0;
        }
      }
    }
    // The most descending inactive coordinate joins, unless x is optimal.
    const Eigen::VectorXd w = h - G * x;
    Eigen::Index best = -1;
    for (Eigen::Index i = 0; i < s; ++i)
      if (!passive[i] && w[i] > tolerance && (best < 0 || w[i] > w[best])) best = i;
    if (best < 0) return;
    passive[best] = 1;
  }
}

}  // namespace

CubatureFit fit_cubature(const Eigen::Ref<const Eigen::MatrixXd>& U,
                         const std::vector<std::array<int, 4>>& term_vertices,
                         const std::vector<CubatureSample>& samples,
                         const CubatureOptions& options) {
  if (options.max_terms < 1)
    throw InputError(message("max_terms: expected at least 1, got ", options.max_terms));
  if (!(options.tolerance > 0 && options.tolerance < 1))
    throw InputError(message("tolerance: expected a value in (0, 1), got ", options.tolerance));
  const Eigen::Index d = U.cols(), rows = U.rows(), P = static_cast<Eigen::Index>(samples.size());
  const int T = static_cast<int>(term_vertices.size());
  for (int t = 0; t < T; ++t)
    for (int m = 0; m < vertex_count(term_vertices[t]); ++m)
      if (term_vertices[t][m] < 0 || 3 * term_vertices[t][m] + 3 > rows)
        throw InputError(message("term_vertices[", t, "]: vertex ", term_vertices[t][m],
                                 " is not among U's ", rows / 3, " vertices"));
  for (Eigen::Index p = 0; p < P; ++p)
    if (samples[p].term_gradients.rows() != T || samples[p].term_gradients.cols() != 12 ||
        !std::isfinite(samples[p].scale))
      throw InputError(message("samples[", p, "]: expected ", T, " by 12 term gradients, got ",
                               samples[p].term_gradients.rows(), " by ",
                               samples[p].term_gradients.cols(), ", and a finite scale"));

  // U_tᵀ g for term t and a gradient g over its vertices (d).
  const auto reduce = [&](int t, const double* g) {
    Eigen::VectorXd a = Eigen::VectorXd::Zero(d);
    for (int m = 0; m < vertex_count(term_vertices[t]); ++m)
      a += U.middleRows<3>(3 * term_vertices[t][m]).transpose() *
           Eigen::Map<const Eigen::Vector3d>(g + 3 * m);
    return a;
  };
  // Term t's column: scale_p U_tᵀ g_{t,p} over the samples p, stacked (d P).
  const auto column = [&](int t) {
    Eigen::VectorXd a(d * P);
    for (Eigen::Index p = 0; p < P; ++p)
      a.segment(p * d, d) = samples[p].scale * reduce(t, samples[p].term_gradients.row(t).data());
    return a;
  };
  // The target: the sum of every term's column.
  Eigen::MatrixXd target(d, P);
  for (Eigen::Index p = 0; p < P; ++p) {
    Eigen::VectorXd g = Eigen::VectorXd::Zero(rows);
    for (int t = 0; t < T; ++t)
      for (int m = 0; m < vertex_count(term_vertices[t]); ++m)
        g.segment<3>(3 * term_vertices[t][m]) +=
            samples[p].term_gradients.row(t).segment<3>(3 * m).transpose();
    target.col(p) = samples[p].scale * (U.transpose() * g);
  }
  const Eigen::Map<const Eigen::VectorXd> b(target.data(), d * P);
  CubatureFit fit;
  const double target_norm = b.norm();
  if (!(target_norm > 0)) return fit;

  // Column norms ‖a_t‖² = Σ_p scale_p² g_{t,p}ᵀ (U_t U_tᵀ) g_{t,p}, U_t the term's rows of U.
  Eigen::VectorXd column_norm(T);
#pragma omp parallel for schedule(dynamic, 256)
  for (int t = 0; t < T; ++t) {
    const int K = vertex_count(term_vertices[t]);
    Eigen::MatrixXd Ut(3 * K, d);
    for (int m = 0; m < K; ++m) Ut.middleRows<3>(3 * m) = U.middleRows<3>(3 * term_vertices[t][m]);
    const Eigen::MatrixXd gram = Ut * Ut.transpose();
    double sum = 0;
    for (Eigen::Index p = 0; p < P; ++p) {
      const Eigen::Map<const Eigen::VectorXd> g(samples[p].term_gradients.row(t).data(), 3 * K);
      sum += samples[p].scale * samples[p].scale * g.dot(gram * g);
    }
    column_norm[t] = std::sqrt(sum);
  }

  std::vector<int> chosen;
  std::vector<char> is_chosen(static_cast<size_t>(T), 0);
  Eigen::MatrixXd A(d * P, 0), G(0, 0);  // the chosen columns and their Gram matrix
  Eigen::VectorXd h(0), x(0);            // Aᵀb and the weights
  Eigen::VectorXd residual = b;
  Eigen::VectorXd score(T);
  for (int round = 0; round < kRoundsPerTerm * options.max_terms; ++round) {
    if (residual.norm() <= options.tolerance * target_norm) break;
    const int room = options.max_terms - static_cast<int>(chosen.size());
    if (room <= 0) break;
    // Each term's correlation with the residual, a_tᵀ res / ‖a_t‖, from Y = U res (3n by P).
    const Eigen::MatrixXd Y =
        U * Eigen::Map<const Eigen::MatrixXd>(residual.data(), d, P);
#pragma omp parallel for schedule(dynamic, 256)
    for (int t = 0; t < T; ++t) {
      score[t] = 0;
      if (is_chosen[t] || !(column_norm[t] > 0)) continue;
      const int K = vertex_count(term_vertices[t]);
      double sum = 0;
      for (Eigen::Index p = 0; p < P; ++p) {
        const double* g = samples[p].term_gradients.row(t).data();
        double dot = 0;
        for (int m = 0; m < K; ++m)
          for (int i = 0; i < 3; ++i) dot += g[3 * m + i] * Y(3 * term_vertices[t][m] + i, p);
        sum += samples[p].scale * dot;
      }
      score[t] = sum / column_norm[t];
    }
    std::vector<int> order(static_cast<size_t>(T));
    std::iota(order.begin(), order.end(), 0);
    const int take = std::min({kTermsPerRound, room, T});
    std::partial_sort(order.begin(), order.begin() + take, order.end(), [&](int i, int j) {
      return score[i] > score[j] || (score[i] == score[j] && i < j);
    });
    int added = 0;
    for (int i = 0; i < take && score[order[i]] > 0; ++i, ++added) {
      const int t = order[i];
      const Eigen::VectorXd a = column(t);
      const Eigen::Index s = A.cols();
      A.conservativeResize(Eigen::NoChange, s + 1);
      A.col(s) = a;
      G.conservativeResize(s + 1, s + 1);
      G.row(s) = a.transpose() * A;
      G.col(s) = G.row(s).transpose();
      h.conservativeResize(s + 1);
      h[s] = a.dot(b);
      x.conservativeResize(s + 1);
      x[s] = 0;
      chosen.push_back(t);
      is_chosen[t] = 1;
    }
    if (added == 0) break;
    std::vector<char> joined(static_cast<size_t>(x.size()), 0);
    std::fill(joined.end() - added, joined.end(), 1);
    nnls(G, h, joined, x);
    // Terms of zero weight leave (they may be chosen again).
    std::vector<Eigen::Index> keep;
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      if (x[i] > 0)
        keep.push_back(i);
      else
        is_chosen[chosen[i]] = 0;
    }
    if (static_cast<Eigen::Index>(keep.size()) < x.size()) {
      std::vector<int> kept_terms;
      for (Eigen::Index i : keep) kept_terms.push_back(chosen[i]);
      chosen = std::move(kept_terms);
      A = A(Eigen::all, keep).eval();
      G = G(keep, keep).eval();
      h = h(keep).eval();
      x = x(keep).eval();
    }
    residual = b - A * x;
    if (std::getenv("MD_CUB_LOG"))
      std::fprintf(stderr, "round %d terms %zu residual %g\n", round, chosen.size(),
                   residual.norm() / target_norm);
  }
  fit.residual = residual.norm() / target_norm;
  std::vector<size_t> order(chosen.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](size_t i, size_t j) { return chosen[i] < chosen[j]; });
  for (size_t i : order) {
    fit.cubature.terms.push_back(chosen[i]);
    fit.cubature.weights.push_back(x[static_cast<Eigen::Index>(i)]);
  }
  return fit;
}

}  // namespace modal_deform
