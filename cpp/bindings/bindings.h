// One bind_xxx per pipeline stage; each only converts arguments and calls the core.
#pragma once

#include <pybind11/pybind11.h>

namespace modal_deform {

void bind_errors(pybind11::module_& m);
void bind_mesh(pybind11::module_& m);
void bind_energy(pybind11::module_& m);
void bind_reduction(pybind11::module_& m);
void bind_modes(pybind11::module_& m);
void bind_solve(pybind11::module_& m);
void bind_bake(pybind11::module_& m);
void bind_dynamics(pybind11::module_& m);

}  // namespace modal_deform
