// The check every entry point that takes positions (or displacements) makes.
#pragma once

#include <cmath>

#include "util/errors.h"
#include "util/types.h"

namespace modal_deform {

// The largest coordinate magnitude the core accepts, in any length unit. The shells energy
// multiplies up to ten lengths (a hinge's ‖e‖²‖n1‖²‖n2‖²), which stays far from overflow below
// this, and no real model needs more: Blender stores coordinates in single precision.
constexpr double kMaxCoordinate = 1e15;

// True when every entry of y is finite and at most kMaxCoordinate in magnitude.
inline bool positions_in_range(const Eigen::Ref<const Eigen::VectorXd>& y) {
  return (y.array().abs() <= kMaxCoordinate).all();  // false for NaN too
}

// Throws InputError unless y has `size` entries (3 per vertex), all finite and at most
// kMaxCoordinate in magnitude; the message names the argument and the first offending vertex
// ("X[7]: vertex 7 has a non-finite coordinate ...").
inline void require_positions(const VectorRef& y, Eigen::Index size, const char* name) {
  if (y.size() != size)
    throw InputError(message(name, ": expected ", size, " values, got ", y.size()));
  if (positions_in_range(y)) return;
  Eigen::Index v = 0;
  while (positions_in_range(y.segment<3>(3 * v))) ++v;
  const Eigen::Vector3d p = y.segment<3>(3 * v);
  if (!p.allFinite())
    throw InputError(message(name, "[", v, "]: vertex ", v, " has a non-finite coordinate (", p[0],
                             ", ", p[1], ", ", p[2], ")"));
  throw InputError(message(name, "[", v, "]: vertex ", v, " has a coordinate too large (", p[0],
                           ", ", p[1], ", ", p[2], "); the core takes magnitudes up to ",
                           kMaxCoordinate, ": scale the mesh down"));
}

}  // namespace modal_deform
