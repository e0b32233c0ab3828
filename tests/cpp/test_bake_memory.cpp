#include <gtest/gtest.h>

#include <string>

#include "bake/bake_memory.h"
#include "linalg/cholmod_llt.h"
#include "stand_in_stiffness.h"
#include "test_support.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

using testing::shared_mesh;
using testing::spring_network_hessian;

TEST(BakeMemory, TheFactorSizeIsKnownFromTheAnalysisAlone) {
  const TriangleMesh& bunny = shared_mesh("bunny.obj.gz");
  SparseMatrix K = spring_network_hessian(bunny.V, bunny.F);
  for (int d = 0; d < K.rows(); ++d) K.coeffRef(d, d) += 1.0;
  CholmodLLT llt(3);
  EXPECT_EQ(llt.factor_bytes(), 0.0);
  llt.analyze(K);
  const double analysed = llt.factor_bytes();
  EXPECT_GE(analysed,
            8 * static_cast<double>(K.nonZeros()) / 2);  // at least the lower triangle's values
  llt.factorize(K);
  EXPECT_EQ(llt.factor_bytes(), analysed);
  EXPECT_GE(analysed, 8 * llt.factor_nonzeros());
}

TEST(BakeMemory, TheEstimateGrowsWithWhatIsAskedFor) {
  const BakeMemory small = estimate_bake_memory(100000, 100000, 1.2e7, 5.6e8, 20, 47);
  const BakeMemory wider = estimate_bake_memory(100000, 100000, 1.2e7, 5.6e8, 20, 110);
  const BakeMemory finer = estimate_bake_memory(400000, 400000, 4.8e7, 3e9, 20, 47);
  EXPECT_EQ(small.factor, 5.6e8);
  EXPECT_GT(wider.vectors, small.vectors);
  EXPECT_GT(finer.total(), 3 * small.total());
  // dragon_vrip_res2 at 20 + 47 peaked at 2.07 GB resident, 0.1 GB of it the process before the
  // bake.
  EXPECT_GT(small.total(), 1.5e9);
  EXPECT_LT(small.total(), 2.5e9);
}

TEST(BakeMemory, MoreThanIsAvailableIsRefusedWithTheFigures) {
  const BakeMemory need = estimate_bake_memory(100000, 100000, 1.2e7, 5.6e8, 20, 47);
  EXPECT_NO_THROW(require_memory(need, 2 * need.total()));
  try {
    require_memory(need, 0.5e9);
    ADD_FAILURE() << "no exception";
  } catch (const OutOfMemory& e) {
    const std::string text = e.what();
    EXPECT_NE(text.find("bake: not enough memory: the bake needs about"), std::string::npos)
        << text;
    EXPECT_NE(text.find("factor of K 0.56 GB from CHOLMOD's analysis"), std::string::npos) << text;
    EXPECT_NE(text.find("only 0.50 GB is available"), std::string::npos) << text;
  }
  EXPECT_GT(available_memory(), 0.0);
}

}  // namespace
}  // namespace modal_deform
