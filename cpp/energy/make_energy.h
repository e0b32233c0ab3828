// The energies the solvers can minimise, chosen by name ("shells", "arap").
#pragma once

#include <memory>
#include <string>

#include "energy/energy.h"

namespace modal_deform {

enum class EnergyKind { kShells, kArap };

// "shells" or "arap"; throws InputError naming `name` otherwise.
EnergyKind energy_kind(const std::string& name);

// The energy of the rest mesh (V #V by 3, F #F by 3): DiscreteShells(V, F, bending, membrane)
// or Arap(V, F), which has no material weights and ignores them.
std::unique_ptr<Energy> make_energy(EnergyKind kind, const VerticesRef& V, const FacesRef& F, double bending = 1.0,
                                    double membrane = 1.0);

}  // namespace modal_deform
