#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "solve/full_solver.h"
#include "solve/refine.h"
#include "test_posing.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

using testing::SmallTube;

// Refine's policy on the small tube, against the two solves it may run, each made on its own.
struct RefineCase {
  SmallTube tube;
  FullSolveOptions options{EnergyKind::kShells, {1.0, 1.0}, 1e-8, 100};

  FullSolveResult from(const RowMatrixX3d* initial) const {
    return solve_full(tube.mesh.V, tube.mesh.F, tube.handles, Eigen::VectorXd(), tube.transforms,
                      1e3, options, initial);
  }
  RefineResult refine(const RowMatrixX3d& initial, ProgressCallback progress = nullptr) const {
    FullSolveOptions reporting = options;
    reporting.progress = std::move(progress);
    return modal_deform::refine(tube.mesh.V, tube.mesh.F, tube.handles, Eigen::VectorXd(),
                                tube.transforms, 1e3, reporting, initial);
  }
  // The tube turned inside out through the origin: a start from which Newton needs several times
  // the iterations of the solve from rest (and finds a higher minimum).
  RowMatrixX3d inside_out() const { return -tube.mesh.V; }
};

// Every report of a refine, in order.
struct Reports {
  std::vector<std::pair<std::string, double>> seen;
  ProgressCallback callback() {
    return [this](const std::string& stage, double fraction) {
      seen.emplace_back(stage, fraction);
      return true;
    };
  }
  void expect_one_bar() const {
    ASSERT_GE(seen.size(), 2u);
    EXPECT_EQ(seen.front(), std::make_pair(std::string("solve"), 0.0));
    EXPECT_EQ(seen.back(), std::make_pair(std::string("solve"), 1.0));
    for (size_t i = 1; i < seen.size(); ++i)
      EXPECT_LE(seen[i - 1].second, seen[i].second) << "report " << i;
  }
};

TEST(Refine, AConvergedStartIsTheAnswerWithoutTheSolveFromRest) {
  const RefineCase c;
  const FullSolveResult reference = c.from(nullptr);
  ASSERT_TRUE(reference.converged);
  const RowMatrixX3d& start = reference.positions;
  const FullSolveResult alone = c.from(&start);
  ASSERT_TRUE(alone.converged);
  Reports reports;
  const RefineResult refined = c.refine(start, reports.callback());
  EXPECT_FALSE(refined.from_rest);
  EXPECT_EQ(refined.positions, alone.positions);
  EXPECT_EQ(refined.iterations, alone.iterations);
  EXPECT_EQ(refined.history.size(), alone.history.size());
  reports.expect_one_bar();
  // The solve from the start reports over the first share of the bar; the last report fills it.
  for (size_t i = 0; i + 1 < reports.seen.size(); ++i)
    EXPECT_LE(reports.seen[i].second, kFromStartShare);
}

TEST(Refine, AStartThatDoesNotConvergeFallsBackToTheSolveFromRest) {
  RefineCase c;
  c.options.max_iterations = 30;
  const RowMatrixX3d start = c.inside_out();
  const FullSolveResult first = c.from(&start);
  const FullSolveResult rest = c.from(nullptr);
  ASSERT_FALSE(first.converged) << first.iterations << " iterations";
  ASSERT_TRUE(rest.converged);
  Reports reports;
  const RefineResult refined = c.refine(start, reports.callback());
  EXPECT_TRUE(refined.from_rest);
  EXPECT_TRUE(refined.converged);
  EXPECT_EQ(refined.positions, rest.positions);
  EXPECT_EQ(refined.energy, rest.energy);
  EXPECT_EQ(refined.steps, rest.steps);
  // What both solves spent, from the start's energy.
  EXPECT_EQ(refined.iterations, first.iterations + rest.iterations);
  EXPECT_EQ(refined.factorizations, first.factorizations + rest.factorizations);
  EXPECT_EQ(refined.history.size(), first.history.size() + rest.history.size());
  EXPECT_EQ(refined.initial_energy, first.initial_energy);
  reports.expect_one_bar();
  // The solve from the start ends its share of the bar where the solve from rest starts its own.
  EXPECT_EQ(std::count_if(reports.seen.begin(), reports.seen.end(),
                          [](const auto& r) { return r.second == kFromStartShare; }),
            2);
}

TEST(Refine, KeepsTheStartsAnswerWhenTheSolveFromRestIsWorse) {
  RefineCase c;
  const RowMatrixX3d minimum = c.from(nullptr).positions;
  const RowMatrixX3d nudged = minimum + 1e-3 * RowMatrixX3d::Random(minimum.rows(), 3);
  c.options.max_iterations =
      0;  // neither solve converges; the start is near the minimum, rest is not
  const FullSolveResult first = c.from(&nudged);
  const FullSolveResult rest = c.from(nullptr);
  ASSERT_FALSE(first.converged);
  ASSERT_FALSE(rest.converged);
  ASSERT_LT(first.energy, rest.energy);
  const RefineResult refined = c.refine(nudged);
  EXPECT_FALSE(refined.from_rest);
  EXPECT_FALSE(refined.converged);
  EXPECT_EQ(refined.positions, first.positions);
  EXPECT_EQ(refined.energy, first.energy);
  EXPECT_EQ(refined.iterations, first.iterations + rest.iterations);
  EXPECT_EQ(refined.history.size(), first.history.size() + rest.history.size());
}

TEST(Refine, ACancelInEitherSolveStopsIt) {
  RefineCase c;
  c.options.max_iterations = 30;
  const RowMatrixX3d start = c.inside_out();
  for (double cancel_above : {-1.0, kFromStartShare}) {
    bool asked = false;
    EXPECT_THROW(c.refine(start,
                          [&](const std::string&, double fraction) {
                            asked = asked || fraction > cancel_above;
                            return fraction <= cancel_above;
                          }),
                 Cancelled)
        << "cancelled above " << cancel_above;
    EXPECT_TRUE(asked);
  }
}

}  // namespace
}  // namespace modal_deform
