#include "linalg/cholmod_llt.h"

#include <cholmod.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "linalg/blas_threads.h"
#include "util/errors.h"
#include "util/stopwatch.h"

namespace modal_deform {
namespace {

// CHOLMOD's error handler has no user pointer; the calling thread's last message is kept here and
// read right after the failing call, on the same thread.
thread_local std::string cholmod_message;

void record_cholmod_error(int status, const char* file, int line, const char* text) {
  cholmod_message = message(text, " (status ", status, ", ", file, ":", line, ")");
}

// While it lives, the OpenMP parallel regions the calling thread starts run on that thread alone.
// CHOLMOD's supernodal factorisation has loops of its own (clearing and assembling each supernode)
// with a team size fixed when it was compiled (4 in Debian's SuiteSparse 5), a team woken and put
// to sleep again for each of thousands of supernodes, which slows the factorisation on 2 cores
// (bench/results/native.json, BM_CholmodFactorize). The BLAS does the factorisation's work.
// MSVC's OpenMP 2.0 has no active levels; there the loops stay parallel.
class SerialOpenMP {
 public:
  SerialOpenMP() {
#if _OPENMP >= 200805
    levels_ = omp_get_max_active_levels();
    omp_set_max_active_levels(0);
#endif
  }
  ~SerialOpenMP() {
#if _OPENMP >= 200805
    omp_set_max_active_levels(levels_);
#endif
  }
  SerialOpenMP(const SerialOpenMP&) = delete;
  SerialOpenMP& operator=(const SerialOpenMP&) = delete;

 private:
  [[maybe_unused]] int levels_ = 0;
};

// The lower triangle of A plus diag(shift), with every diagonal entry stored (an unreferenced
// vertex has none in A, but still needs a pivot).
SparseMatrix lower_with_diagonal(const SparseMatrix& A, const VectorRef* shift) {
  if (A.rows() != A.cols())
    throw InputError(message("A: expected a square matrix, got ", A.rows(), " by ", A.cols()));
  const int n = static_cast<int>(A.rows());
  if (shift && shift->size() != n)
    throw InputError(message("shift: expected ", n, " values, got ", shift->size()));
  std::vector<int> count(n, 0);
  for (int j = 0; j < n; ++j) {
    int previous = -1;
    bool has_diagonal = false;
    for (SparseMatrix::InnerIterator it(A, j); it; ++it) {
      const int i = static_cast<int>(it.row());
      if (i <= previous)
        throw InputError(message("A: row indices of column ", j, " are not sorted or repeat"));
      previous = i;
      if (!std::isfinite(it.value()))
        throw InputError(message("A(", i, ", ", j, ") is not finite"));
      if (i >= j) ++count[j];
      has_diagonal |= i == j;
    }
    if (!has_diagonal) ++count[j];
  }
  SparseMatrix lower(n, n);
  int* outer = lower.outerIndexPtr();
  outer[0] = 0;
  for (int j = 0; j < n; ++j) outer[j + 1] = outer[j] + count[j];
  lower.resizeNonZeros(outer[n]);
  int* inner = lower.innerIndexPtr();
  double* value = lower.valuePtr();
  for (int j = 0; j < n; ++j) {
    int k = outer[j];
    const double diagonal_shift = shift ? (*shift)[j] : 0.0;
    if (!std::isfinite(diagonal_shift)) throw InputError(message("shift[", j, "] is not finite"));
    SparseMatrix::InnerIterator it(A, j);
    while (it && it.row() < j) ++it;
    if (!it || it.row() != j) {
      inner[k] = j;
      value[k++] = diagonal_shift;
    }
    for (; it; ++it) {
      inner[k] = static_cast<int>(it.row());
      value[k++] = it.value() + (it.row() == j ? diagonal_shift : 0.0);
    }
  }
  return lower;
}

// The lower triangle of the graph of nodes (groups of b consecutive rows) of `lower`, as a pattern.
SparseMatrix node_graph(const SparseMatrix& lower, int b) {
  const int nodes = static_cast<int>(lower.rows()) / b;
  std::vector<int> marker(static_cast<size_t>(nodes), -1);
  std::vector<int> outer{0}, inner;
  for (int J = 0; J < nodes; ++J) {
    for (int j = b * J; j < b * (J + 1); ++j)
      for (SparseMatrix::InnerIterator it(lower, j); it; ++it) {
        const int I = static_cast<int>(it.row()) / b;
        if (marker[static_cast<size_t>(I)] != J) {
          marker[static_cast<size_t>(I)] = J;
          inner.push_back(I);
        }
      }
    std::sort(inner.begin() + outer.back(), inner.end());
    outer.push_back(static_cast<int>(inner.size()));
  }
  SparseMatrix graph(nodes, nodes);
  graph.resizeNonZeros(static_cast<Eigen::Index>(inner.size()));
  std::copy(outer.begin(), outer.end(), graph.outerIndexPtr());
  std::copy(inner.begin(), inner.end(), graph.innerIndexPtr());
  return graph;
}

bool same_pattern(const SparseMatrix& a, const SparseMatrix& b) {
  return a.rows() == b.rows() && a.nonZeros() == b.nonZeros() &&
         std::equal(a.outerIndexPtr(), a.outerIndexPtr() + a.cols() + 1, b.outerIndexPtr()) &&
         std::equal(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros(), b.innerIndexPtr());
}

}  // namespace

struct CholmodLLT::Cholmod {
  cholmod_common common;
  cholmod_factor* factor = nullptr;
  // Workspaces of cholmod_solve2, kept between solves of the same width.
  cholmod_dense* solution = nullptr;
  cholmod_dense* work_y = nullptr;
  cholmod_dense* work_e = nullptr;

  Cholmod() {
    cholmod_start(&common);
    common.print = 0;  // never write to stdout/stderr; errors come back as exceptions
    common.error_handler = record_cholmod_error;
    common.supernodal = CHOLMOD_SUPERNODAL;
    common.final_ll = 1;
    common.quick_return_if_not_posdef = 1;
    // METIS ends the process when it runs out of memory; with this, CHOLMOD checks for room first
    // and falls back to AMD.
    common.metis_memory = 2.0;
    common.nmethods = 1;
    common.method[0].ordering = CHOLMOD_GIVEN;
  }
  ~Cholmod() {
    free_factor();
    cholmod_free_dense(&solution, &common);
    cholmod_free_dense(&work_y, &common);
    cholmod_free_dense(&work_e, &common);
    cholmod_finish(&common);
  }
  Cholmod(const Cholmod&) = delete;
  Cholmod& operator=(const Cholmod&) = delete;

  void free_factor() { cholmod_free_factor(&factor, &common); }

  // Throws when the last call failed (negative status): OutOfMemory for a lack of memory (or a
  // problem too large for CHOLMOD's integers), NumericalError otherwise.
  void check(bool ok, const char* what) {
    if (ok && common.status >= CHOLMOD_OK) return;
    if (common.status == CHOLMOD_OUT_OF_MEMORY || common.status == CHOLMOD_TOO_LARGE)
      throw OutOfMemory(message("CHOLMOD ", what, ": out of memory (", cholmod_message, ")"));
    throw NumericalError(message("CHOLMOD ", what, " failed: ", cholmod_message));
  }

  // A no-copy CHOLMOD view of `lower`, the lower triangle of a symmetric matrix (its pattern only
  // when `values` is false).
  static cholmod_sparse view(SparseMatrix& lower, bool values = true) {
    cholmod_sparse A{};
    A.nrow = A.ncol = static_cast<size_t>(lower.rows());
    A.nzmax = static_cast<size_t>(lower.nonZeros());
    A.p = lower.outerIndexPtr();
    A.i = lower.innerIndexPtr();
    A.x = values ? lower.valuePtr() : nullptr;
    A.stype = -1;  // symmetric, lower triangle stored
    A.itype = CHOLMOD_INT;
    A.xtype = values ? CHOLMOD_REAL : CHOLMOD_PATTERN;
    A.dtype = CHOLMOD_DOUBLE;
    A.sorted = 1;
    A.packed = 1;
    return A;
  }
};

CholmodLLT::CholmodLLT(int dofs_per_node)
    : cholmod_(std::make_unique<Cholmod>()), dofs_per_node_(dofs_per_node) {
  if (dofs_per_node < 1)
    throw InputError(message("dofs_per_node: expected 1 or more, got ", dofs_per_node));
}

CholmodLLT::~CholmodLLT() = default;

int CholmodLLT::rows() const { return static_cast<int>(lower_.rows()); }

double CholmodLLT::factor_nonzeros() const {
  const cholmod_factor* L = cholmod_->factor;
  if (!L) return 0;
  return L->is_super ? static_cast<double>(L->xsize) : static_cast<double>(L->nzmax);
}

double CholmodLLT::factor_bytes() const {
  const cholmod_factor* L = cholmod_->factor;
  if (!L) return 0;
  // Values, row indices, and the column (or supernode) arrays.
  if (L->is_super) return 8.0 * L->xsize + 4.0 * L->ssize + 4.0 * 4 * L->nsuper;
  return 12.0 * static_cast<double>(L->nzmax) + 4.0 * 4 * L->n;
}

void CholmodLLT::analyze(const SparseMatrix& A) {
  const Stopwatch stopwatch(seconds_);
  lower_ = lower_with_diagonal(A, nullptr);
  analyze_lower();
}

void CholmodLLT::analyze_lower() {
  factorized_ = false;
  cholmod_->free_factor();
  const int n = rows();
  const int b = n % dofs_per_node_ == 0 ? dofs_per_node_ : 1;
  SparseMatrix graph = node_graph(lower_, b);
  cholmod_sparse graph_view = Cholmod::view(graph, false);
  std::vector<int> node_order(static_cast<size_t>(n / b)), order(static_cast<size_t>(n));
  cholmod_->check(
      cholmod_metis(&graph_view, nullptr, 0, 1, node_order.data(), &cholmod_->common) != 0,
      "METIS ordering");
  for (int k = 0; k < n / b; ++k)
    for (int r = 0; r < b; ++r)
      order[static_cast<size_t>(b * k + r)] = b * node_order[static_cast<size_t>(k)] + r;
  cholmod_sparse view = Cholmod::view(lower_);
  cholmod_->factor = cholmod_analyze_p(&view, order.data(), nullptr, 0, &cholmod_->common);
  cholmod_->check(cholmod_->factor != nullptr, "analyze");
}

void CholmodLLT::factorize(const SparseMatrix& A) {
  factorize_lower(lower_with_diagonal(A, nullptr), kSingularRcond);
}

void CholmodLLT::factorize(const SparseMatrix& A, const VectorRef& shift, double min_rcond) {
  factorize_lower(lower_with_diagonal(A, &shift), min_rcond);
}

void CholmodLLT::factorize_lower(SparseMatrix lower, double min_rcond) {
  const Stopwatch stopwatch(seconds_);
  factorized_ = false;
  failed_row_ = -1;
  const bool new_pattern = !cholmod_->factor || !same_pattern(lower, lower_);
  lower_ = std::move(lower);
  if (new_pattern) analyze_lower();
  cholmod_sparse view = Cholmod::view(lower_);
  cholmod_factor* L = cholmod_->factor;
  const BlasThreadLimit blas_threads;
  const SerialOpenMP serial_openmp;
  const int ok = cholmod_factorize(&view, L, &cholmod_->common);
  if (cholmod_->common.status == CHOLMOD_NOT_POSDEF) {
    const int pivot = static_cast<int>(L->minor);
    const int row = static_cast<const int*>(L->Perm)[pivot];
    failed_row_ = row;
    throw NumericalError(message(
        "the matrix is not positive definite: the Cholesky factorisation breaks down at row ", row,
        " (pivot ", pivot + 1, " of ", rows(), " in CHOLMOD's ordering)"));
  }
  cholmod_->check(ok != 0, "factorize");
  rcond_ = cholmod_rcond(L, &cholmod_->common);
  if (!(rcond_ >= min_rcond))
    throw NumericalError(message(
        "the matrix is singular to working precision (CHOLMOD's reciprocal condition estimate ",
        rcond_, "): its solutions would be rounding noise"));
  factorized_ = true;
}

Eigen::MatrixXd CholmodLLT::solve(const Eigen::Ref<const Eigen::MatrixXd>& B) {
  Eigen::MatrixXd X(B.rows(), B.cols());
  solve(B, X);
  return X;
}

void CholmodLLT::solve(const Eigen::Ref<const Eigen::MatrixXd>& B, Eigen::Ref<Eigen::MatrixXd> X) {
  if (X.rows() != B.rows() || X.cols() != B.cols())
    throw InputError(
        message("X: expected ", B.rows(), " by ", B.cols(), ", got ", X.rows(), " by ", X.cols()));
  X = solve_in_workspace(B);
}

CholmodLLT::Solution CholmodLLT::solve_in_workspace(const Eigen::Ref<const Eigen::MatrixXd>& B) {
  if (!factorized_)
    throw std::logic_error("CholmodLLT::solve: no successful factorisation to solve with");
  if (B.rows() != rows())
    throw InputError(message("B: expected ", rows(), " rows, got ", B.rows()));
  if (B.cols() == 0) return Solution(nullptr, B.rows(), 0, Eigen::OuterStride<>(B.rows()));
  cholmod_dense rhs{};
  rhs.nrow = static_cast<size_t>(B.rows());
  rhs.ncol = static_cast<size_t>(B.cols());
  rhs.d = static_cast<size_t>(B.outerStride());
  rhs.nzmax = rhs.d * rhs.ncol;
  rhs.x = const_cast<double*>(B.data());  // read only
  rhs.xtype = CHOLMOD_REAL;
  rhs.dtype = CHOLMOD_DOUBLE;
  Cholmod& c = *cholmod_;
  const BlasThreadLimit blas_threads;
  const int ok = cholmod_solve2(CHOLMOD_A, c.factor, &rhs, nullptr, &c.solution, nullptr, &c.work_y,
                                &c.work_e, &c.common);
  c.check(ok != 0, "solve");
  return Solution(static_cast<const double*>(c.solution->x), B.rows(), B.cols(),
                  Eigen::OuterStride<>(static_cast<Eigen::Index>(c.solution->d)));
}

}  // namespace modal_deform
