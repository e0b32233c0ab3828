#include <gtest/gtest.h>

#include <algorithm>

#include "linalg/blas_threads.h"

namespace modal_deform {
namespace {

TEST(BlasThreads, TheGuardLeavesACoreAndRestoresTheCount) {
  const int before = blas_threads();
  ASSERT_GT(before, 0) << "the BLAS under CHOLMOD is OpenBLAS here, which says how many threads it runs";
  {
    const BlasLeavesACore guard;
    EXPECT_EQ(blas_threads(), std::max(1, before - 1));
  }
  EXPECT_EQ(blas_threads(), before);
}

}  // namespace
}  // namespace modal_deform
