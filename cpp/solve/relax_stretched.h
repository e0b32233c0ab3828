// Refine's start mended where it is stretched, before the full solve's Newton iterations.
//
// A reduced pose moves a scan's fins and needles (a vertex hanging from the mesh by a doubled or
// sliver triangle) with the basis, and the ghost the reduced solver minimises on does not see
// them: such a vertex sits far off, its edges stretched hundreds of times, and holds most of F at
// the start. A full Newton step swings it through its base edges, so the turn-over guard cuts the
// step of the whole mesh for many iterations. Relaxing those vertices alone first, on the few
// faces around them, costs milliseconds (bench/results/refine.json, "relaxed").
#pragma once

#include "solve/pose_objective.h"
#include "solve/shifted_newton.h"

namespace modal_deform {

// Edges longer than this many times their rest length mark their vertices as stretched: the fins
// of a scan's reduced pose, not the triangles a strong pose crushes (those are what the pose
// needs, and relaxing them costs Newton iterations).
inline constexpr double kStretchedBeyond = 3.0;

// Minimises F over the coordinates of the vertices (not held) of the edges `point` stretches
// beyond kStretchedBeyond times their rest length, every other vertex held where `point` has it,
// on the faces around them (PoseObjective::around); `point` is updated, F and ∇F at the result.
// Returns the vertices relaxed (0: nothing was stretched, `point` unchanged).
int relax_stretched(const PoseObjective& objective, NewtonPoint& point);

}  // namespace modal_deform
