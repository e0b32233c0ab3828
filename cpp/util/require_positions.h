// The check every entry point that takes flat positions (or displacements) makes.
#pragma once

#include "util/errors.h"
#include "util/types.h"

namespace modal_deform {

// Throws InputError unless y has `size` entries (3 per vertex) and all are finite; the message
// names the argument and the first vertex with a non-finite coordinate ("X[7]: vertex 7 ...").
inline void require_positions(const VectorRef& y, Eigen::Index size, const char* name) {
  if (y.size() != size) throw InputError(message(name, ": expected ", size, " values, got ", y.size()));
  if (y.allFinite()) return;
  Eigen::Index v = 0;
  while (y.segment<3>(3 * v).allFinite()) ++v;
  throw InputError(message(name, "[", v, "]: vertex ", v, " has a non-finite coordinate (", y[3 * v], ", ",
                           y[3 * v + 1], ", ", y[3 * v + 2], ")"));
}

}  // namespace modal_deform
