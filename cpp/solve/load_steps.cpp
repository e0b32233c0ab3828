#include "solve/load_steps.h"

#include <algorithm>
#include <cmath>

#include "mesh/normalization.h"
#include "util/math_constants.h"

namespace modal_deform {
namespace {

constexpr int kMaxLoadSteps = 100;
// From rest, the first load step is this fraction of the suggested one.
constexpr double kFirstStepDivisor = 6;

}  // namespace

LoadPath::LoadPath(const VerticesRef& V, const Handles& handles, const Transforms& transforms)
    : transforms_(transforms) {
  const double diagonal = bounding_box_diagonal(V);
  for (size_t h = 0; h < handles.size(); ++h) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int v : handles[h]) c += V.row(v).transpose();
    c /= static_cast<double>(handles[h].size());
    centres_.push_back(c);
    const Eigen::AngleAxisd rotation(Eigen::Matrix3d(transforms[h].topLeftCorner<3, 3>()));
    const double move =
        (transforms[h].topLeftCorner<3, 3>() * c + transforms[h].topRightCorner<3, 1>() - c).norm();
    const double wanted = std::max(std::abs(rotation.angle()) / (kPi / 6), move / (0.1 * diagonal));
    steps_ = std::max(steps_,
                      static_cast<int>(std::ceil(std::min<double>(wanted - 1e-9, kMaxLoadSteps))));
  }
}

Transforms LoadPath::at(double t) const {
  if (t >= 1) return transforms_;
  Transforms partial(transforms_.size());
  for (size_t h = 0; h < transforms_.size(); ++h) {
    const Eigen::Matrix4d& T = transforms_[h];
    const Eigen::Vector3d& c = centres_[h];
    const Eigen::AngleAxisd rotation(Eigen::Matrix3d(T.topLeftCorner<3, 3>()));
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(t * rotation.angle(), rotation.axis()).toRotationMatrix();
    const Eigen::Vector3d moved = T.topLeftCorner<3, 3>() * c + T.topRightCorner<3, 1>();
    partial[h].setIdentity();
    partial[h].topLeftCorner<3, 3>() = R;
    partial[h].topRightCorner<3, 1>() = c + t * (moved - c) - R * c;
  }
  return partial;
}

LoadSchedule::LoadSchedule(bool stepping, int suggested_steps)
    : stepping_(stepping),
      largest_increment_(1.0 / suggested_steps),
      increment_(stepping ? largest_increment_ / kFirstStepDivisor : 1.0) {}

double LoadSchedule::next(bool spent) const {
  return spent || load_ + 1.25 * increment_ >= 1 ? 1.0 : load_ + increment_;
}

void LoadSchedule::advance(double next, int iterations, bool reached) {
  previous_increment_ = next - load_;
  load_ = next;
  if (reached && iterations <= kFewIterations)
    increment_ = std::min(2 * increment_, largest_increment_);
  else if (!reached || iterations > kManyIterations)
    increment_ = std::max(increment_ / 2, largest_increment_ / (4 * kFirstStepDivisor));
}

}  // namespace modal_deform
