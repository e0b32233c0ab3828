// The compiled extension modal_deform._native. The Python package modal_deform.core wraps it.
#include "bindings/bindings.h"

PYBIND11_MODULE(_native, m) {
  m.doc() = "Modal Deform native core (use modal_deform.core)";
  modal_deform::bind_errors(m);
  modal_deform::bind_mesh(m);
  modal_deform::bind_energy(m);
  modal_deform::bind_reduction(m);
  modal_deform::bind_modes(m);
  modal_deform::bind_solve(m);
  modal_deform::bind_bake(m);
  modal_deform::bind_dynamics(m);
  modal_deform::bind_inbetween(m);
  modal_deform::bind_shapes(m);
}
