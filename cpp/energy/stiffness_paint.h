// Stiffness painted per vertex, as Blender's Cloth takes it from a vertex group: a
// weight w_v in [0, 1] per vertex and a maximum; each element of the energy (an edge, a triangle,
// a hinge) has its material weights α, β multiplied by
//
//   1 + (max_stiffness − 1) w̄_e,   w̄_e the mean weight of the element's vertices
//
// (Cloth's linear convention: weight 0 is the material itself, weight 1 is max_stiffness times
// it). The factor is linear in the weights, so a coarse vertex standing for several fine ones (a
// ghost or proxy vertex) carries the mass-weighted mean of their weights (restrict_to_ghost) and
// its elements are as stiff as the fine ones on average.
#pragma once

#include <array>

#include "util/errors.h"
#include "util/types.h"

namespace modal_deform {

// The largest max_stiffness: stiff parts 1e4 times the rest bend 1e4 times less, which is rigid
// to the eye; beyond it the stiffness matrix's condition grows for nothing.
constexpr double kMaxStiffness = 1e4;

// max_stiffness where nothing else says: a weight of 1 is 100 times as stiff as weight 0.
constexpr double kDefaultMaxStiffness = 100.0;

struct StiffnessPaint {
  Eigen::VectorXd weights;  // #V in [0, 1], or empty: the material is uniform
  double max_stiffness = kDefaultMaxStiffness;

  bool uniform() const { return weights.size() == 0 || max_stiffness == 1.0; }

  // The multiplier of an element with these vertices.
  template <size_t K>
  double factor(const std::array<int, K>& vertices) const {
    if (uniform()) return 1.0;
    double sum = 0;
    for (int v : vertices) sum += weights[v];
    return 1.0 + (max_stiffness - 1.0) * sum / static_cast<double>(K);
  }
};

// Throws InputError naming what is wrong: max_stiffness outside [1, kMaxStiffness] (NaN too),
// weights neither empty nor one per vertex (num_vertices), or a weight that is not a number in
// [0, 1] (naming the first such vertex). `name` names the weights in the messages.
void require_stiffness_paint(const StiffnessPaint& paint, Eigen::Index num_vertices,
                             const char* name = "stiffness_weights");

}  // namespace modal_deform
