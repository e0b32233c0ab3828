#include <gtest/gtest.h>

#include <cmath>

#include "solve/load_steps.h"
#include "test_posing.h"
#include "util/math_constants.h"

namespace modal_deform {
namespace {

using testing::rigid_transform;

// From rest the path starts with a sixth of the suggested increment, doubles after an easy load
// step up to the suggested one, halves after a hard one, and ends exactly at the full load; a
// start of its own is one load step.
TEST(LoadSchedule, IncrementsFollowHowHardTheLastStepWas) {
  LoadSchedule schedule(true, 4);
  EXPECT_DOUBLE_EQ(schedule.next(false), 0.25 / 6);
  schedule.advance(schedule.next(false), LoadSchedule::kFewIterations, true);
  EXPECT_DOUBLE_EQ(schedule.previous_increment(), 0.25 / 6);
  EXPECT_DOUBLE_EQ(schedule.next(false) - schedule.load(), 0.25 / 3);  // easy: doubled
  schedule.advance(schedule.next(false), LoadSchedule::kManyIterations + 1, true);
  EXPECT_DOUBLE_EQ(schedule.next(false) - schedule.load(), 0.25 / 6);  // hard: halved
  schedule.advance(schedule.next(false), 1, false);
  EXPECT_DOUBLE_EQ(schedule.next(false) - schedule.load(), 0.25 / 12);  // tolerance missed: halved
  EXPECT_EQ(schedule.next(true), 1.0);  // no iterations left: the full load
  for (int step = 0; step < 200 && !schedule.done(); ++step)
    schedule.advance(schedule.next(false), 1, true);
  EXPECT_TRUE(schedule.done());
  EXPECT_EQ(schedule.load(), 1.0);

  LoadSchedule from_a_start(false, 4);
  EXPECT_EQ(from_a_start.next(false), 1.0);
  from_a_start.advance(1.0, 30, false);
  EXPECT_TRUE(from_a_start.done());
}

// The path turns each handle about its centre by the fraction of its angle and moves the centre
// along a straight line; at 1 it is the given transforms, and 120° with a short move is cut into
// steps of at most 30°.
TEST(LoadPath, TurnsAboutTheHandleCentreByTheFraction) {
  RowMatrixX3d V(4, 3);
  V << 0, 0, 0, 2, 0, 0, 0, 2, 0, 2, 2, 10;
  const Handles handles = {{0, 1, 2}};  // centre (2/3, 2/3, 0)
  const double pi = kPi;
  const Eigen::Matrix4d T =
      rigid_transform({0, 0, 1}, 2 * pi / 3, {2.0 / 3, 2.0 / 3, 0}, {0, 0, 0.1});
  const LoadPath path(V, handles, {T});
  EXPECT_EQ(path.suggested_steps(), 4);
  EXPECT_EQ(path.at(1.0)[0], T);
  const Eigen::Matrix4d half = path.at(0.5)[0];
  const Eigen::Vector3d centre(2.0 / 3, 2.0 / 3, 0);
  EXPECT_LE((half.topLeftCorner<3, 3>() * centre + half.topRightCorner<3, 1>() -
             (centre + Eigen::Vector3d(0, 0, 0.05)))
                .norm(),
            1e-12);
  EXPECT_NEAR(Eigen::AngleAxisd(Eigen::Matrix3d(half.topLeftCorner<3, 3>())).angle(), pi / 3,
              1e-12);
}

}  // namespace
}  // namespace modal_deform
