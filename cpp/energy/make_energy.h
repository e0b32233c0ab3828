// The energies the solvers can minimise, chosen by name ("shells", "arap").
#pragma once

#include <memory>
#include <string>

#include "energy/energy.h"
#include "energy/material.h"

namespace modal_deform {

enum class EnergyKind { kShells, kArap };

// "shells" or "arap"; throws InputError naming `name` otherwise.
EnergyKind energy_kind(const std::string& name);
// The name energy_kind takes for `kind`.
const char* energy_name(EnergyKind kind);

// The energy of the rest mesh (V #V by 3, F #F by 3): DiscreteShells with the material, or
// Arap(V, F), which has no material weights and ignores bending and membrane.
std::unique_ptr<Energy> make_energy(EnergyKind kind, const VerticesRef& V, const FacesRef& F,
                                    const Material& material = {});

// Throws InputError for painted stiffness with ARAP: its energy is a sum over vertex cells, not
// over the elements the paint weighs.
void require_paintable(EnergyKind kind, const StiffnessPaint& paint);

}  // namespace modal_deform
