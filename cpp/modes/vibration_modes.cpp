#include "modes/vibration_modes.h"

#include <Spectra/SymGEigsShiftSolver.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "linalg/cholmod_llt.h"
#include "modes/stiffness_and_mass.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

// σ = −kShiftFraction · tr K / tr M, or kDeflatedShiftFraction when a kernel is deflated. The
// trace ratio is a mass-weighted mean of the spectrum, far above its low end and growing with the
// resolution (2.6e6 on the dragon with 23k vertices, 2.1e8 with 100k, whose lowest flexible
// eigenvalues are 0.024 and 0.037), so σ sits just below λ = 0 while K − σM stays far from
// singular. Zero modes left in K (undeflated ones, a floppy mesh's mechanisms) want σ not too
// close to 0: at 1e-10 the residuals of the other modes of two small spring networks exceed
// 1e-8 of the top eigenvalue. The wanted modes want it not far below them: deflating the rigid
// motions, the 100k dragon took 111 solves for 14 modes at 1e-8, 50 at 1e-10 or 1e-12; on the
// 23k dragon 20 modes took 93 solves for every fraction from 1e-12 to 1e-8 (106 at 1e-6).
// 1e-12 would let the bake's derivative solves refine once instead of twice (their contraction
// −σ/(λ − σ) below 1e-3 on the 100k dragon), but leaves small meshes' modes above their residual
// tolerance (the ARAP bake of a 3 by 3 by 3 bar: 5.3e-7 against 3.0e-7).
constexpr double kShiftFraction = 1e-8;
constexpr double kDeflatedShiftFraction = 1e-10;
// Spectra's convergence tolerance on the transformed eigenvalues.
constexpr double kEigenTolerance = 1e-10;
constexpr int kMaxRestarts = 1000;
// A mode fails when its residual exceeds kResidualTolerance · (|λ| + the largest λ computed) +
// kRoundingFloor · tr K / tr M, the last term for rounding in modes with λ = 0, plus the rounding
// of K φ itself (rounding_levels).
constexpr double kResidualTolerance = 1e-6;
constexpr double kRoundingFloor = 1e-12;

// y = (K − σM)⁻¹ x through one CHOLMOD factorisation: Spectra's operator for the shift-invert mode
// (its own SymShiftInvert factors with SparseLU, far slower). Each solve reports progress.
// Single-vector Lanczos still beats block methods here, although a single solve on the 100k
// dragon costs 115-130 ms against 18-26 ms per right-hand side in blocks of 15 to 52 (two solves
// at once on the two cores gain nothing: they are memory bound): block subspace iteration from
// modes of a 2000-vertex edge-collapsed coarse mesh, prolongated piecewise constant (after
// Nasikun & Hildebrandt 2022), needed 200 right-hand sides for 15 modes of the 100k dragon where
// Lanczos needs 52, and 480 against 72 for 20 modes of the 23k dragon (2.2 times the time).
class ShiftInvert {
 public:
  using Scalar = double;

  ShiftInvert(const SparseMatrix& K, const Eigen::VectorXd& dof_mass, const Eigen::MatrixXd& Z,
              Eigen::VectorXd decoupled_stiffness, Progress* progress, int expected_solves, CholmodLLT& llt)
      : K_(K),
        dof_mass_(dof_mass),
        Z_(Z),
        MZ_(dof_mass.asDiagonal() * Z),
        decoupled_stiffness_(std::move(decoupled_stiffness)),
        progress_(progress),
        expected_solves_(expected_solves),
        llt_(llt) {}

  Eigen::Index rows() const { return K_.rows(); }
  Eigen::Index cols() const { return K_.cols(); }

  // Factors K − σM; DOFs outside the problem get a stiffness so the matrix stays definite. With
  // σ < 0 and K semidefinite it is definite however ill-conditioned (shift-invert wants it near
  // singular), so only a failed pivot, K indefinite, is an error.
  void set_shift(double sigma) {
    try {
      llt_.factorize(K_, decoupled_stiffness_ - sigma * dof_mass_, 0.0);
    } catch (const OutOfMemory& e) {
      const double bytes = llt_.factor_bytes();  // 0 when the analysis itself ran out
      throw OutOfMemory(message("vibration modes: not enough memory to factor K - sigma M (", K_.rows(), " rows",
                                bytes > 0 ? message(", a factor of ", bytes / 1e9, " GB") : std::string(),
                                "): ", e.what()));
    } catch (const NumericalError& e) {
      throw NumericalError(message("vibration modes: K - sigma M with sigma = ", sigma,
                                   " cannot be factored; is K positive semidefinite? ", e.what()));
    }
  }

  void perform_op(const Scalar* x, Scalar* y) {
    Eigen::Map<Eigen::VectorXd>(y, rows()) = solve(Eigen::Map<const Eigen::VectorXd>(x, rows()));
  }

  // (K − σM)⁻¹ B, M-orthogonal to Z: Z spans eigenvectors, so projecting commutes with the
  // inverse and keeps the Krylov space off the deflated kernel.
  Eigen::MatrixXd solve(const Eigen::Ref<const Eigen::MatrixXd>& B) {
    Eigen::MatrixXd X = llt_.solve(B);
    if (Z_.cols()) X -= Z_ * (MZ_.transpose() * X);
    solves_ += static_cast<int>(B.cols());
    // Lanczos needs a few times ncv solves; the bar approaches 1 without reaching it.
    if (progress_) progress_->report("modes", 1.0 - std::exp(-static_cast<double>(solves_) / expected_solves_));
    return X;
  }

  int solves() const { return solves_; }

 private:
  const SparseMatrix& K_;
  const Eigen::VectorXd& dof_mass_;
  const Eigen::MatrixXd& Z_;
  const Eigen::MatrixXd MZ_;
  Eigen::VectorXd decoupled_stiffness_;
  Progress* progress_;
  int expected_solves_;
  int solves_ = 0;
  CholmodLLT& llt_;
};

// y = M x with the lumped (diagonal) mass matrix: the inner product of the Lanczos vectors.
struct MassProduct {
  using Scalar = double;
  const Eigen::VectorXd& dof_mass;
  void perform_op(const Scalar* x, Scalar* y) const {
    Eigen::Map<Eigen::VectorXd>(y, dof_mass.size()) =
        dof_mass.cwiseProduct(Eigen::Map<const Eigen::VectorXd>(x, dof_mass.size()));
  }
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
Eigen::VectorXd rounding_levels(const SparseMatrix& K, const Eigen::MatrixXd& modes, const Eigen::VectorXd& m) {
  const Eigen::MatrixXd magnitudes = modes.cwiseAbs().transpose();  // count by 3n: a DOF's values contiguous
  Eigen::MatrixXd products = Eigen::MatrixXd::Zero(magnitudes.rows(), magnitudes.cols());
  for (Eigen::Index j = 0; j < K.outerSize(); ++j)
    for (SparseMatrix::InnerIterator it(K, j); it; ++it)
      products.col(it.row()) += std::abs(it.value()) * magnitudes.col(j);
  const double terms_per_row = static_cast<double>(K.nonZeros()) / static_cast<double>(K.rows());
  return terms_per_row * std::numeric_limits<double>::epsilon() * inverse_mass_norms(products.transpose(), m);
}

// Z: a checked kernel basis (see checked_kernel_basis), possibly empty.
VibrationModes deflated_modes(const SparseMatrix& K, const VectorRef& mass, int count, const Eigen::MatrixXd& Z,
                              Progress* progress, CholmodLLT* factor) {
  const Eigen::VectorXd m = dof_masses(mass);
  const int n = static_cast<int>(m.size());
  const int free = static_cast<int>((m.array() > 0).count() - Z.cols());
  if (count < 1 || count >= free)
    throw InputError(message("count: expected 1 to ", free - 1,
                             " modes (DOFs with mass, less the deflated kernel, less 1), got ", count));
  const double trace_K = K.diagonal().sum();
  if (!(trace_K > 0)) throw InputError("K: no positive diagonal entry; there is no stiffness to take modes of");
  const double scale = trace_K / m.sum();
  const double sigma = -(Z.cols() ? kDeflatedShiftFraction : kShiftFraction) * scale;

  const std::vector<bool> decoupled = decoupled_dofs(K, mass);
  const int num_decoupled = static_cast<int>(std::count(decoupled.begin(), decoupled.end(), true));
  Eigen::VectorXd decoupled_stiffness = Eigen::VectorXd::Zero(n);
  for (int d = 0; d < n; ++d)
    if (decoupled[static_cast<size_t>(d)]) decoupled_stiffness[d] = trace_K / (n - num_decoupled);

  const int ncv = std::min(free, std::max(2 * count, count + 20));
  if (progress) progress->report("modes", 0.0);
  CholmodLLT own_factor(3);  // orders vertices, 3 DOFs each
  ShiftInvert op(K, m, Z, std::move(decoupled_stiffness), progress, 3 * ncv, factor ? *factor : own_factor);
  MassProduct mass_product{m};
  // Spectra selects among the transformed values ν = 1/(λ − σ): the smallest λ above σ have the
  // largest ν, hence LargestMagn. SmallestAlge only orders the result by ascending λ.
  Spectra::SymGEigsShiftSolver<ShiftInvert, MassProduct, Spectra::GEigsMode::ShiftInvert> eigs(op, mass_product, count,
                                                                                               ncv, sigma);
  // Start from (K − σM)⁻¹ M r for a random r: a rough start vector leaves rough components in the
  // Ritz vectors, which K amplifies into large residuals.
  std::mt19937 random(1);
  std::uniform_real_distribution<double> uniform(-0.5, 0.5);
  Eigen::VectorXd r(n), start(n);
  for (int d = 0; d < n; ++d) r[d] = m[d] * uniform(random);
  op.perform_op(r.data(), start.data());
  Eigen::Index converged = 0;
  try {
    eigs.init(start.data());
    converged =
        eigs.compute(Spectra::SortRule::LargestMagn, kMaxRestarts, kEigenTolerance, Spectra::SortRule::SmallestAlge);
  } catch (const NumericalError&) {
    throw;
  } catch (const Cancelled&) {
    throw;
  } catch (const OutOfMemory&) {
    throw;
  } catch (const std::runtime_error& e) {
    // Spectra's own failures (e.g. "TridiagEigen: eigen decomposition failed"): seen when most of
    // the mesh's motions cost no energy, so Lanczos meets one eigenvalue of huge multiplicity.
    throw NumericalError(message("vibration modes: the eigensolver failed (", e.what(),
                                 "); does the energy leave most motions free (a flat mesh under ARAP, a zero "
                                 "weight)? Try the shells energy with positive weights, or fewer modes"));
  }
  if (eigs.info() != Spectra::CompInfo::Successful)
    throw NumericalError(message("vibration modes: the eigensolver did not converge: ", converged, " of ", count,
                                 " eigenpairs after ", eigs.num_iterations(), " restarts and ", op.solves(),
                                 " solves"));

  // One step of inverse iteration on the Ritz vectors, then Rayleigh–Ritz on the block: a Ritz
  // vector keeps a trace of rough rounding error that K amplifies into a large residual, and one
  // more solve damps it by λ / λ_max.
  Eigen::MatrixXd Y = op.solve(m.asDiagonal() * eigs.eigenvectors());
  const Eigen::MatrixXd KY = multiply(K, Y);
  const Eigen::MatrixXd reduced_K = Y.transpose() * KY;
  const Eigen::MatrixXd reduced_M = Y.transpose() * (m.asDiagonal() * Y);
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> ritz(0.5 * (reduced_K + reduced_K.transpose()),
                                                                 0.5 * (reduced_M + reduced_M.transpose()));
  if (ritz.info() != Eigen::Success) throw NumericalError("vibration modes: the Rayleigh-Ritz step failed");

  VibrationModes result;
  result.eigenvalues = ritz.eigenvalues();  // ascending
  result.modes = Y * ritz.eigenvectors();   // M-orthonormal
  const Eigen::MatrixXd residual =
      KY * ritz.eigenvectors() - m.asDiagonal() * (result.modes * result.eigenvalues.asDiagonal());
  result.residuals = inverse_mass_norms(residual, m);
  const double largest = result.eigenvalues[count - 1];
  result.tolerances = kResidualTolerance * (result.eigenvalues.array().abs() + largest) + kRoundingFloor * scale +
                      rounding_levels(K, result.modes, m).array();
  result.shift = sigma;
  result.solves = op.solves();
  if (progress) progress->report("modes", 1.0);
  return result;
}

}  // namespace

void require_accurate(const VibrationModes& modes, int first, int last) {
  for (int i = first; i < last; ++i)
    if (!(modes.residuals[i] <= modes.tolerances[i]))
      throw NumericalError(message("vibration modes: mode ", i, " (eigenvalue ", modes.eigenvalues[i],
                                   ") has residual ", modes.residuals[i], ", above the tolerance ",
                                   modes.tolerances[i]));
}

VibrationModes vibration_modes(const SparseMatrix& K, const VectorRef& mass, int count, Progress* progress) {
  validate_stiffness_and_mass(K, mass);
  VibrationModes modes = deflated_modes(K, mass, count, Eigen::MatrixXd(K.rows(), 0), progress, nullptr);
  require_accurate(modes, 0, count);
  return modes;
}

VibrationModes vibration_modes(const SparseMatrix& K, const VectorRef& mass, int count,
                               const Eigen::Ref<const Eigen::MatrixXd>& Z, Progress* progress, CholmodLLT* factor,
                               ResidualCheck check) {
  VibrationModes modes = deflated_modes(K, mass, count, checked_kernel_basis(K, mass, Z), progress, factor);
  if (check == ResidualCheck::kThrow) require_accurate(modes, 0, count);
  return modes;
}

}  // namespace modal_deform
