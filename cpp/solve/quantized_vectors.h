// The basis vectors U (rows by r, float32) stored a second time in 16 bits, for the map
// x = x̄ + U q that the pose writes to the fine mesh every update (paper section 5, "map q to the
// fine mesh"). That map reads all of U for a few multiply-adds per entry, so it runs at memory
// speed: half the bytes take half the time.
//
// Each block of kRowsPerBlock rows stores, per column j, its largest |U_kj| as a scale s_bj and the
// entries as round(32767 U_kj / s_bj) in int16, so a row of block b maps with an error of at most
// e_b(q) = Σ_j s_bj |q_j| / 65534, known per block for each q before mapping it. A block is stored
// column by column (no sum across a vector per row). A block whose bound exceeds the caller's
// tolerance is mapped from the float32 rows instead: every coordinate is then within the
// tolerance of the float32 map. How often that happens, and why per block: docs/design.md,
// "The 16-bit map".
#pragma once

#include <cstdint>
#include <vector>

#include "util/types.h"

namespace modal_deform {

class QuantizedVectors {
 public:
  // Rows per block: the float32 map's blocks (64 vertices), so a block's fallback streams once.
  static constexpr Eigen::Index kRowsPerBlock = 192;

  // U: rows by r, row-major. In parallel over the blocks.
  explicit QuantizedVectors(const RowMatrixXf& U);

  // out[k] = rest[k] + (U q)[k] (rest null: U q alone) for every row k, each within `tolerance` (≥
  // 0, U's units) of the float32 map, U being the matrix this was made from; q has r entries.
  // Returns the number of blocks mapped from float32. In parallel over blocks when there are many
  // rows.
  Eigen::Index map(const RowMatrixXf& U, const Eigen::VectorXf& q, const float* rest,
                   double tolerance, float* out) const;

  Eigen::Index rows() const { return rows_; }
  Eigen::Index blocks() const { return scales_.rows(); }

 private:
  Eigen::Index rows_ = 0, cols_ = 0;
  std::vector<std::int16_t> values_;  // block by block, each column by column (rows × r in all)
  RowMatrixXf scales_;                // blocks by r: s_bj
};

}  // namespace modal_deform
