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
// 100k dragon's fins stretch 26 edges beyond it; reduced poses of the 23k dragon stretch none
// (at most 9 times, under turns up to 170° and a 90° bend). Relaxing there more loosely (3 times,
// or triangles crushed below a third of their area too) cost the 23k turns iterations: the turn
// by 30° took 13 instead of 8, by 170° 65 instead of 56 (and 234 with crushed ones, whose
// crushing the pose needs).
inline constexpr double kStretchedBeyond = 3.0;

// Minimises F over the coordinates of the vertices (not held) of the edges `point` stretches
// beyond kStretchedBeyond times their rest length, every other vertex held where `point` has it,
// on the faces around them (PoseObjective::around); `point` is updated, F and ∇F at the result.
// Returns the vertices relaxed (0: nothing was stretched, `point` unchanged).
int relax_stretched(const PoseObjective& objective, NewtonPoint& point);

}  // namespace modal_deform
