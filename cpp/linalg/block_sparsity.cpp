#include "linalg/block_sparsity.h"

#include <algorithm>
#include <limits>
#include <stdexcept>

#include "util/errors.h"

namespace modal_deform {
namespace {

// Fewer columns are sorted on the calling thread.
constexpr int kParallelColumns = 20000;

}  // namespace

BlockSparsity::BlockSparsity(int num_vertices, const std::vector<std::array<int, 2>>& pairs) {
  // Counting sort of both directions of every pair (plus the diagonal) by column, then sort
  // and deduplicate each column.
  std::vector<long long> count(num_vertices, 1);
  for (const auto& [a, b] : pairs) {
    ++count[a];
    ++count[b];
  }
  std::vector<long long> start(num_vertices + 1, 0);
  for (int v = 0; v < num_vertices; ++v) start[v + 1] = start[v] + count[v];
  std::vector<int> rows(static_cast<size_t>(start[num_vertices]));
  std::vector<long long> fill(start.begin(), start.end() - 1);
  for (int v = 0; v < num_vertices; ++v) rows[fill[v]++] = v;
  for (const auto& [a, b] : pairs) {
    rows[fill[b]++] = a;
    rows[fill[a]++] = b;
  }
  // The columns are sorted in parallel (each is its own), then moved together in order.
  std::vector<int> unique(num_vertices);
#pragma omp parallel for schedule(dynamic, 4096) if (num_vertices >= kParallelColumns)
  for (int v = 0; v < num_vertices; ++v) {
    const auto first = rows.begin() + start[v], last = rows.begin() + start[v + 1];
    std::sort(first, last);
    unique[v] = static_cast<int>(std::unique(first, last) - first);
  }
  begin_.assign(num_vertices + 1, 0);
  long long kept = 0;
  for (int v = 0; v < num_vertices; ++v) {
    std::copy(rows.begin() + start[v], rows.begin() + start[v] + unique[v], rows.begin() + kept);
    kept += unique[v];
    if (9 * kept > std::numeric_limits<int>::max())
      throw InputError(message("mesh too large: the Hessian's vertex blocks up to vertex ", v,
                               " already have more than 2^31 nonzeros"));
    begin_[v + 1] = static_cast<int>(kept);
  }
  rows.resize(kept);
  rows_ = std::move(rows);
}

int BlockSparsity::offset(int a, int b) const {
  const auto first = rows_.begin() + begin_[b], last = rows_.begin() + begin_[b + 1];
  const auto it = std::lower_bound(first, last, a);
  if (it == last || *it != a)
    throw std::logic_error(message("BlockSparsity: no block (", a, ", ", b, ")"));
  return 9 * begin_[b] + 3 * static_cast<int>(it - first);
}

SparseMatrix BlockSparsity::zero_matrix() const {
  SparseMatrix matrix;
  allocate_matrix(matrix);
  zero_columns(matrix, 0, num_vertices());
  return matrix;
}

void BlockSparsity::allocate_matrix(SparseMatrix& matrix) const {
  const int n = num_vertices();
  matrix.resize(3 * n, 3 * n);  // keeps the value and index storage, resizeNonZeros reuses it
  matrix.resizeNonZeros(num_nonzeros());
  int* outer = matrix.outerIndexPtr();
  for (int b = 0; b < n; ++b)
    for (int j = 0; j < 3; ++j) outer[3 * b + j] = 9 * begin_[b] + j * column_stride(b);
  outer[3 * n] = num_nonzeros();
}

void BlockSparsity::zero_columns(SparseMatrix& matrix, int first_vertex, int last_vertex) const {
  int* inner = matrix.innerIndexPtr();
  double* values = matrix.valuePtr();
  int at = 9 * begin_[first_vertex];
  for (int b = first_vertex; b < last_vertex; ++b)
    for (int j = 0; j < 3; ++j)
      for (int k = begin_[b]; k < begin_[b + 1]; ++k)
        for (int i = 0; i < 3; ++i) {
          inner[at] = 3 * rows_[k] + i;
          values[at++] = 0.0;
        }
}

}  // namespace modal_deform
