// The checks every entry point that takes an energy weight (bending, membrane) or a handle weight
// makes.
#pragma once

#include <cmath>

#include "util/errors.h"

namespace modal_deform {

// The largest weight or stiffness the core accepts. Weights scale terms whose geometric factors
// reach far beyond 1 (a hinge's 3‖ē‖²/Ā_e on a sliver, μs⁴ for a tiny mesh); near the top of the
// double range their product overflows, and inf · 0 at rest is NaN. Only ratios of weights
// matter, and the paper uses 1.
constexpr double kMaxWeight = 1e12;

// Throws InputError unless weight is in [0, kMaxWeight] (NaN fails); the message names it.
inline void require_weight(double weight, const char* name) {
  if (!(weight >= 0 && weight <= kMaxWeight))
    throw InputError(message(name, ": expected a finite weight >= 0 and at most ", kMaxWeight,
                             ", got ", weight));
}

}  // namespace modal_deform
