#include "modes/shifted_pencil.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "linalg/row_blocks.h"
#include "linalg/sparse_operations.h"
#include "modes/modal_derivatives.h"
#include "modes/stiffness_and_mass.h"
#include "util/bake_stages.h"
#include "util/errors.h"
#include "util/stopwatch.h"

namespace modal_deform {
namespace {

// σ = −kShiftFraction · tr K / tr M, or kDeflatedShiftFraction when a kernel is deflated. The
// trace ratio is a mass-weighted mean of the spectrum, far above its low end and growing with the
// resolution (the dragons': docs/measurements.md, "The eigensolver"), so σ sits just below λ = 0
// while K − σM stays far from singular. Zero modes left in K (undeflated ones, a floppy mesh's
// mechanisms) want σ not too close to 0: at 1e-10 the residuals of the other modes of two small
// spring networks exceed 1e-8 of the top eigenvalue. The wanted modes want it not far below
// them, or Lanczos needs more solves per mode.
// The deflated fraction also sets how often the bake's derivative solves refine: their
// contraction is −σ/(λ − σ), so a σ ten times closer to 0 saves a refinement step (a solve as wide
// as the derivatives); much closer (1e-12) leaves small meshes' modes above their residual
// tolerance (the ARAP bake of a 3 by 3 by 3 bar, tests/cpp/test_bake.cpp).
constexpr double kShiftFraction = 1e-8;
constexpr double kDeflatedShiftFraction = 1e-11;
// A mode fails when its residual exceeds kResidualTolerance · (|λ| + the largest λ computed) +
// kRoundingFloor · tr K / tr M, the last term for rounding in modes with λ = 0, plus the rounding
// of K φ itself (rounding_levels).
constexpr double kResidualTolerance = 1e-6;
constexpr double kRoundingFloor = 1e-12;

// Lanczos stops when ‖T y − ν y‖_M ≤ kEigenTolerance |ν| for each wanted Ritz pair: tight enough
// for the residuals tests/cpp/test_vibration_modes.cpp asks for after the final inverse iteration.
constexpr double kEigenTolerance = 1e-10;
// A Ritz estimate stops falling near the rounding of the largest ν, ε ν_max (docs/measurements.md,
// "The eigensolver"). A pair whose tolerance kEigenTolerance |ν| is below ε ν_max is out of reach
// once its Ritz value has settled (its estimate below kSettledEstimate |ν|: early Ritz values are
// low, so a mode can look out of reach and still converge); pairs all within kRoundingLevels
// ε ν_max have stalled when kStalledBlocks blocks do not halve the worst estimate relative to its
// tolerance.
constexpr double kSettledEstimate = 1e-6;
constexpr double kRoundingLevels = 10;
constexpr size_t kStalledBlocks = 4;
// A new Lanczos direction whose M-norm is below this fraction of the largest one in its block is
// dropped (the Krylov space has closed, up to rounding).
constexpr double kDependentNorm = 1e-8;
// Lanczos vectors allowed: kMaxColumnsPerMode per wanted mode, at least kMinColumns (a flat plate's
// few lowest modes take more than their share), plus the first block; twice what the dragons take
// (docs/measurements.md, "The eigensolver").
constexpr int kMaxColumnsPerMode = 12;
constexpr int kMinColumns = 120;
// Right-hand sides per block solve. A single solve streams the whole factor; a block shares the
// stream among its columns, so a solve per column costs less in wider blocks, but wider blocks
// need more columns for the same modes and keep more vectors: 8 balances the two (the cost per
// column: bench/results/native.json, BM_CholmodSolve/1 against BM_CholmodSolve/64).
constexpr int kBlockWidth = 8;

// solve_in_range refines until the error left on each eigenvector it does not know is below this
// fraction of that component, in at most this many steps. Those components are the small,
// high-frequency part of a modal derivative: one step (the contraction at σ's
// kDeflatedShiftFraction) leaves it about where the pinned solve gets (docs/measurements.md,
// "The eigensolver").
constexpr double kRefinementTolerance = 1e-3;
constexpr int kMaxRefinementSteps = 6;

// T X = P (K − σM)⁻¹ M X through one CHOLMOD factorisation, P the M-orthogonal projection off the
// deflated kernel Z: Z spans eigenvectors, so projecting commutes with the inverse and keeps the
// Krylov space off the kernel. T is self-adjoint in the M inner product.
class ShiftInvert {
 public:
  // factor: of K − σM; expected_solves: for the bar.
  ShiftInvert(CholmodLLT& factor, const Eigen::VectorXd& dof_mass, const Eigen::MatrixXd& Z,
              Progress* progress, int expected_solves)
      : factor_(factor),
        dof_mass_(dof_mass),
        Z_(Z),
        progress_(progress),
        expected_solves_(expected_solves) {}

  // T X: one block solve of X's columns.
  Eigen::MatrixXd apply(const Eigen::Ref<const Eigen::MatrixXd>& X) {
    Eigen::MatrixXd Y = factor_.solve(dof_mass_.asDiagonal() * X);
    if (Z_.cols()) add_dense_product(Y, Z_, -inner_product(Z_, dof_mass_, Y));
    solves_ += static_cast<int>(X.cols());
    // The bar approaches 1 without reaching it: the number of solves is not known in advance.
    if (progress_)
      progress_->report(stages::kModes,
                        1.0 - std::exp(-static_cast<double>(solves_) / expected_solves_));
    return Y;
  }

  int solves() const { return solves_; }

 private:
  CholmodLLT& factor_;
  const Eigen::VectorXd& dof_mass_;
  const Eigen::MatrixXd& Z_;
  Progress* progress_;
  int expected_solves_;
  int solves_ = 0;
};

// The eigenvectors of T with the largest ν = 1/(λ − σ), by block Lanczos with full
// reorthogonalisation in the M inner product. Stops when the Ritz residual ‖T y − ν y‖_M of each
// of the `count` largest is below kEigenTolerance |ν|, or early for a caller that deflates zero
// modes (see run); throws NumericalError past max_columns.
class BlockLanczos {
 public:
  // dimension: of the space T acts on (DOFs with mass less the deflated kernel); max_columns:
  // Lanczos vectors allowed, at most that; zero_nu: the ν above which a pair is a zero mode that
  // the caller deflates (infinity when it does not).
  BlockLanczos(ShiftInvert& T, const Eigen::VectorXd& m, Eigen::Index dimension,
               Eigen::Index max_columns, double zero_nu)
      : T_(T),
        m_(m),
        dimension_(dimension),
        zero_nu_(zero_nu),
        Q_(m.size(), max_columns),
        H_(Eigen::MatrixXd::Zero(max_columns, max_columns)) {}

  // R: the random start block (n by width). Returns the Ritz vectors (n by count, M-orthonormal)
  // of the `count` largest ν, descending.
  Eigen::MatrixXd run(const Eigen::MatrixXd& R, int count) {
    // The start block is T² R: undeflated zero modes dominate T R by up to 1/|σ| over the others
    // (1e7 on small meshes), whose directions in the orthonormalised block then carry rough
    // rounding error of that relative size, which K amplifies into residuals far above those of
    // a smooth start. A second solve damps it.
    Eigen::MatrixXd W = T_.apply(R);
    orthonormal_coefficients(W);
    W = T_.apply(W);
    orthonormal_coefficients(W);
    append(W);
    for (;;) {
      const Eigen::Index first = block_first_, last = columns_;
      W = T_.apply(Q_.middleCols(first, last - first));
      H_.block(0, first, last, last - first) = orthogonalize(W, last);
      const Eigen::MatrixXd next = orthonormal_coefficients(W);  // W before = W after · next
      // Ritz pairs of the space so far: T Q = Q H + W next Eᵀ over its last block.
      const Eigen::MatrixXd H =
          0.5 * (H_.topLeftCorner(last, last) + H_.topLeftCorner(last, last).transpose());
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> ritz(H);
      if (ritz.info() != Eigen::Success)
        throw NumericalError("vibration modes: the Ritz step failed");
      const Eigen::Index added = std::min<Eigen::Index>(next.rows(), Q_.cols() - last);
      if (last >= count) {
        const Eigen::MatrixXd S = ritz.eigenvectors().rowwise().reverse().leftCols(count);
        const Eigen::VectorXd nu = ritz.eigenvalues().reverse().head(count);
        const Eigen::VectorXd estimate = (next * S.bottomRows(last - first)).colwise().norm();
        const auto converged = (estimate.array() <= kEigenTolerance * nu.array().abs()).eval();
        // With `dimension` vectors the space is the whole problem and its Ritz pairs are exact
        // (small meshes).
        if (converged.all() || next.rows() == 0 || last == dimension_ ||
            zero_modes_stand_in_the_way(nu, estimate, converged))
          return dense_product(Q_.leftCols(last), S);
      }
      if (added == 0)
        throw NumericalError(message("vibration modes: the eigensolver did not converge within ",
                                     last, " Lanczos vectors (", T_.solves(), " solves)"));
      H_.block(last, first, added, last - first) = next.topRows(added);
      append(W.leftCols(added));
    }
  }

 private:
  // Zero modes left in T (a floppy mesh's) have ν about 1/|σ|, up to 1e6 times the wanted
  // flexible modes', whose estimates then stop near the rounding of the largest ν, above their
  // tolerance: true, once the zero modes have converged, when an unconverged pair is out of reach
  // or all have stalled at that rounding, so that the caller deflates them and solves again.
  bool zero_modes_stand_in_the_way(const Eigen::VectorXd& nu, const Eigen::VectorXd& estimate,
                                   const Eigen::Array<bool, Eigen::Dynamic, 1>& converged) {
    const auto zero = (nu.array() >= zero_nu_).eval();
    if (!zero.any() || (zero && !converged).any()) return false;
    const double rounding = std::numeric_limits<double>::epsilon() * nu.maxCoeff();
    const auto tolerance = (kEigenTolerance * nu.array().abs()).eval();
    const auto settled = (estimate.array() <= kSettledEstimate * nu.array().abs()).eval();
    if ((!converged && settled && tolerance < rounding).any()) return true;
    if ((!converged && estimate.array() > kRoundingLevels * rounding).any()) {
      worst_.clear();
      return false;
    }
    worst_.push_back((estimate.array() / tolerance).maxCoeff());
    const size_t blocks = worst_.size();
    return blocks > kStalledBlocks &&
           worst_[blocks - 1] > 0.5 * worst_[blocks - 1 - kStalledBlocks];
  }

  // W −= Q Qᵀ M W over the first `columns` of Q; returns the coefficients removed. W = T Q_j lies
  // in the span of the blocks j − 1, j and j + 1 but for what rounding lost: first the
  // recurrence's large parts along the last two blocks, then one pass over all of Q for the small
  // rest, which a single pass removes to rounding. Half the work of two full passes, which cost as
  // much as the solves (docs/measurements.md, "The eigensolver").
  Eigen::MatrixXd orthogonalize(Eigen::MatrixXd& W, Eigen::Index columns) const {
    Eigen::MatrixXd C = Eigen::MatrixXd::Zero(columns, W.cols());
    const Eigen::Index recent = std::max<Eigen::Index>(0, previous_first_);
    const auto R = Q_.middleCols(recent, columns - recent);
    C.bottomRows(columns - recent) = inner_product(R, m_, W);
    add_dense_product(W, R, -C.bottomRows(columns - recent));
    const auto Q = Q_.leftCols(columns);
    const Eigen::MatrixXd rest = inner_product(Q, m_, W);
    add_dense_product(W, Q, -rest);
    return C + rest;
  }

  // Makes W M-orthonormal in place, dropping directions below kDependentNorm of its largest
  // column; returns B with W before = W after · B. Twice: the Gram matrix squares W's condition,
  // so one pass leaves W orthonormal only up to rounding times that condition.
  Eigen::MatrixXd orthonormal_coefficients(Eigen::MatrixXd& W) const {
    const Eigen::MatrixXd first = orthonormal_pass(W);
    return orthonormal_pass(W) * first;
  }

  Eigen::MatrixXd orthonormal_pass(Eigen::MatrixXd& W) const {
    if (W.cols() == 0)
      return Eigen::MatrixXd(0, 0);  // Eigen's eigensolver fails on an empty matrix
    const Eigen::MatrixXd gram = inner_product(W, m_, W);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(gram);
    const double floor = kDependentNorm * kDependentNorm * gram.diagonal().maxCoeff();
    Eigen::Index keep = 0;
    while (keep < gram.rows() && eig.eigenvalues()[gram.rows() - 1 - keep] > floor) ++keep;
    const Eigen::MatrixXd V = eig.eigenvectors().rightCols(keep);
    const Eigen::VectorXd d = eig.eigenvalues().tail(keep).cwiseSqrt();
    W = dense_product(W, V * d.cwiseInverse().asDiagonal());
    return d.asDiagonal() * V.transpose();
  }

  // Appends W (M-orthonormal, M-orthogonal to Q) to Q as a new block.
  void append(const Eigen::Ref<const Eigen::MatrixXd>& W) {
    previous_first_ = block_first_;
    block_first_ = columns_;
    Q_.middleCols(columns_, W.cols()) = W;
    columns_ += W.cols();
  }

  ShiftInvert& T_;
  const Eigen::VectorXd& m_;
  Eigen::Index dimension_;
  double zero_nu_;
  // Per check since every unconverged estimate came within kRoundingLevels ε ν_max: the largest
  // estimate relative to its tolerance.
  std::vector<double> worst_;
  Eigen::MatrixXd Q_;  // the Lanczos vectors, columns_ of them so far
  Eigen::MatrixXd H_;  // Qᵀ M T Q
  Eigen::Index columns_ = 0;
  Eigen::Index block_first_ = 0;     // the last block's first column
  Eigen::Index previous_first_ = 0;  // the block before it's
};

// ‖R.col(i)‖ in the M⁻¹-norm for each column (DOFs without mass left out).
Eigen::VectorXd inverse_mass_norms(const Eigen::MatrixXd& R, const Eigen::VectorXd& m) {
  Eigen::VectorXd norms(R.cols());
  for (Eigen::Index i = 0; i < R.cols(); ++i) {
    double squared = 0;
    for (Eigen::Index d = 0; d < R.rows(); ++d)
      if (m[d] > 0) squared += R(d, i) * R(d, i) / m[d];
    norms[i] = std::sqrt(squared);
  }
  return norms;
}

// How far rounding alone can put each K φ off, in the M⁻¹-norm: a sum of k products carries an
// error up to about k ε Σ|K_dj||φ_j| (Higham's γ_k), k the nonzeros per row. Modes on a scan's
// stiff small parts (needles, flaps at non-manifold edges) have |K||φ| far above tr K / tr M, so
// their residuals stop at this level rather than at kRoundingFloor's, which assumes an even mesh.
Eigen::VectorXd rounding_levels(const SparseMatrix& K, const Eigen::MatrixXd& modes,
                                const Eigen::VectorXd& m) {
  const Eigen::MatrixXd magnitudes =
      modes.cwiseAbs().transpose();  // count by 3n: a DOF's values contiguous
  Eigen::MatrixXd products = Eigen::MatrixXd::Zero(magnitudes.rows(), magnitudes.cols());
  // Row d of |K||φ| from column d of K, K being symmetric: each is summed on one thread.
  for_row_blocks(K.outerSize(), [&](Eigen::Index first, Eigen::Index count) {
    for (Eigen::Index d = first; d < first + count; ++d)
      for (SparseMatrix::InnerIterator it(K, d); it; ++it)
        products.col(d) += std::abs(it.value()) * magnitudes.col(it.row());
  });
  const double terms_per_row = static_cast<double>(K.nonZeros()) / static_cast<double>(K.rows());
  return terms_per_row * std::numeric_limits<double>::epsilon() *
         inverse_mass_norms(products.transpose(), m);
}

}  // namespace

void require_accurate(const VibrationModes& modes, int first, int last) {
  for (int i = first; i < last; ++i)
    if (!(modes.residuals[i] <= modes.tolerances[i]))
      throw NumericalError(message("vibration modes: mode ", i, " (eigenvalue ",
                                   modes.eigenvalues[i], ") has residual ", modes.residuals[i],
                                   ", above the tolerance ", modes.tolerances[i]));
}

ShiftedPencil::ShiftedPencil(const SparseMatrix& K, const VectorRef& mass,
                             const Eigen::Ref<const Eigen::MatrixXd>& kernel, double shift)
    : K_(K), requested_shift_(shift), kernel_(checked_kernel_basis(K, mass, kernel)) {
  if (!(shift <= 0 && std::isfinite(shift)))
    throw InputError(
        message("shift: expected a finite sigma < 0, or 0 to choose one, got ", shift));
  const double trace_K = K.diagonal().sum();
  if (!(trace_K > 0))
    throw InputError("K: no positive diagonal entry; there is no stiffness to take modes of");
  dof_mass_ = dof_masses(mass);
  scale_ = trace_K / dof_mass_.sum();
  // DOFs outside the problem get a stiffness so that K − σM stays definite.
  decoupled_ = decoupled_dofs(K, mass);
  const auto n = static_cast<int>(K.rows());
  const int num_decoupled =
      static_cast<int>(std::count(decoupled_.begin(), decoupled_.end(), true));
  decoupled_stiffness_ = Eigen::VectorXd::Zero(n);
  for (int d = 0; d < n; ++d)
    if (decoupled_[static_cast<size_t>(d)]) decoupled_stiffness_[d] = trace_K / (n - num_decoupled);
}

void ShiftedPencil::analyze() { factor_.analyze(K_); }

// With σ < 0 and K semidefinite, K − σM is definite however ill-conditioned (shift-invert wants it
// near singular), so only a failed pivot, K indefinite, is an error.
void ShiftedPencil::factor_with_shift(double sigma) {
  try {
    factor_.factorize(K_, decoupled_stiffness_ - sigma * dof_mass_, 0.0);
  } catch (const OutOfMemory& e) {
    const double bytes = factor_.factor_bytes();  // 0 when the analysis itself ran out
    throw OutOfMemory(
        message("vibration modes: not enough memory to factor K - sigma M (", K_.rows(), " rows",
                bytes > 0 ? message(", a factor of ", bytes / 1e9, " GB") : std::string(),
                "): ", e.what()));
  } catch (const NumericalError& e) {
    throw NumericalError(message("vibration modes: K - sigma M with sigma = ", sigma,
                                 " cannot be factored; is K positive semidefinite? ", e.what()));
  }
  factored_shift_ = sigma;
}

VibrationModes ShiftedPencil::lowest_modes(int count, Progress* progress, double zero_modes_below) {
  if (!(zero_modes_below >= 0 && std::isfinite(zero_modes_below)))
    throw InputError(
        message("zero_modes_below: expected a finite bound >= 0, got ", zero_modes_below));
  const Eigen::VectorXd& m = dof_mass_;
  const auto n = static_cast<int>(m.size());
  const int free = static_cast<int>((m.array() > 0).count() - kernel_.cols());
  if (count < 1 || count >= free)
    throw InputError(message("count: expected 1 to ", free - 1,
                             " modes (DOFs with mass, less the deflated kernel, less 1), got ",
                             count));
  const double sigma = requested_shift_ < 0
                           ? requested_shift_
                           : -(kernel_.cols() ? kDeflatedShiftFraction : kShiftFraction) * scale_;
  const int width = std::min(free, kBlockWidth);
  const Eigen::Index max_columns =
      std::min(free, std::max(kMaxColumnsPerMode * count, kMinColumns) + width);
  if (progress) progress->report(stages::kModes, 0.0);
  if (sigma != factored_shift_) factor_with_shift(sigma);

  const Stopwatch stopwatch(timings_.modes);
  ShiftInvert T(factor_, m, kernel_, progress, 6 * count);
  std::mt19937 random(1);
  std::uniform_real_distribution<double> uniform(-0.5, 0.5);
  Eigen::MatrixXd R(n, width);
  for (Eigen::Index j = 0; j < width; ++j)
    for (int d = 0; d < n; ++d) R(d, j) = uniform(random);
  const double zero_nu = zero_modes_below > 0 ? 1 / (zero_modes_below - sigma)
                                              : std::numeric_limits<double>::infinity();
  BlockLanczos lanczos(T, m, free, max_columns, zero_nu);
  const Eigen::MatrixXd ritz_vectors = lanczos.run(R, count);

  // One step of inverse iteration on the Ritz vectors, then Rayleigh–Ritz on the block: a Ritz
  // vector keeps a trace of rough rounding error that K amplifies into a large residual, and one
  // more solve damps it by λ / λ_max.
  Eigen::MatrixXd Y = T.apply(ritz_vectors);
  const Eigen::MatrixXd KY = multiply(K_, Y);
  const Eigen::MatrixXd reduced_K = inner_product(Y, KY);
  const Eigen::MatrixXd reduced_M = inner_product(Y, m, Y);
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> ritz(
      0.5 * (reduced_K + reduced_K.transpose()), 0.5 * (reduced_M + reduced_M.transpose()));
  if (ritz.info() != Eigen::Success)
    throw NumericalError("vibration modes: the Rayleigh-Ritz step failed");

  VibrationModes result;
  result.eigenvalues = ritz.eigenvalues();               // ascending
  result.modes = dense_product(Y, ritz.eigenvectors());  // M-orthonormal
  Eigen::MatrixXd residual = dense_product(KY, ritz.eigenvectors());
  for_row_blocks(residual.rows(), [&](Eigen::Index first, Eigen::Index rows) {
    residual.middleRows(first, rows) -=
        m.segment(first, rows).asDiagonal() *
        (result.modes.middleRows(first, rows) * result.eigenvalues.asDiagonal());
  });
  result.residuals = inverse_mass_norms(residual, m);
  const double largest = result.eigenvalues[count - 1];
  result.tolerances = kResidualTolerance * (result.eigenvalues.array().abs() + largest) +
                      kRoundingFloor * scale_ + rounding_levels(K_, result.modes, m).array();
  result.shift = sigma;
  result.solves = T.solves();

  std::vector<Eigen::Index> within;
  for (Eigen::Index i = 0; i < count; ++i)
    if (result.residuals[i] <= result.tolerances[i]) within.push_back(i);
  known_eigenvalues_ = result.eigenvalues(within);
  known_modes_ = result.modes(Eigen::all, within);
  deflatable_ = 0;
  while (deflatable_ < static_cast<Eigen::Index>(within.size()) &&
         within[static_cast<size_t>(deflatable_)] == deflatable_)
    ++deflatable_;
  if (progress) progress->report(stages::kModes, 1.0);
  return result;
}

FlexibleModes ShiftedPencil::flexible_modes(int flexible, double zero, Progress* progress) {
  const auto free = static_cast<int>(K_.rows() - kernel_.cols());
  std::vector<double> zero_values;
  for (;;) {
    const int known = static_cast<int>(zero_values.size());
    const int count = std::min(flexible, free - known - 1);
    if (count < flexible)
      throw InputError(message("modes: the simulated mesh has only ", free - known,
                               " degrees of freedom besides its rigid motions and ", known,
                               " zero modes; ask for fewer modes"));
    const VibrationModes modes = lowest_modes(count, progress, zero);
    int found = 0;
    while (found < count && modes.eigenvalues[found] < zero) ++found;
    // The zero modes are deflated next, and the flexible ones go into the basis: both must be
    // accurate. Those past them only correct the derivative solves, which check their residuals.
    const int wanted = std::min(count, found + flexible);
    const auto within = (modes.residuals.array() <= modes.tolerances.array()).eval();
    require_accurate(modes, 0, found);
    if (found == 0) require_accurate(modes, 0, wanted);  // nothing to deflate: no second try
    deflate(found);
    zero_values.insert(zero_values.end(), modes.eigenvalues.data(),
                       modes.eigenvalues.data() + found);
    if (within.segment(found, wanted - found).all() && count - found >= flexible) {
      FlexibleModes result;
      result.num_zero = static_cast<int>(zero_values.size());
      result.eigenvalues.resize(result.num_zero + flexible);
      result.eigenvalues.head(result.num_zero) =
          Eigen::Map<const Eigen::VectorXd>(zero_values.data(), result.num_zero);
      result.eigenvalues.tail(flexible) = modes.eigenvalues.segment(found, flexible);
      result.flexible = modes.modes.middleCols(found, flexible);
      return result;
    }
  }
}

void ShiftedPencil::deflate(int count) {
  if (count < 0 || count > deflatable_)
    throw InputError(message("deflate: ", count, " modes asked for, but the last lowest_modes has ",
                             deflatable_, " lowest modes within their tolerance left to deflate"));
  const Eigen::Index kept = known_modes_.cols() - count;
  kernel_.conservativeResize(Eigen::NoChange, kernel_.cols() + count);
  kernel_.rightCols(count) = known_modes_.leftCols(count);
  known_eigenvalues_ = known_eigenvalues_.tail(kept).eval();
  known_modes_ = known_modes_.rightCols(kept).eval();
  deflatable_ -= count;
}

Eigen::MatrixXd ShiftedPencil::solve_in_range(Eigen::MatrixXd B, Progress* progress) {
  const Stopwatch stopwatch(timings_.solves);
  if (known_eigenvalues_.size() == 0)
    throw InputError(
        "solve_in_range: no eigenpair known to correct the shifted solves; call lowest_modes "
        "first");
  if (!(known_eigenvalues_.array() > 0).all())
    throw InputError(message("solve_in_range: the eigenpairs found include eigenvalue ",
                             known_eigenvalues_.minCoeff(),
                             ", not above 0: deflate the zero modes first"));
  if (progress) progress->report(stages::kDerivativeSolves, 0.0);
  const Eigen::Index n = K_.rows();
  const double sigma = factored_shift_;
  const Eigen::VectorXd& eigenvalues = known_eigenvalues_;
  const Eigen::MatrixXd& modes = known_modes_;
  const Eigen::VectorXd& m = dof_mass_;
  // (K − σM)⁻¹ = Σ φφᵀ/(λ − σ) over the M-orthonormal eigenpairs, K⁺ = Σ φφᵀ/λ on the range.
  // The known pairs get the difference −σ/(λ(λ − σ)) added; on the others the error of each step
  // is the fraction −σ/(λ − σ), at most `contraction`.
  const Eigen::VectorXd correction =
      (-sigma) * (eigenvalues.array() * (eigenvalues.array() - sigma)).inverse();
  const double contraction = -sigma / (eigenvalues.maxCoeff() - sigma);
  const int steps =
      static_cast<int>(std::ceil(std::log(kRefinementTolerance) / std::log(contraction)));
  if (steps > kMaxRefinementSteps)
    throw NumericalError(message(
        "solve_in_range: sigma = ", sigma, " is too far below the largest eigenvalue known, ",
        eigenvalues.maxCoeff(), ": ", steps, " refinement steps would be needed"));
  // One step: X += (K − σM)⁻¹ R less its kernel part, corrected on the known pairs by w. What it
  // leaves of R needs no product with K: K (K − σM)⁻¹ R = R + σM (K − σM)⁻¹ R, K Z = 0 and
  // K Φ = M Φ Λ, so R − K X = −σ M (K − σM)⁻¹ R − M Φ Λ w, which overwrites R: after the last
  // step it is the residual that solve_in_range_by_blocks checks, up to the rounding of the solve,
  // whose factor the modes' residuals (computed with K) have checked already.
  // The updates of X and R go through the rows once, block by block in parallel (rather than a
  // pass over 3n rows per statement on one thread). Each product is a statement of its own: nested
  // in one expression, Eigen evaluates M (σY − ΦΛw) coefficient by coefficient, as slowly as the
  // solve. Y stays in the factor's solution buffer, which is kept from step to step.
  const auto step = [&](Eigen::MatrixXd& R, Eigen::Ref<Eigen::MatrixXd> X) {
    const CholmodLLT::Solution Y = factor_.solve_in_workspace(R);
    const Eigen::MatrixXd w = correction.asDiagonal() * inner_product(modes, R);
    const Eigen::MatrixXd lambda_w = eigenvalues.asDiagonal() * w;
    const Eigen::MatrixXd kernel_part = inner_product(kernel_, m, Y);
    for_row_blocks(n, [&](Eigen::Index first, Eigen::Index rows) {
      auto x = X.middleRows(first, rows);
      const auto y = Y.middleRows(first, rows);
      const auto phi = modes.middleRows(first, rows);
      x += y;
      x.noalias() -= kernel_.middleRows(first, rows) * kernel_part;
      x.noalias() += phi * w;
      auto r = R.middleRows(first, rows);
      r = (-sigma) * y;
      r.noalias() -= phi * lambda_w;
      r.array().colwise() *= m.segment(first, rows).array();
    });
  };
  return solve_in_range_by_blocks(
      K_, m, kernel_, decoupled_, std::move(B),
      [&](Eigen::MatrixXd& PB, Eigen::Ref<Eigen::MatrixXd> X,
          const std::function<void(double)>& report) {
        X.setZero();
        for (int k = 0; k < steps; ++k) {
          if (k > 0) report(static_cast<double>(k) / steps);
          step(PB, X);  // PB becomes the residual
        }
        return true;
      },
      progress);
}

ShiftedPencil::Timings ShiftedPencil::timings() const {
  Timings timings = timings_;
  timings.factorisation = factor_.seconds();
  return timings;
}

}  // namespace modal_deform
