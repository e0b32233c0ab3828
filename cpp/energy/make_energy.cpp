#include "energy/make_energy.h"

#include "energy/arap.h"
#include "energy/discrete_shells.h"
#include "util/errors.h"

namespace modal_deform {

EnergyKind energy_kind(const std::string& name) {
  if (name == "shells") return EnergyKind::kShells;
  if (name == "arap") return EnergyKind::kArap;
  throw InputError(message("energy: expected \"shells\" or \"arap\", got \"", name, "\""));
}

const char* energy_name(EnergyKind kind) { return kind == EnergyKind::kArap ? "arap" : "shells"; }

void require_paintable(EnergyKind kind, const StiffnessPaint& paint) {
  if (kind == EnergyKind::kArap && !paint.uniform())
    throw InputError(
        "stiffness_weights: the ARAP energy has no painted stiffness (its energy is per vertex "
        "neighbourhood, not per element); use the shells energy, or no stiffness weights");
}

std::unique_ptr<Energy> make_energy(EnergyKind kind, const VerticesRef& V, const FacesRef& F,
                                    const Material& material) {
  require_paintable(kind, material.paint);
  if (kind == EnergyKind::kArap) return std::make_unique<Arap>(V, F);
  return std::make_unique<DiscreteShells>(V, F, material.bending, material.membrane,
                                          material.paint);
}

}  // namespace modal_deform
