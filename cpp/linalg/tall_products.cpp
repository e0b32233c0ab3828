#include "linalg/tall_products.h"

#include <algorithm>
#include <vector>

#include "util/errors.h"
#include "util/parallel_for.h"

namespace modal_deform {
namespace {

// Rows per chunk: enough for BLAS-3 speed in each, few enough that two threads share 300k rows
// evenly.
constexpr Eigen::Index kChunkRows = 8192;

Eigen::Index chunks(Eigen::Index rows) { return (rows + kChunkRows - 1) / kChunkRows; }

}  // namespace

Eigen::MatrixXd weighted_inner(const Eigen::Ref<const Eigen::MatrixXd>& A, const Eigen::VectorXd& w,
                               const Eigen::Ref<const Eigen::MatrixXd>& B) {
  if (A.rows() != w.size() || B.rows() != w.size())
    throw InputError(message("weighted_inner: A, w and B have ", A.rows(), ", ", w.size(), " and ", B.rows(), " rows"));
  const Eigen::Index count = chunks(w.size());
  std::vector<Eigen::MatrixXd> parts(static_cast<size_t>(count));
  parallel_for(count, [&](Eigen::Index c) {
    const Eigen::Index first = c * kChunkRows, rows = std::min(kChunkRows, w.size() - first);
    parts[static_cast<size_t>(c)].noalias() =
        A.middleRows(first, rows).transpose() * (w.segment(first, rows).asDiagonal() * B.middleRows(first, rows));
  });
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(A.cols(), B.cols());
  for (const Eigen::MatrixXd& part : parts) sum += part;
  return sum;
}

void subtract_product(const Eigen::Ref<const Eigen::MatrixXd>& A, const Eigen::Ref<const Eigen::MatrixXd>& C,
                      Eigen::Ref<Eigen::MatrixXd> X) {
  if (A.rows() != X.rows() || A.cols() != C.rows() || C.cols() != X.cols())
    throw InputError(message("subtract_product: A is ", A.rows(), " by ", A.cols(), ", C ", C.rows(), " by ", C.cols(),
                             ", X ", X.rows(), " by ", X.cols()));
  const Eigen::Index count = chunks(X.rows());
  parallel_for(count, [&](Eigen::Index c) {
    const Eigen::Index first = c * kChunkRows, rows = std::min(kChunkRows, X.rows() - first);
    X.middleRows(first, rows).noalias() -= A.middleRows(first, rows) * C;
  });
}

}  // namespace modal_deform
