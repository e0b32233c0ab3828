// Refine's start mended where it is stretched, before the full solve's Newton iterations.
//
// A reduced pose moves a scan's fins and needles (a vertex hanging from the mesh by a doubled or
// sliver triangle) with the basis, and the ghost the reduced solver minimises on does not see
// them: on the 100k dragon turned by 30° three such vertices sit 0.15–0.23 units (2% of its
// length) off, their edges stretched 260–530 times, and they hold 98% of F at the start. A full
// Newton step swings them through their base edges, so the turn-over guard cuts the step of the
// whole mesh: 12 iterations at α from 1e-4 to 0.06 before the steps grew. Relaxing those
// vertices alone first, on the few faces around them, costs milliseconds.
#pragma once

#include "solve/pose_objective.h"
#include "solve/shifted_newton.h"

namespace modal_deform {

// Edges longer than this many times their rest length mark their vertices as stretched. The
// 100k dragon turned by 30° has 38 such edges at its reduced pose (17 vertices, fins); the 23k
// dragon's reduced poses 0 to 6, by at most 9 times. The outcome is sensitive to the set: on the
// 100k turn, 17 vertices relaxed took Newton 21 iterations / 15 factorisations, the 15 beyond
// 10 times 46 / 30, and 23 (also triangles crushed below a third) 16 / 11, which cost the 23k turn
// by 170° 234 iterations instead of 56 (its crushed triangles are what the pose needs).
inline constexpr double kStretchedBeyond = 3.0;

// Minimises F over the coordinates of the vertices (not held) of the edges `point` stretches
// beyond kStretchedBeyond times their rest length, every other vertex held where `point` has it,
// on the faces around them (PoseObjective::around); `point` is updated, F and ∇F at the result.
// Returns the vertices relaxed (0: nothing was stretched, `point` unchanged).
int relax_stretched(const PoseObjective& objective, NewtonPoint& point);

}  // namespace modal_deform
