// The shells energy's material: the weights of E = α E_F + β (E_L + E_A) (discrete_shells.h) and
// their painting per vertex (stiffness_paint.h). One definition for the bake, the solvers, the
// stored basis and the bindings (for_each_material_field).
#pragma once

#include "energy/stiffness_paint.h"
#include "util/require_weight.h"

namespace modal_deform {

// max_stiffness where nothing else says: a weight of 1 is 100 times as stiff as weight 0.
constexpr double kDefaultMaxStiffness = 100.0;

struct Material {
  double bending = 1.0;   // α, finite and ≥ 0 (the paper's 1)
  double membrane = 1.0;  // β, finite and ≥ 0 (the paper's 1)
  // #V weights in [0, 1] (empty: uniform) and the multiplier where a weight is 1.
  StiffnessPaint paint = {Eigen::VectorXd(), kDefaultMaxStiffness};
};

// The fields of a Material by the names the Python API gives them: visit(name, field) with
// `field` an accessor m -> m.member, const when m is.
template <typename Visit>
void for_each_material_field(Visit&& visit) {
  visit("bending", [](auto& m) -> auto& { return m.bending; });
  visit("membrane", [](auto& m) -> auto& { return m.membrane; });
  visit("stiffness_weights", [](auto& m) -> auto& { return m.paint.weights; });
  visit("max_stiffness", [](auto& m) -> auto& { return m.paint.max_stiffness; });
}

// The material fields of options that hold a Material `material`, as fields of the options:
// visit(name, field) with `field` an accessor o -> o.material.member.
template <typename Visit>
void for_each_material_option(Visit&& visit) {
  for_each_material_field([&](const char* name, auto field) {
    visit(name, [field](auto& o) -> auto& { return field(o.material); });
  });
}

// Throws InputError naming the first field that is out of range (require_weight,
// require_stiffness_paint with num_vertices).
inline void require_material(const Material& material, Eigen::Index num_vertices) {
  require_weight(material.bending, "bending");
  require_weight(material.membrane, "membrane");
  require_stiffness_paint(material.paint, num_vertices);
}

}  // namespace modal_deform
