#include <gtest/gtest.h>

#include <random>
#include <set>
#include <stdexcept>

#include "linalg/block_sparsity.h"

namespace modal_deform {
namespace {

// Vertices 0-1-2 in a path, vertex 3 alone: blocks (0,0) (0,1) (1,0) (1,1) (1,2) (2,1) (2,2) (3,3).
TEST(BlockSparsity, PatternHasEveryPairBothWaysAndTheDiagonal) {
  const BlockSparsity pattern(4, {{1, 0}, {1, 2}, {0, 1}});
  EXPECT_EQ(pattern.num_nonzeros(), 9 * 8);
  const SparseMatrix zero = pattern.zero_matrix();
  ASSERT_TRUE(zero.isCompressed());
  EXPECT_EQ(zero.rows(), 12);
  EXPECT_EQ(zero.nonZeros(), 72);
  EXPECT_EQ(Eigen::MatrixXd(zero).norm(), 0.0);
  // Each entry's offset, written through the value array, lands at its (row, column).
  SparseMatrix matrix = pattern.zero_matrix();
  for (auto [a, b] : {std::pair{0, 0}, {0, 1}, {1, 0}, {1, 1}, {1, 2}, {2, 1}, {2, 2}, {3, 3}})
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i)
        matrix.valuePtr()[pattern.offset(a, b) + j * pattern.column_stride(b) + i] =
            100 * (3 * a + i) + 3 * b + j;
  for (int k = 0; k < matrix.outerSize(); ++k)
    for (SparseMatrix::InnerIterator it(matrix, k); it; ++it)
      EXPECT_EQ(it.value(), 100 * it.row() + it.col());
  EXPECT_THROW(pattern.offset(0, 2), std::logic_error);
  EXPECT_THROW(pattern.offset(3, 0), std::logic_error);
}

TEST(BlockSparsity, ColumnsFilledInPiecesEqualTheWholeMatrix) {
  const BlockSparsity pattern(5, {{0, 4}, {1, 3}, {2, 3}, {0, 1}});
  SparseMatrix pieces;
  pattern.allocate_matrix(pieces);
  pattern.zero_columns(pieces, 3, 5);
  pattern.zero_columns(pieces, 0, 3);
  const SparseMatrix whole = pattern.zero_matrix();
  ASSERT_EQ(pieces.nonZeros(), whole.nonZeros());
  for (int k = 0; k <= pieces.outerSize(); ++k)
    EXPECT_EQ(pieces.outerIndexPtr()[k], whole.outerIndexPtr()[k]);
  for (int k = 0; k < pieces.nonZeros(); ++k)
    EXPECT_EQ(pieces.innerIndexPtr()[k], whole.innerIndexPtr()[k]);
}

// Enough vertices that the columns are sorted in parallel: each column holds its distinct rows in
// order, the diagonal included, as a set of the pairs says.
TEST(BlockSparsity, LargePatternMatchesASetOfItsPairs) {
  const int n = 50000;
  std::mt19937 random(3);
  std::uniform_int_distribution<int> vertex(0, n - 1);
  std::vector<std::array<int, 2>> pairs;
  std::set<std::pair<int, int>> blocks;  // (column, row), in the matrix's order
  for (int v = 0; v < n; ++v) blocks.insert({v, v});
  for (int k = 0; k < 4 * n; ++k) {
    const int a = vertex(random), b = (a + 1 + vertex(random) % 40) % n;  // near a, repeats likely
    pairs.push_back({a, b});
    blocks.insert({a, b});
    blocks.insert({b, a});
  }
  const BlockSparsity pattern(n, pairs);
  EXPECT_EQ(pattern.num_nonzeros(), 9 * static_cast<int>(blocks.size()));
  const SparseMatrix zero = pattern.zero_matrix();
  auto block = blocks.begin();
  for (int b = 0; b < n; ++b)
    for (SparseMatrix::InnerIterator it(zero, 3 * b); it; ++it)
      if (it.row() % 3 == 0) {
        ASSERT_EQ(*block, (std::pair<int, int>{b, static_cast<int>(it.row() / 3)}))
            << "column " << b;
        EXPECT_EQ(pattern.offset(block->second, b), &it.valueRef() - zero.valuePtr());
        ++block;
      }
  EXPECT_EQ(block, blocks.end());
}

}  // namespace
}  // namespace modal_deform
