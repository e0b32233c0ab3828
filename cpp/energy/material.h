// The shells energy's material: the weights of E = α E_F + β (E_L + E_A) (discrete_shells.h) and
// their painting per vertex (stiffness_paint.h). One definition for the bake, the solvers, the
// stored basis and the bindings (for_each_material_field).
#pragma once

#include "energy/stiffness_paint.h"
#include "util/option.h"
#include "util/require_weight.h"

namespace modal_deform {

struct Material {
  double bending = 1.0;   // α, finite and ≥ 0 (the paper's 1)
  double membrane = 1.0;  // β, finite and ≥ 0 (the paper's 1)
  // #V weights in [0, 1] (empty: uniform) and the multiplier where a weight is 1.
  StiffnessPaint paint = {};
};

// The fields of a Material as options (option.h): visit(option, field) with `field` an accessor
// m -> m.member, const when m is.
template <typename Visit>
void for_each_material_field(Visit&& visit) {
  visit(
      Option{"bending", "How much the surface resists bending (the weight α of the shells energy).",
             closed(0, kMaxWeight)},
      [](auto& m) -> auto& { return m.bending; });
  visit(Option{"membrane",
               "How much the surface resists stretching and squashing (the weight β of the shells "
               "energy).",
               closed(0, kMaxWeight)},
        [](auto& m) -> auto& { return m.membrane; });
  visit(Option{"stiffness_weights",
               "Stiffness painted per vertex, as Cloth takes it from a vertex group: (n,) weights "
               "in [0, 1], "
               "or None for a uniform material. Each element's bending and membrane weights are "
               "multiplied by "
               "1 + (max_stiffness - 1) times the mean weight of its vertices."},
        [](auto& m) -> auto& { return m.paint.weights; });
  visit(
      Option{"max_stiffness", "How many times stiffer than the material a painted weight of 1 is.",
             closed(1, kMaxStiffness)},
      [](auto& m) -> auto& { return m.paint.max_stiffness; });
}

// The material fields of options that hold a Material `material`, as fields of the options:
// visit(option, field) with `field` an accessor o -> o.material.member.
template <typename Visit>
void for_each_material_option(Visit&& visit) {
  for_each_material_field([&](const Option& option, auto field) {
    visit(option, [field](auto& o) -> auto& { return field(o.material); });
  });
}

// Throws InputError naming the first field that is out of range (the table's ranges, then
// require_stiffness_paint with num_vertices).
inline void require_material(const Material& material, Eigen::Index num_vertices) {
  check_options(material, [](auto visit) { for_each_material_field(visit); });
  require_stiffness_paint(material.paint, num_vertices);
}

}  // namespace modal_deform
