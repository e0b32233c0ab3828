#include "solve/inbetween.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <string>

#include "solve/reduced_solver.h"
#include "util/errors.h"
#include "util/parallel_for.h"

namespace modal_deform {
namespace {

// The key penalty's weight against the motion's own terms at a key node (traces of the normal
// matrix's blocks): the keys' fits are met within about its inverse of what the motion would
// rather do; higher stiffens the problem and slows the quasi-Newton iteration on large motions.
constexpr double kKeyDominance = 1e4;
// The static poses (posing's minima): BFGS iterations at most.
constexpr int kPoseIterations = 1000;
// ∇²V u by a forward difference of ghost gradients, the step moving no coordinate by more than this
// (normalised frame: the mesh about unit size).
constexpr double kDifferenceStep = 1e-7;
// Armijo's sufficient decrease, and the backtracking's halvings at most.
constexpr double kArmijo = 1e-4;
constexpr int kMaxHalvings = 40;
// The objective at this fraction of the starting guess's, when no step decreases it further: as
// low as the differenced gradient lets it go (converged).
constexpr double kFloor = 1e-6;
// The model's least curvature, this fraction of its largest block's mean: directions the
// dynamics at rest leave free (a free body's rigid motions, modes no key sees) stiffen as the part
// turns, and a step along them from a model that lacks it overshoots by orders of magnitude.
constexpr double kProximity = 1e-2;
// L-BFGS pairs kept.
constexpr int kCorrections = 8;
// The nodes are evaluated in this many runs of consecutive nodes, each on its own copy of the
// ghost energy (whose work space is its own), spread over the threads: nodes are independent
// given the states, so the results are the same bits for any thread count.
constexpr int kRuns = 4;
// A key's penalty curvature below this fraction of its largest is a direction the keyed handles
// do not see.
constexpr double kZeroCurvature = 1e-10;

// A symmetric positive definite matrix of N by N blocks of size r, zero beyond two blocks from
// the diagonal, factored as L Lᵀ with L of the same band.
class BandedCholesky {
 public:
  static constexpr int kBand = 2;

  // diagonal[i]: block (i, i); below[d][i]: block (i + d + 1, i).
  void factor(const std::vector<Eigen::MatrixXd>& diagonal,
              const std::array<std::vector<Eigen::MatrixXd>, kBand>& below) {
    const int n = static_cast<int>(diagonal.size());
    diagonal_.assign(n, Eigen::LLT<Eigen::MatrixXd>());
    for (auto& blocks : lower_) blocks.assign(n, Eigen::MatrixXd());
    for (int i = 0; i < n; ++i) {
      // L_ij = (B_ij − Σ_{i−2 ≤ k < j} L_ik L_jkᵀ) L_jj⁻ᵀ for j = i−2, i−1.
      for (int j = std::max(0, i - kBand); j < i; ++j) {
        Eigen::MatrixXd block = below[i - j - 1][j];
        for (int k = std::max(0, i - kBand); k < j; ++k)
          block.noalias() -= lower(i, k) * lower(j, k).transpose();
        lower_[i - j - 1][j] = diagonal_[j].matrixL().solve(block.transpose()).transpose();
      }
      Eigen::MatrixXd block = diagonal[i];
      for (int k = std::max(0, i - kBand); k < i; ++k)
        block.noalias() -= lower(i, k) * lower(i, k).transpose();
      diagonal_[i].compute(block);
      if (diagonal_[i].info() != Eigen::Success)
        throw NumericalError("in-betweens: the banded model matrix is not positive definite");
    }
  }

  // x = (L Lᵀ)⁻¹ b, block by block, in place.
  void solve(std::vector<Eigen::VectorXd>& x) const {
    const int n = static_cast<int>(x.size());
    for (int i = 0; i < n; ++i) {
      for (int k = std::max(0, i - kBand); k < i; ++k) x[i].noalias() -= lower(i, k) * x[k];
      diagonal_[i].matrixL().solveInPlace(x[i]);
    }
    for (int i = n - 1; i >= 0; --i) {
      for (int k = i + 1; k <= std::min(n - 1, i + kBand); ++k)
        x[i].noalias() -= lower(k, i).transpose() * x[k];
      diagonal_[i].matrixU().solveInPlace(x[i]);
    }
  }

 private:
  const Eigen::MatrixXd& lower(int i, int j) const { return lower_[i - j - 1][j]; }

  std::vector<Eigen::LLT<Eigen::MatrixXd>> diagonal_;
  std::array<std::vector<Eigen::MatrixXd>, kBand> lower_;
};

// Inner products and updates of states stacked by node.
double dot(const std::vector<Eigen::VectorXd>& a, const std::vector<Eigen::VectorXd>& b) {
  double sum = 0;
  for (size_t i = 0; i < a.size(); ++i) sum += a[i].dot(b[i]);
  return sum;
}
void add(std::vector<Eigen::VectorXd>& a, double scale, const std::vector<Eigen::VectorXd>& b) {
  for (size_t i = 0; i < a.size(); ++i) a[i] += scale * b[i];
}

// An L-BFGS pair: the step s, the gradient's change y, and 1/(yᵀs).
struct Correction {
  std::vector<Eigen::VectorXd> s, y;
  double rho;
};

std::string key_name(const InbetweenKey& key, int index) {
  return message("keys[", index, "] (frame ", key.frame, ")");
}

// The keys by frame, each checked (the constructor's comment says what is refused).
std::vector<InbetweenKey> checked_keys(std::vector<InbetweenKey> keys, int num_handles) {
  if (keys.empty()) throw InputError("keys: none given; in-betweens need at least one key");
  if (static_cast<int>(keys.size()) > kMaxInbetweenKeys)
    throw InputError(message("keys: ", keys.size(), " given, at most ", kMaxInbetweenKeys));
  for (size_t i = 0; i < keys.size(); ++i) {
    const InbetweenKey& key = keys[i];
    const std::string name = key_name(key, static_cast<int>(i));
    if (key.frame < 0 || key.frame > kMaxInbetweenFrame)
      throw InputError(message(name, ": the frame is outside [0, ", kMaxInbetweenFrame, "]"));
    if (static_cast<int>(key.transforms.size()) != num_handles)
      throw InputError(message(name, ": expected ", num_handles,
                               " transforms (one per handle, None where not keyed), got ",
                               key.transforms.size()));
    bool any = false;
    for (int h = 0; h < num_handles; ++h) {
      if (!key.transforms[h]) continue;
      any = true;
      try {
        check_transforms({*key.transforms[h]}, 1);
      } catch (const InputError& error) {
        // check_transforms names the transform as transforms[0]: name it by key and handle.
        std::string what = error.what();
        what.replace(0, std::string("transforms[0]").size(), message(name, ", handle ", h));
        throw InputError(what);
      }
    }
    if (!any) throw InputError(message(name, ": keys no handle (every transform is None)"));
  }
  std::stable_sort(keys.begin(), keys.end(),
                   [](const InbetweenKey& a, const InbetweenKey& b) { return a.frame < b.frame; });
  for (size_t i = 1; i < keys.size(); ++i)
    if (keys[i].frame == keys[i - 1].frame)
      throw InputError(message("keys: two keys at frame ", keys[i].frame,
                               " (keys must be at least a frame apart)"));
  if (keys.back().frame - keys.front().frame > kMaxInbetweenFrames)
    throw InputError(message("keys: from frame ", keys.front().frame, " to ", keys.back().frame,
                             " spans more than ", kMaxInbetweenFrames, " frames"));
  return keys;
}

const InbetweenOptions& checked(const InbetweenOptions& options) {
  check_options(options, [](auto visit) { for_each_inbetween_option(visit); });
  return options;
}

}  // namespace

// The spacetime problem over nodes 0 … N (the header's notation).
class Inbetween::Problem {
 public:
  Problem(const Basis& basis, const Handles& handles, const Eigen::VectorXd& weights,
          const std::vector<InbetweenKey>& keys, const InbetweenOptions& options, EnergyKind energy,
          const DynamicsParameters& parameters)
      : never_keyed_(dynamics_handle_term(basis, handles, never_keyed_weights(weights, keys),
                                          options.simulation.pull)),
        r_(basis.dimension()),
        h_(parameters.substep),
        rho_(parameters.mass_scale),
        a_(1 + 2 * parameters.rayleigh / parameters.substep),
        b_(2 * parameters.rayleigh / parameters.substep),
        s_(parameters.substep * parameters.substep / (2 * parameters.mass_scale)) {
    const int substeps = options.simulation.substeps;
    N_ = (keys.back().frame - keys.front().frame) * substeps;
    // Each key after the first: its node and its penalty on the keyed handles' rigid fits.
    for (size_t k = 1; k < keys.size(); ++k) {
      KeyTerm term;
      term.node = (keys[k].frame - keys.front().frame) * substeps;
      term.hessian = Eigen::MatrixXd::Zero(r_, r_);
      term.gradient = Eigen::VectorXd::Zero(r_);
      for (size_t h = 0; h < handles.size(); ++h)
        if (keys[k].transforms[h])
          add_rigid_fit_term(basis, handles[h], weights[static_cast<Eigen::Index>(h)],
                             *keys[k].transforms[h], term);
      term.hessian = 0.5 * (term.hessian + term.hessian.transpose()).eval();
      // The penalty as ½ (q − q*)ᵀ H (q − q*), q* a fit that meets it (H⁺ on the directions
      // the keyed handles' fits see), evaluated without the cancellation of ½ qᵀHq + gᵀq + e.
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(term.hessian);
      const Eigen::VectorXd& lambda = eigen.eigenvalues();
      const double cutoff = kZeroCurvature * std::max(0.0, lambda.maxCoeff());
      const Eigen::VectorXd inverse =
          lambda.unaryExpr([cutoff](double l) { return l > cutoff ? 1 / l : 0.0; });
      term.fit = -(eigen.eigenvectors() *
                   (inverse.asDiagonal() * (eigen.eigenvectors().transpose() * term.gradient)));
      key_terms_.push_back(std::move(term));
    }
    for (int run = 0; run < kRuns; ++run) evaluators_.emplace_back(basis, energy, never_keyed_);
    hessian_ = evaluators_.front().ghost_energy.rest_hessian() + never_keyed_.hessian();
    hessian_ = 0.5 * (hessian_ + hessian_.transpose()).eval();
    for (const InbetweenKey& key : keys)
      key_nodes_.push_back((key.frame - keys.front().frame) * substeps);
    gx_.assign(N_, Eigen::VectorXd(r_));
    gq_.assign(N_, Eigen::VectorXd(r_));
    px_.assign(N_, Eigen::VectorXd(r_));
    pq_.assign(N_, Eigen::VectorXd(r_));
    R_.assign(N_, Eigen::VectorXd(r_));
  }

  int nodes() const { return N_; }
  int evaluations() const {
    int sum = 0;
    for (const Evaluator& evaluator : evaluators_) sum += evaluator.evaluations;
    return sum;
  }

  // ½ Σ ‖R_n‖² + the keys' penalty at the nodes q (N + 1 states), keeping ∇V and R for
  // gradient(); +inf where the ghost leaves the coordinates the energies take.
  double objective(const std::vector<Eigen::VectorXd>& q) {
    std::array<bool, kRuns> finite;
    over_nodes(
        [&](Evaluator& evaluator, int begin, int end, bool& ok) {
          for (int n = begin; n < end && ok; ++n)
            ok = evaluator.potential_gradient(0.5 * (q[n] + q[n + 1]), gx_[n]) &&
                 (b_ == 0 || evaluator.potential_gradient(q[n], gq_[n]));
        },
        finite);
    for (bool ok : finite)
      if (!ok) return kInfinity;
    control_ = 0;
    for (int n = 0; n < N_; ++n) {
      Eigen::VectorXd& R = R_[n];
      R = q[n + 1] - q[n];
      if (n > 0) R += q[n - 1] - q[n];
      R += s_ * force(n);
      if (n > 0) R += s_ * force(n - 1);
      control_ += 0.5 * R.squaredNorm();
    }
    double penalty = 0;
    for (const KeyTerm& key : key_terms_) {
      const Eigen::VectorXd d = q[key.node] - key.fit;
      penalty += 0.5 * d.dot(key.hessian * d);
    }
    return control_ + 0.5 * key_weight_ * penalty;
  }
  double control() const { return control_; }

  // ∇ of the last objective() with respect to q_1 … q_N (N blocks).
  void gradient(const std::vector<Eigen::VectorXd>& q, std::vector<Eigen::VectorXd>& g) {
    // F_n enters R_n and R_{n+1}, each times s: its ∂/∂q_n and ∂/∂q_{n+1} applied to
    // u_n = s (R_n + R_{n+1}), ∇²V(x_n) u_n and ∇²V(q_n) u_n, node by node in parallel.
    std::array<bool, kRuns> unused;
    over_nodes(
        [&](Evaluator& evaluator, int begin, int end, bool&) {
          Eigen::VectorXd u(r_);
          for (int n = begin; n < end; ++n) {
            u = R_[n];
            if (n + 1 < N_) u += R_[n + 1];
            u *= s_;
            const Eigen::VectorXd x = 0.5 * (q[n] + q[n + 1]);
            hessian_product(evaluator, x, gx_[n], u, px_[n]);
            if (n >= 1 && b_ != 0) hessian_product(evaluator, q[n], gq_[n], u, pq_[n]);
          }
        },
        unused);
    g.assign(N_, Eigen::VectorXd::Zero(r_));
    for (int n = 0; n < N_; ++n) {
      // R_n's second difference on q_{n+1}, q_n (n ≥ 1), q_{n−1} (n ≥ 2); g[m − 1] is q_m's.
      g[n] += R_[n];
      if (n >= 1) g[n - 1] -= 2 * R_[n];
      if (n >= 2) g[n - 2] += R_[n];
      g[n] += (a_ / 2) * px_[n];
      if (n >= 1) {
        g[n - 1] += (a_ / 2) * px_[n];
        if (b_ != 0) g[n - 1] -= b_ * pq_[n];
      }
    }
    for (const KeyTerm& key : key_terms_)
      g[key.node - 1] += key_weight_ * (key.hessian * (q[key.node] - key.fit));
  }

  // The model's solve: x ← B⁻¹ x (factor() first).
  void solve(std::vector<Eigen::VectorXd>& x) const { cholesky_.solve(x); }

  // v_n⁺ = (q_n − q_{n−1})/h − (h/2ρ) F_{n−1} at the nodes of the last objective() (v_0 = 0).
  std::vector<Eigen::VectorXd> velocities(const std::vector<Eigen::VectorXd>& q) const {
    std::vector<Eigen::VectorXd> v(N_ + 1, Eigen::VectorXd::Zero(r_));
    for (int n = 1; n <= N_; ++n) v[n] = (q[n] - q[n - 1]) / h_ - (h_ / (2 * rho_)) * force(n - 1);
    return v;
  }

 private:
  static constexpr double kInfinity = std::numeric_limits<double>::infinity();

  struct KeyTerm {
    int node = 0;
    Eigen::MatrixXd hessian;
    Eigen::VectorXd gradient;
    Eigen::VectorXd fit;  // q*
  };

  // Adds to `term` a handle's rigid-fit penalty, the squared mass-metric norm of the rigid part
  // of its vertices' residual e_i = x̄_i + U_i q − T x̄_i: with y_i = T x̄_i about their mass
  // centroid c (r_i = y_i − c), total mass m and inertia I, the fit's translation moment
  // Σ m_i e_i and rotation moment Σ m_i r_i × e_i weigh |·|²/m and I⁺: zero exactly when the
  // handle's rigid fit (to first order in e) is T, whatever the handle's own deformation.
  static void add_rigid_fit_term(const Basis& basis, const std::vector<int>& handle, double weight,
                                 const Eigen::Matrix4d& T, KeyTerm& term) {
    const Eigen::Index r = term.gradient.size();
    const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
    const Eigen::Vector3d t = T.topRightCorner<3, 1>();
    double mass = 0;
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (int v : handle) {
      mass += basis.mass[v];
      centre += basis.mass[v] * (R * basis.rest.row(v).transpose() + t);
    }
    if (!(mass > 0) || !(weight > 0)) return;
    centre /= mass;
    Eigen::Matrix<double, 6, Eigen::Dynamic> A = Eigen::MatrixXd::Zero(6, r);
    Eigen::Matrix<double, 6, 1> offset = Eigen::Matrix<double, 6, 1>::Zero();
    Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
    for (int v : handle) {
      const double m = basis.mass[v];
      const Eigen::Vector3d rest = basis.rest.row(v).transpose();
      const Eigen::Vector3d arm = R * rest + t - centre;
      Eigen::Matrix3d cross;
      cross << 0, -arm.z(), arm.y(), arm.z(), 0, -arm.x(), -arm.y(), arm.x(), 0;
      const Eigen::Matrix<double, 3, Eigen::Dynamic> rows = basis.vertex_rows(v);
      A.topRows<3>() += m * rows;
      A.bottomRows<3>() += m * cross * rows;
      const Eigen::Vector3d miss = rest - (R * rest + t);
      offset.head<3>() += m * miss;
      offset.tail<3>() += m * arm.cross(miss);
      inertia += m * (arm.squaredNorm() * Eigen::Matrix3d::Identity() - arm * arm.transpose());
    }
    // The metric: 1/m on the translation moment, I⁺ on the rotation moment (a handle on a line
    // has no moment about it).
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(inertia);
    const double cutoff = kZeroCurvature * std::max(0.0, eigen.eigenvalues().maxCoeff());
    const Eigen::Vector3d inverse =
        eigen.eigenvalues().unaryExpr([cutoff](double l) { return l > cutoff ? 1 / l : 0.0; });
    Eigen::Matrix<double, 6, 6> metric = Eigen::Matrix<double, 6, 6>::Zero();
    metric.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() / mass;
    metric.bottomRightCorner<3, 3>() =
        eigen.eigenvectors() * inverse.asDiagonal() * eigen.eigenvectors().transpose();
    term.hessian += weight * (A.transpose() * metric * A);
    term.gradient += weight * (A.transpose() * (metric * offset));
  }

  // The handles' weights in V: each handle never keyed keeps its own, the keyed ones none.
  static Eigen::VectorXd never_keyed_weights(Eigen::VectorXd weights,
                                             const std::vector<InbetweenKey>& keys) {
    for (const InbetweenKey& key : keys)
      for (size_t h = 0; h < key.transforms.size(); ++h)
        if (key.transforms[h]) weights[static_cast<Eigen::Index>(h)] = 0;
    return weights;
  }

  // F_n = a ∇V(x_n) − b ∇V(q_n).
  Eigen::VectorXd force(int n) const {
    Eigen::VectorXd F = a_ * gx_[n];
    if (b_ != 0) F -= b_ * gq_[n];
    return F;
  }

  // V's gradient on a ghost energy of its own.
  struct Evaluator {
    Evaluator(const Basis& basis, EnergyKind energy, const ReducedHandleTerm& never_keyed)
        : ghost_energy(basis, energy), never_keyed(never_keyed), work(basis.dimension()) {}

    // ∇V(x) into `gradient`; false where the ghost leaves the energies' range.
    bool potential_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) {
      ++evaluations;
      if (!std::isfinite(ghost_energy.value_and_gradient(x, gradient))) return false;
      never_keyed.value_and_gradient(x, work);
      gradient += work;
      return true;
    }

    GhostEnergy ghost_energy;
    const ReducedHandleTerm& never_keyed;
    Eigen::VectorXd work;
    int evaluations = 0;
  };

  // work(evaluator, begin, end, ok) for the kRuns runs of nodes [begin, end) that split 0 … N − 1,
  // each on its own evaluator, in parallel; ok starts true.
  template <typename Work>
  void over_nodes(Work&& work, std::array<bool, kRuns>& ok) {
    ok.fill(true);
    parallel_for(kRuns, [&](int run) {
      work(evaluators_[run], N_ * run / kRuns, N_ * (run + 1) / kRuns, ok[run]);
    });
  }

  // ∇²V(x) u from ∇V(x) (`gradient`) and one more gradient.
  void hessian_product(Evaluator& evaluator, const Eigen::VectorXd& x,
                       const Eigen::VectorXd& gradient, const Eigen::VectorXd& u,
                       Eigen::VectorXd& product) const {
    const double size = u.cwiseAbs().maxCoeff();
    if (!(size > 0)) {
      product.setZero();
      return;
    }
    const double step = kDifferenceStep * std::max(1.0, x.cwiseAbs().maxCoeff()) / size;
    if (!evaluator.potential_gradient(x + step * u, product)) {
      // Beyond the energies' range: the model's curvature instead.
      product = hessian_ * u;
      return;
    }
    product = (product - gradient) / step;
  }

  // ∇²V at q by differences of ghost gradients, symmetrised (r + 1 gradients).
  Eigen::MatrixXd hessian_at(const Eigen::VectorXd& q) {
    Evaluator& evaluator = evaluators_.front();
    Eigen::VectorXd base(r_), moved(r_);
    if (!evaluator.potential_gradient(q, base)) return hessian_;
    const double step = kDifferenceStep * std::max(1.0, q.cwiseAbs().maxCoeff());
    Eigen::MatrixXd H(r_, r_);
    Eigen::VectorXd x = q;
    for (Eigen::Index j = 0; j < r_; ++j) {
      x[j] += step;
      if (!evaluator.potential_gradient(x, moved)) return hessian_;
      H.col(j) = (moved - base) / step;
      x[j] = q[j];
    }
    return 0.5 * (H + H.transpose());
  }

 public:
  // B = Σ JᵀJ of the dynamics linearised along the motion plus the keys' penalty, factored: each
  // substep's ∇²V is K_n, interpolated linearly in time between its keys' ∇²V at their static
  // `poses` (the geometric stiffening a turned part shows, which the rest's K̃ lacks). With
  // F_n ≈ K_n ((a/2)(q_n + q_{n+1}) − b q_n), R_n's blocks on q_{n−1}, q_n, q_{n+1} are
  // I + s(a/2 − b)K_{n−1}, −2I + s(a/2)K_{n−1} + s(a/2 − b)K_n and I + s(a/2)K_n (R_0 only
  // the last, on q_1).
  void factor(const std::vector<Eigen::VectorXd>& poses) {
    std::vector<Eigen::MatrixXd> key_hessians;
    for (const Eigen::VectorXd& pose : poses) key_hessians.push_back(hessian_at(pose));
    const auto substep_hessian = [&](int n) {
      size_t k = 0;
      while (k + 2 < key_nodes_.size() && key_nodes_[k + 1] <= n) ++k;
      const double t = (n + 0.5 - key_nodes_[k]) / (key_nodes_[k + 1] - key_nodes_[k]);
      return Eigen::MatrixXd((1 - t) * key_hessians[k] + t * key_hessians[k + 1]);
    };
    const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(r_, r_);
    // Block m − 1 is q_m's (m = 1 … N).
    std::vector<Eigen::MatrixXd> diagonal(N_, Eigen::MatrixXd::Zero(r_, r_));
    std::array<std::vector<Eigen::MatrixXd>, BandedCholesky::kBand> below;
    for (auto& blocks : below) blocks.assign(N_, Eigen::MatrixXd::Zero(r_, r_));
    Eigen::MatrixXd previous;  // K_{n−1}
    for (int n = 0; n < N_; ++n) {
      const Eigen::MatrixXd K = substep_hessian(n);
      // (node, block) of R_n on the unknowns q_1 … q_N.
      std::vector<std::pair<int, Eigen::MatrixXd>> blocks;
      if (n >= 2) blocks.emplace_back(n - 1, I + (s_ * (a_ / 2 - b_)) * previous);
      if (n >= 1)
        blocks.emplace_back(n, -2 * I + (s_ * (a_ / 2)) * previous + (s_ * (a_ / 2 - b_)) * K);
      blocks.emplace_back(n + 1, I + (s_ * (a_ / 2)) * K);
      for (const auto& [i, A] : blocks)
        for (const auto& [j, C] : blocks) {
          if (j > i) continue;
          if (i == j)
            diagonal[i - 1].noalias() += A.transpose() * A;
          else
            below[i - j - 1][j - 1].noalias() += A.transpose() * C;
        }
      previous = K;
    }
    // One weight for every key: kKeyDominance times the largest block's trace over the keys'.
    double motion = 0, keys = 0;
    for (const Eigen::MatrixXd& block : diagonal) motion = std::max(motion, block.trace());
    for (const KeyTerm& key : key_terms_) keys = std::max(keys, key.hessian.trace());
    key_weight_ = keys > 0 ? kKeyDominance * motion / keys : 0;
    for (const KeyTerm& key : key_terms_) diagonal[key.node - 1] += key_weight_ * key.hessian;
    for (Eigen::MatrixXd& block : diagonal) block.diagonal().array() += kProximity * motion / r_;
    cholesky_.factor(diagonal, below);
  }

 private:
  ReducedHandleTerm never_keyed_;
  std::deque<Evaluator> evaluators_;  // kRuns, one a run of nodes
  Eigen::Index r_;
  double h_, rho_, a_, b_, s_;
  int N_ = 0;
  std::vector<KeyTerm> key_terms_;
  double key_weight_ = 0;
  Eigen::MatrixXd hessian_;  // K̃ = ∇²V at rest, where a difference leaves the energies' range
  std::vector<int> key_nodes_;
  BandedCholesky cholesky_;
  // At the last objective(): ∇V(x_n), ∇V(q_n), R_n, ½ Σ ‖R_n‖².
  std::vector<Eigen::VectorXd> gx_, gq_, R_;
  // At the last gradient(): ∇²V(x_n) u_n and ∇²V(q_n) u_n.
  std::vector<Eigen::VectorXd> px_, pq_;
  double control_ = 0;
};

Inbetween::Inbetween(const Basis& basis, const Handles& handles, const VectorRef& weights,
                     std::vector<InbetweenKey> keys, const InbetweenOptions& options,
                     EnergyKind energy)
    : basis_(basis),
      handles_(handles),
      num_handles_(static_cast<int>(handles.size())),
      options_(checked(options)),
      energy_(energy) {
  // Simulation checks the basis, the handles, the weights and its options.
  simulation_ =
      std::make_unique<ReducedDynamics>(basis, handles, weights, options.simulation, energy);
  weights_ = checked_handle_weights(handles, weights, basis.num_vertices());
  keys_ = checked_keys(std::move(keys), num_handles_);
  Eigen::MatrixXd K = GhostEnergy(basis, energy).rest_hessian();
  K = 0.5 * (K + K.transpose()).eval();
  parameters_ = dynamics_parameters(K, options.simulation);
  problem_ =
      std::make_unique<Problem>(basis, handles, weights_, keys_, options_, energy, parameters_);
  // After the last key: each keyed handle at its last keyed transform, the others at the
  // identity.
  last_transforms_.assign(num_handles_, Eigen::Matrix4d::Identity());
  for (const InbetweenKey& key : keys_)
    for (int h = 0; h < num_handles_; ++h)
      if (key.transforms[h]) last_transforms_[h] = *key.transforms[h];
}

Inbetween::~Inbetween() = default;

Eigen::VectorXd Inbetween::static_pose(const InbetweenKey& key) const {
  // The handles keyed here at their transforms and the never-keyed at the identity; the others
  // free (weight 0).
  Eigen::VectorXd weights = weights_;
  Transforms transforms(num_handles_, Eigen::Matrix4d::Identity());
  for (int h = 0; h < num_handles_; ++h) {
    if (key.transforms[h]) {
      transforms[h] = *key.transforms[h];
      continue;
    }
    for (const InbetweenKey& other : keys_)
      if (other.transforms[h]) weights[h] = 0;
  }
  ReducedSolver solver(basis_, handles_, weights, options_.simulation.pull, energy_);
  solver.set_transforms(transforms);
  solver.solve(kPoseIterations, options_.simulation.tolerance);
  return solver.q();
}

InbetweenStats Inbetween::solve() {
  const auto start = std::chrono::steady_clock::now();
  const int N = problem_->nodes();
  const int substeps = options_.simulation.substeps;
  const int evaluations_before = problem_->evaluations();
  InbetweenStats stats;
  stats.nodes = N;
  // The starting guess: the keys' static poses, linear in between.
  std::vector<Eigen::VectorXd> poses;
  for (const InbetweenKey& key : keys_) poses.push_back(static_pose(key));
  std::vector<Eigen::VectorXd> q(N + 1);
  for (size_t k = 0; k + 1 < keys_.size(); ++k) {
    const int from = (keys_[k].frame - first_frame()) * substeps;
    const int to = (keys_[k + 1].frame - first_frame()) * substeps;
    for (int n = from; n <= to; ++n) {
      const double t = static_cast<double>(n - from) / (to - from);
      q[n] = (1 - t) * poses[k] + t * poses[k + 1];
    }
  }
  q[0] = poses.front();

  if (N > 0) {
    problem_->factor(poses);
    double value = problem_->objective(q);
    if (!std::isfinite(value))
      throw InputError(
          "keys: the static poses of the keys move the mesh beyond the coordinates "
          "the energies take");
    stats.initial_control = problem_->control();
    const double initial_value = value;
    // Quasi-Newton: L-BFGS whose initial inverse Hessian is the banded Gauss-Newton model's, so
    // that the steps learn how the curvature departs from the rest's along the motion.
    std::vector<Eigen::VectorXd> gradient, previous_gradient, step, trial(q);
    std::deque<Correction> corrections;
    for (stats.iterations = 0; stats.iterations < options_.solve_iterations; ++stats.iterations) {
      problem_->gradient(q, gradient);
      if (!step.empty()) {
        Correction correction{step, gradient, 0};
        for (int i = 0; i < N; ++i) correction.y[i] -= previous_gradient[i];
        const double curvature = dot(correction.y, correction.s);
        if (curvature > 0) {
          correction.rho = 1 / curvature;
          corrections.push_back(std::move(correction));
          if (static_cast<int>(corrections.size()) > kCorrections) corrections.pop_front();
        }
      }
      step = gradient;
      std::vector<double> alphas(corrections.size());
      for (size_t c = corrections.size(); c-- > 0;) {
        alphas[c] = corrections[c].rho * dot(corrections[c].s, step);
        add(step, -alphas[c], corrections[c].y);
      }
      problem_->solve(step);
      for (size_t c = 0; c < corrections.size(); ++c)
        add(step, alphas[c] - corrections[c].rho * dot(corrections[c].y, step), corrections[c].s);
      double size = 0;
      for (int i = 0; i < N; ++i) {
        step[i] = -step[i];
        size = std::max(size, step[i].cwiseAbs().maxCoeff());
      }
      const double slope = dot(gradient, step);
      if (size <= options_.solve_tolerance) {
        stats.converged = true;
        break;
      }
      // Backtracking from the full step; objective() leaves ∇V and R at the accepted trial.
      double alpha = 1, trial_value = value;
      bool decreased = false;
      if (slope < 0) {
        for (int halving = 0; halving <= kMaxHalvings; ++halving, alpha /= 2) {
          for (int i = 0; i < N; ++i) trial[i + 1] = q[i + 1] + alpha * step[i];
          trial_value = problem_->objective(trial);
          if (trial_value <= value + kArmijo * alpha * slope) {
            decreased = true;
            break;
          }
        }
      }
      if (!decreased) {
        // L-BFGS's pairs may have learnt the differenced gradient's noise: the model's own step
        // next; failing that, the objective is at the precision its gradient has.
        if (!corrections.empty()) {
          corrections.clear();
          problem_->objective(q);
          step.clear();
          continue;
        }
        stats.converged = value <= kFloor * initial_value;
        stats.stalled = !stats.converged;
        problem_->objective(q);
        break;
      }
      for (int i = 0; i < N; ++i) step[i] *= alpha;
      previous_gradient = gradient;
      std::swap(q, trial);
      trial = q;
      value = trial_value;
    }
    stats.control = problem_->control();
  }
  q_ = q;
  v_ = N > 0 ? problem_->velocities(q)
             : std::vector<Eigen::VectorXd>(1, Eigen::VectorXd::Zero(dimension()));
  // Simulation after the last key, from the state there.
  after_.clear();
  simulation_->set_state(q_.back(), v_.back(), last_transforms_);
  simulation_->forget();
  after_.emplace_back(q_.back(), v_.back());
  solved_ = true;
  stats.evaluations = problem_->evaluations() - evaluations_before;
  stats.ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  stats_ = stats;
  return stats;
}

const std::pair<Eigen::VectorXd, Eigen::VectorXd>& Inbetween::after(int frame) {
  const size_t index = static_cast<size_t>(frame - last_frame());
  while (after_.size() <= index) {
    simulation_->step(last_transforms_);
    after_.emplace_back(simulation_->q(), simulation_->v());
  }
  return after_[index];
}

void Inbetween::state(int frame, Eigen::VectorXd& q, Eigen::VectorXd& v) {
  if (frame < 0 || frame > kMaxInbetweenFrame)
    throw InputError(message("frame: ", frame, " is outside [0, ", kMaxInbetweenFrame, "]"));
  if (!solved_) solve();
  if (frame <= first_frame()) {
    q = q_.front();
    v = v_.front();
  } else if (frame < last_frame()) {
    const size_t node = static_cast<size_t>(frame - first_frame()) * options_.simulation.substeps;
    q = q_[node];
    v = v_[node];
  } else {
    const auto& state = after(frame);
    q = state.first;
    v = state.second;
  }
}

void Inbetween::positions(int frame, Eigen::Ref<Eigen::VectorXf> out) {
  Eigen::VectorXd q, v;
  state(frame, q, v);
  simulation_->positions_of(q, out);
}

}  // namespace modal_deform
