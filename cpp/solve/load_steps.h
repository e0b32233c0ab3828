// The full solve's load steps (full_solver.h): from rest, the handles' transforms are followed
// from the identity, each handle turning about its centre (the mean of its rest vertices), its
// centre moving in a straight line, in increments that adapt to how hard the last one was.
#pragma once

#include <vector>

#include "solve/handle_term.h"
#include "util/types.h"

namespace modal_deform {

// The handles' transforms a fraction t of the way from the identity: each rotation by t times its
// angle about the handle's centre c, which moves along the straight line to T(c).
class LoadPath {
 public:
  // V: #V by 3 rest positions; transforms: one rigid transform per handle (checked).
  LoadPath(const VerticesRef& V, const Handles& handles, const Transforms& transforms);

  // Steps of at most 30° and a tenth of the bounding-box diagonal per handle (at most 100: a move
  // of 1e6 diagonals, a typo in a transform, would otherwise start with a millionth of the way).
  int suggested_steps() const { return steps_; }

  // The transforms at t in [0, 1] (the given ones at 1).
  Transforms at(double t) const;

 private:
  Transforms transforms_;
  std::vector<Eigen::Vector3d> centres_;
  int steps_ = 1;
};

// The loads a solve visits, from 0 to 1. From rest the first increment is a sixth of the
// suggested one: longer, its first Newton step (nearly the linear elastic answer) tangles fins and
// flaps, collapses triangles and stalls the solve far above the minimum (docs/measurements.md,
// "Choices in the core"). Each next increment doubles after an easy step (at most
// kFewIterations), up to the suggested one, and halves after a hard one (more than
// kManyIterations, or its tolerance not reached). From a given start there is one step, the full
// load.
class LoadSchedule {
 public:
  static constexpr int kFewIterations = 4;
  static constexpr int kManyIterations = 10;

  // stepping: from rest along the path (suggested_steps of it), else the full load at once.
  LoadSchedule(bool stepping, int suggested_steps);

  bool stepping() const { return stepping_; }
  bool done() const { return load_ >= 1; }
  double load() const { return load_; }
  // The increment that led to load() (0 before the first step).
  double previous_increment() const { return previous_increment_; }

  // The next load: the full one when `spent` (no iterations left) or when only a sliver of the
  // path would remain after it (taken with the step before).
  double next(bool spent) const;

  // Moves to `next`, the last load solved in `iterations` Newton iterations, to its tolerance or
  // not (`reached`).
  void advance(double next, int iterations, bool reached);

 private:
  bool stepping_;
  double largest_increment_, increment_;
  double load_ = 0, previous_increment_ = 0;
};

}  // namespace modal_deform
