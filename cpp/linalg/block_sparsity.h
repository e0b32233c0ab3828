// The sparsity pattern of a symmetric 3n by 3n matrix assembled from 3 by 3 vertex blocks, such as
// the Hessian of an energy that sums terms over mesh elements.
//
// Block (a, b) is present when a == b or when a and b share an element. The layout is the one
// SparseMatrix uses (column-major, compressed, rows sorted); the three columns of a vertex have
// the same rows, so one offset and the column stride locate all 9 entries of a block. An
// energy computes the offsets of its elements' blocks once and then scatters element Hessians
// straight into the value array, without triplets.
#pragma once

#include <array>
#include <vector>

#include "util/types.h"

namespace modal_deform {

class BlockSparsity {
 public:
  // Blocks (a, b) and (b, a) for every pair {a, b} in `pairs` (a != b, any order, repeats
  // allowed; indices in [0, num_vertices)), and every diagonal block. Throws InputError when
  // the matrix would have more nonzeros than a SparseMatrix can index (2^31 − 1).
  BlockSparsity(int num_vertices, const std::vector<std::array<int, 2>>& pairs);
  // The pattern of a 0 by 0 matrix.
  BlockSparsity() : begin_{0} {}

  int num_vertices() const { return static_cast<int>(begin_.size()) - 1; }
  int num_nonzeros() const { return 9 * static_cast<int>(rows_.size()); }

  // Index in the value array of entry (3a, 3b): entry (3a + i, 3b + j) is at
  // offset(a, b) + j * column_stride(b) + i. Throws std::logic_error when the block is absent.
  int offset(int a, int b) const;
  int column_stride(int b) const { return 3 * (begin_[b + 1] - begin_[b]); }

  // The 3n by 3n matrix with this pattern and all values zero.
  SparseMatrix zero_matrix() const;
  // The same in two steps, so that threads can fill their own columns: `matrix` given this
  // pattern's column starts but unset row indices and values (its storage kept when large enough:
  // a Newton solve reassembles a Hessian of 130 MB at 100k vertices each iteration, and fresh
  // pages cost a page fault each), then the row indices and zero values of the columns of
  // vertices [first_vertex, last_vertex).
  void allocate_matrix(SparseMatrix& matrix) const;
  void zero_columns(SparseMatrix& matrix, int first_vertex, int last_vertex) const;

 private:
  std::vector<int>
      begin_;  // #V + 1: the blocks of vertex column b are rows_[begin_[b] .. begin_[b + 1])
  std::vector<int> rows_;  // row vertex of each block, sorted within a column
};

}  // namespace modal_deform
