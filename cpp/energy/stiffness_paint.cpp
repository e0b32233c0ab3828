#include "energy/stiffness_paint.h"

namespace modal_deform {

void require_stiffness_paint(const StiffnessPaint& paint, Eigen::Index num_vertices,
                             const char* name) {
  if (!(paint.max_stiffness >= 1.0 && paint.max_stiffness <= kMaxStiffness))
    throw InputError(message("max_stiffness: expected a number from 1 to ", kMaxStiffness, ", got ",
                             paint.max_stiffness));
  const Eigen::VectorXd& w = paint.weights;
  if (w.size() != 0 && w.size() != num_vertices)
    throw InputError(
        message(name, ": expected one weight per vertex (", num_vertices, "), got ", w.size()));
  for (Eigen::Index v = 0; v < w.size(); ++v)
    if (!(w[v] >= 0.0 && w[v] <= 1.0))
      throw InputError(message(name, "[", v, "] = ", w[v], ": expected a weight from 0 to 1"));
}

}  // namespace modal_deform
