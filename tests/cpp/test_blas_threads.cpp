#include <gtest/gtest.h>

#include <algorithm>
#include <memory>

#include "linalg/blas_threads.h"

namespace modal_deform {
namespace {

TEST(BlasThreadLimit, LimitsOpenBlasAndRestoresTheCallersThreadsWhenTheLastLimitEnds) {
  const int callers = BlasThreadLimit::current();
  if (callers == 0) GTEST_SKIP() << "the BLAS under CHOLMOD is not OpenBLAS";
  const int limited = std::min(callers, BlasThreadLimit::most_threads());
  // Two limits that overlap without nesting, as two bakes on two threads do.
  auto first = std::make_unique<BlasThreadLimit>();
  EXPECT_EQ(BlasThreadLimit::current(), limited);
  auto second = std::make_unique<BlasThreadLimit>();
  first.reset();
  EXPECT_EQ(BlasThreadLimit::current(), limited);
  second.reset();
  EXPECT_EQ(BlasThreadLimit::current(), callers);
}

}  // namespace
}  // namespace modal_deform
