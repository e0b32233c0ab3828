#include "solve/quantized_vectors.h"

#include <algorithm>
#include <cmath>

namespace modal_deform {
namespace {

constexpr float kLargest = 32767.0f;  // the largest int16 magnitude, what s_bj maps to
// Threads only where they pay (the float32 map's threshold: 4096 vertices).
constexpr Eigen::Index kParallelRows = 3 * 4096;

// One float32 row's dot product with q.
float row_dot(const float* u, const float* q, Eigen::Index r) {
  float dot = 0;
#pragma omp simd reduction(+ : dot)
  for (Eigen::Index j = 0; j < r; ++j) dot += u[j] * q[j];
  return dot;
}

// sum[k] = Σ_j values[j count + k] scaled_q[j] for the `count` rows of a block stored column by
// column: one multiply-add per entry along the rows, no sum across a vector per row. Compiled
// twice where the compiler can dispatch on the CPU: for AVX2 and FMA (8 entries per instruction,
// any x86-64 since 2013) and for the wheel's baseline (SSE4.2, 4). Dispatch needs ELF's ifunc: the
// Windows build has the baseline only.
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__) && defined(__ELF__)
__attribute__((target_clones("arch=x86-64-v3", "default")))
#endif
void accumulate_columns(const std::int16_t* values, const float* scaled_q, Eigen::Index count,
                        Eigen::Index r, float* sum) {
  for (Eigen::Index k = 0; k < count; ++k) sum[k] = 0;
  for (Eigen::Index j = 0; j < r; ++j) {
    const std::int16_t* column = values + j * count;
    const float qj = scaled_q[j];
#pragma omp simd
    for (Eigen::Index k = 0; k < count; ++k) sum[k] += static_cast<float>(column[k]) * qj;
  }
}

}  // namespace

QuantizedVectors::QuantizedVectors(const RowMatrixXf& U)
    : rows_(U.rows()),
      cols_(U.cols()),
      values_(static_cast<std::size_t>(U.size())),
      scales_((U.rows() + kRowsPerBlock - 1) / kRowsPerBlock, U.cols()) {
  const Eigen::Index blocks = scales_.rows();
#pragma omp parallel for schedule(static) if (rows_ >= kParallelRows)
  for (Eigen::Index block = 0; block < blocks; ++block) {
    const Eigen::Index begin = block * kRowsPerBlock, end = std::min(rows_, begin + kRowsPerBlock);
    const Eigen::Index count = end - begin;
    auto scale = scales_.row(block);
    scale = U.middleRows(begin, count).cwiseAbs().colwise().maxCoeff();
    std::int16_t* stored = values_.data() + begin * cols_;
    for (Eigen::Index j = 0; j < cols_; ++j)
      for (Eigen::Index k = begin; k < end; ++k) {
        const float unit = scale(j) > 0 ? U(k, j) / scale(j) : 0.0f;
        stored[j * count + (k - begin)] = static_cast<std::int16_t>(std::lround(kLargest * unit));
      }
  }
}

Eigen::Index QuantizedVectors::map(const RowMatrixXf& U, const Eigen::VectorXf& q,
                                   const float* rest, double tolerance, float* out) const {
  const Eigen::Index blocks = scales_.rows();
  const Eigen::VectorXd q_abs = q.cwiseAbs().cast<double>();
  Eigen::Index from_float32 = 0;
#pragma omp parallel reduction(+ : from_float32) if (rows_ >= kParallelRows)
  {
    Eigen::VectorXf scaled_q(cols_);
    float sum[kRowsPerBlock];
#pragma omp for schedule(static)
    for (Eigen::Index block = 0; block < blocks; ++block) {
      const Eigen::Index begin = block * kRowsPerBlock,
                         end = std::min(rows_, begin + kRowsPerBlock);
      const auto scale = scales_.row(block);
      if (scale.cast<double>().dot(q_abs) / (2.0 * kLargest) > tolerance) {  // the bound e_b(q)
        for (Eigen::Index k = begin; k < end; ++k)
          sum[k - begin] = row_dot(U.data() + k * cols_, q.data(), cols_);
        ++from_float32;
      } else {
        scaled_q = scale.transpose().cwiseProduct(q) / kLargest;
        accumulate_columns(values_.data() + begin * cols_, scaled_q.data(), end - begin, cols_,
                           sum);
      }
      for (Eigen::Index k = begin; k < end; ++k)
        out[k] = rest ? rest[k] + sum[k - begin] : sum[k - begin];
    }
  }
  return from_float32;
}

}  // namespace modal_deform
