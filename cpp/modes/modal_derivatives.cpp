#include "modes/modal_derivatives.h"

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "linalg/cholmod_llt.h"
#include "linalg/row_blocks.h"
#include "linalg/sparse_operations.h"
#include "mesh/union_find.h"
#include "modes/stiffness_and_mass.h"
#include "util/bake_stages.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

// A pivot of the QR of Z's rows this much smaller than the largest counts as zero.
constexpr double kRankThreshold = 1e-8;
// ‖K ψ − P b‖ ≤ kResidualTolerance (‖K‖₁ ‖ψ‖ + ‖P b‖) for each column.
constexpr double kResidualTolerance = 1e-6;
// Right-hand sides per solve: blocked solves run at BLAS-3 speed, and the bar moves between them.
constexpr Eigen::Index kBlockColumns = 64;

// A checked kernel basis, zero on the DOFs that take no part in the problem.
struct Kernel {
  Eigen::MatrixXd Z;
  std::vector<bool> decoupled;
};

Kernel checked_kernel(const SparseMatrix& K, const VectorRef& mass,
                      const Eigen::Ref<const Eigen::MatrixXd>& Z) {
  return {checked_kernel_basis(K, mass, Z), decoupled_dofs(K, mass)};
}

std::vector<int> pins_for(const SparseMatrix& K, const Kernel& kernel) {
  const int n = static_cast<int>(K.rows());
  UnionFind components(n);
  for (int j = 0; j < K.outerSize(); ++j)
    for (SparseMatrix::InnerIterator it(K, j); it; ++it)
      if (it.value() != 0) components.unite(static_cast<int>(it.row()), j);
  std::unordered_map<int, std::vector<int>> dofs_of;
  for (int d = 0; d < n; ++d)
    if (!kernel.decoupled[static_cast<size_t>(d)]) dofs_of[components.find(d)].push_back(d);

  std::vector<int> pins;
  for (const auto& [root, dofs] : dofs_of) {
    // The columns of Z that move this component, restricted to its DOFs, transposed: pivoting
    // picks the DOFs (columns) that best pin down the component's kernel.
    std::vector<Eigen::Index> columns;
    for (Eigen::Index k = 0; k < kernel.Z.cols(); ++k)
      if (std::any_of(dofs.begin(), dofs.end(), [&](int d) { return kernel.Z(d, k) != 0; }))
        columns.push_back(k);
    if (columns.empty()) continue;
    Eigen::MatrixXd rows_t(static_cast<Eigen::Index>(columns.size()),
                           static_cast<Eigen::Index>(dofs.size()));
    for (size_t a = 0; a < columns.size(); ++a)
      for (size_t b = 0; b < dofs.size(); ++b) rows_t(a, b) = kernel.Z(dofs[b], columns[a]);
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(rows_t);
    qr.setThreshold(kRankThreshold);
    for (Eigen::Index r = 0; r < qr.rank(); ++r)
      pins.push_back(dofs[qr.colsPermutation().indices()[r]]);
  }
  if (static_cast<Eigen::Index>(pins.size()) != kernel.Z.cols())
    throw InputError(message(
        "Z: its ", kernel.Z.cols(), " columns do not split over the connected components of K ",
        "(their ranks per component add up to ", pins.size(), "); Z must span the kernel of K"));
  std::sort(pins.begin(), pins.end());
  return pins;
}

void check_right_hand_sides(const SparseMatrix& K, const Eigen::Ref<const Eigen::MatrixXd>& B) {
  if (B.rows() != K.rows())
    throw InputError(message("B: expected ", K.rows(), " rows, got ", B.rows()));
  if (!B.allFinite()) throw InputError("B: has an entry that is not finite");
}

Eigen::MatrixXd solve_with_pins(const SparseMatrix& K, const VectorRef& mass, const Kernel& kernel,
                                const Eigen::Ref<const Eigen::MatrixXd>& B,
                                const std::vector<int>& pins, Progress* progress) {
  const Eigen::Index n = K.rows();
  if (progress) progress->report(stages::kDerivativeSolves, 0.0);

  // With P b in the range of K, K ψ = P b has a solution with ψ = 0 at the pins (the pinned rows
  // of Z are invertible), and that solution also solves (K + w Σ eₛeₛᵀ) ψ = P b, which is definite:
  // pinning adds a stiffness on the diagonal and keeps the pattern. w: K's mean diagonal entry.
  const std::vector<bool>& decoupled = kernel.decoupled;
  const auto coupled = static_cast<double>(std::count(decoupled.begin(), decoupled.end(), false));
  const double w = K.diagonal().sum() / std::max(coupled, 1.0);
  Eigen::VectorXd pin_stiffness = Eigen::VectorXd::Zero(n);
  for (int s : pins) pin_stiffness[s] = w;
  for (Eigen::Index d = 0; d < n; ++d)
    if (decoupled[static_cast<size_t>(d)]) pin_stiffness[d] = w > 0 ? w : 1.0;
  CholmodLLT llt(3);  // orders vertices, 3 DOFs each
  try {
    llt.factorize(K, pin_stiffness);
  } catch (const NumericalError& e) {
    throw NumericalError(message(
        "solve_in_range: K with its kernel pinned cannot be factored; does Z span the whole ",
        "kernel of K? ", e.what()));
  }
  return solve_in_range_by_blocks(
      K, dof_masses(mass), kernel.Z, kernel.decoupled, Eigen::MatrixXd(B),
      [&](Eigen::MatrixXd& PB, Eigen::Ref<Eigen::MatrixXd> X, const std::function<void(double)>&) {
        llt.solve(PB, X);
        return false;  // a pinned factor knows no residual
      },
      progress);
}

}  // namespace

// Each block is copied out of B before its solution goes in, so Ψ needs no memory of its own. The
// blocks reuse their buffers: at 100k vertices each is 113 MB, and fresh memory costs page faults.
Eigen::MatrixXd solve_in_range_by_blocks(const SparseMatrix& K, const Eigen::VectorXd& m,
                                         const Eigen::MatrixXd& Z,
                                         const std::vector<bool>& decoupled, Eigen::MatrixXd B,
                                         const BlockSolve& solve, Progress* progress) {
  check_right_hand_sides(K, B);
  const Eigen::Index n = K.rows();
  // P = I − Z (ZᵀZ)⁻¹ Zᵀ, also zero on the decoupled DOFs (part of the kernel, zero rows in Z).
  const Eigen::LLT<Eigen::MatrixXd> gram(Z.transpose() * Z);
  const double norm_K = norm_1(K);
  Eigen::MatrixXd& Psi = B;
  Eigen::MatrixXd PB;
  // Blocks of equal width, at most kBlockColumns: 110 columns go as 55 + 55 rather than 64 + 46,
  // so the buffers are the narrower (at 100k vertices 88 MB less for the four of them).
  const Eigen::Index blocks = (B.cols() + kBlockColumns - 1) / kBlockColumns;
  const Eigen::Index block_columns = blocks > 0 ? (B.cols() + blocks - 1) / blocks : 1;
  for (Eigen::Index first = 0; first < B.cols(); first += block_columns) {
    const Eigen::Index width = std::min(block_columns, B.cols() - first);
    PB.resize(n, width);
    for_row_blocks(n, [&](Eigen::Index first_row, Eigen::Index rows) {
      PB.middleRows(first_row, rows) = B.block(first_row, first, rows, width);
      for (Eigen::Index d = first_row; d < first_row + rows; ++d)
        if (decoupled[static_cast<size_t>(d)]) PB.row(d).setZero();
    });
    if (Z.cols()) add_dense_product(PB, Z, -gram.solve(inner_product(Z, PB)));
    const std::function<void(double)> report = [&](double part) {
      if (progress)
        progress->report(stages::kDerivativeSolves,
                         (static_cast<double>(first) + part * width) / B.cols());
    };
    auto X = Psi.middleCols(first, width);
    const Eigen::VectorXd rhs_norms = PB.colwise().norm();
    const bool residual_known = solve(PB, X, report);
    if (!residual_known) report(1.0);  // the product with K below takes as long as a step
    // K Z = 0: removing the kernel part leaves the residual as it is.
    if (Z.cols()) add_dense_product(X, Z, -inner_product(Z, m, X));
    if (!residual_known) add_product(K, X, -1.0, PB);  // PB becomes the residual P B − K X
    for (Eigen::Index j = 0; j < width; ++j) {
      const double bound = kResidualTolerance * (norm_K * X.col(j).norm() + rhs_norms[j]);
      if (!(PB.col(j).norm() <= bound))
        throw NumericalError(message("solve_in_range: column ", first + j, " has residual ",
                                     PB.col(j).norm(), ", above ", bound,
                                     "; does Z span the kernel of K?"));
    }
  }
  return std::move(Psi);
}

std::vector<std::array<int, 2>> derivative_pairs(const std::vector<std::vector<int>>& components,
                                                 int count) {
  const auto share_a_component = [](const std::vector<int>& a, const std::vector<int>& b) {
    for (size_t i = 0, j = 0; i < a.size() && j < b.size();) {
      if (a[i] == b[j]) return true;
      a[i] < b[j] ? ++i : ++j;
    }
    return false;
  };
  if (count < 0) throw InputError(message("derivatives: expected 0 or more, got ", count));
  std::vector<std::array<int, 2>> pairs;
  const auto k = static_cast<int>(components.size());
  for (int j = 0; j < k && static_cast<int>(pairs.size()) < count; ++j)
    for (int i = 0; i <= j && static_cast<int>(pairs.size()) < count; ++i)
      if (share_a_component(components[static_cast<size_t>(i)], components[static_cast<size_t>(j)]))
        pairs.push_back({i, j});
  if (static_cast<int>(pairs.size()) < count)
    throw InputError(
        message("derivatives: ", count, " asked for, but the ", k,
                " modes that have derivatives (all but the translations and zero modes) give only ",
                pairs.size(), " pairs; ask for more modes or fewer derivatives"));
  return pairs;
}

std::vector<std::vector<int>> components_moved(const Eigen::Ref<const Eigen::MatrixXd>& Phi,
                                               const Eigen::Ref<const Eigen::VectorXi>& component) {
  if (Phi.rows() != 3 * component.size())
    throw InputError(message("Phi: expected ", 3 * component.size(),
                             " rows (3 per labelled vertex), got ", Phi.rows()));
  if (component.size() > 0 && component.minCoeff() < 0)
    throw InputError(message("component: expected labels >= 0, got ", component.minCoeff()));
  const int c = component.size() > 0 ? component.maxCoeff() + 1 : 0;
  std::vector<std::vector<int>> moved(static_cast<size_t>(Phi.cols()));
  for (Eigen::Index col = 0; col < Phi.cols(); ++col) {
    Eigen::VectorXd norm = Eigen::VectorXd::Zero(c);
    for (Eigen::Index v = 0; v < component.size(); ++v)
      norm[component[v]] += Phi.col(col).segment<3>(3 * v).squaredNorm();
    const double total = norm.sum();
    for (int k = 0; k < c; ++k)
      if (norm[k] > 1e-12 * total) moved[static_cast<size_t>(col)].push_back(k);
  }
  return moved;
}

Eigen::MatrixXd solve_in_range(const SparseMatrix& K, const VectorRef& mass,
                               const Eigen::Ref<const Eigen::MatrixXd>& Z,
                               const Eigen::Ref<const Eigen::MatrixXd>& B, Progress* progress) {
  const Kernel kernel = checked_kernel(K, mass, Z);
  return solve_with_pins(K, mass, kernel, B, pins_for(K, kernel), progress);
}

}  // namespace modal_deform
