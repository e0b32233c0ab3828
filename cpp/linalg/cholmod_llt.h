// Sparse Cholesky factorisation A = L Lᵀ with CHOLMOD's supernodal method (dense BLAS-3 kernels
// on the supernodes; OpenBLAS here).
//
// The fill-reducing ordering is METIS nested dissection of the graph of nodes, groups of
// dofs_per_node consecutive rows (3 for x, y, z): the fill of ordering every row, with a ninth of
// the graph to partition. On a shells pattern this shortens the analysis and keeps the factor
// smaller than AMD's, which makes each solve faster (docs/measurements.md, "Choices in the core").
//
// The symbolic analysis (fill-reducing ordering, supernodes) depends only on the sparsity pattern
// and is kept across numeric factorisations of matrices with the same pattern, such as K − σM for
// another σ, or K with other pinned DOFs. Each instance owns its cholmod_common and workspaces, so
// one instance must not be used from two threads at once; two instances may.
#pragma once

#include <memory>

#include "util/types.h"

namespace modal_deform {

class CholmodLLT {
 public:
  explicit CholmodLLT(int dofs_per_node = 1);
  ~CholmodLLT();
  CholmodLLT(const CholmodLLT&) = delete;
  CholmodLLT& operator=(const CholmodLLT&) = delete;

  // Fill-reducing ordering and symbolic factorisation of the pattern of A (square, symmetric,
  // both triangles stored; only the lower triangle and the diagonal are read).
  void analyze(const SparseMatrix& A);

  // Below this estimate of the reciprocal condition number the factor is of a matrix that is
  // singular up to rounding: its solutions would be noise. Exactly singular positive semidefinite
  // matrices give estimates near machine epsilon, since their last pivot is rounding error.
  static constexpr double kSingularRcond = 1e-13;

  // Numeric factorisation of A + diag(shift) (shift: one value per row). Analyses A first when
  // its pattern differs from the one analysed last. Throws InputError for a malformed A,
  // OutOfMemory when CHOLMOD runs out of memory (analysis, factorisation or solve), and
  // NumericalError, naming the row where the factorisation broke down, when the matrix is not
  // numerically positive definite, or when rcond() is below min_rcond. A caller that knows the
  // matrix is definite and wants it nearly singular (shift-invert) passes 0: on a scan with
  // slivers, such as dragon_vrip_res2, the estimate falls below 1e-13 for any useful shift.
  void factorize(const SparseMatrix& A, const VectorRef& shift, double min_rcond = kSingularRcond);
  void factorize(const SparseMatrix& A);

  // X = (A + diag(shift))⁻¹ B for a rows() by k block of right-hand sides (k = 1 for a vector).
  // A block is much faster than k single solves. The second form writes into X, of B's size, so
  // that a caller solving again reuses its memory.
  Eigen::MatrixXd solve(const Eigen::Ref<const Eigen::MatrixXd>& B);
  void solve(const Eigen::Ref<const Eigen::MatrixXd>& B, Eigen::Ref<Eigen::MatrixXd> X);
  // The same solution left in CHOLMOD's own solution buffer (kept between solves of the same
  // width), viewed without a copy; valid until the next solve with this instance. Spares a buffer
  // of B's size: 125 MB for the bake's 52 modal derivatives at 100k vertices.
  using Solution = Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>>;
  Solution solve_in_workspace(const Eigen::Ref<const Eigen::MatrixXd>& B);

  int rows() const;
  // CHOLMOD's cheap estimate of the reciprocal condition number, (min Lᵢᵢ / max Lᵢᵢ)².
  double rcond() const { return rcond_; }
  // The row (in A's order) where the last factorisation found A not positive definite; -1 when
  // it did not fail that way.
  int failed_row() const { return failed_row_; }
  // Nonzeros of the factor L.
  double factor_nonzeros() const;
  // Bytes the numeric factor takes, known from the symbolic analysis already (before factorize).
  double factor_bytes() const;
  // Wall seconds spent in analyze and factorize since construction, solves excluded (the bake
  // reports factorisation apart from the stages that call it).
  double seconds() const { return seconds_; }

 private:
  void analyze_lower();
  void factorize_lower(SparseMatrix lower, double min_rcond);

  struct Cholmod;  // the CHOLMOD objects, freed by its destructor on every path
  std::unique_ptr<Cholmod> cholmod_;
  int dofs_per_node_;
  SparseMatrix lower_;  // lower triangle of A + diag(shift), the matrix CHOLMOD factors
  bool factorized_ = false;
  int failed_row_ = -1;
  double rcond_ = 0;
  double seconds_ = 0;
};

}  // namespace modal_deform
