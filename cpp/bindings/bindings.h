// One bind_xxx per pipeline stage; each only converts arguments and calls the core.
#pragma once

#include <pybind11/pybind11.h>

#include <Eigen/Core>
#include <vector>

#include "solve/handle_term.h"

namespace modal_deform {

void bind_errors(pybind11::module_& m);
void bind_mesh(pybind11::module_& m);
void bind_energy(pybind11::module_& m);
void bind_reduction(pybind11::module_& m);
void bind_modes(pybind11::module_& m);
void bind_solve(pybind11::module_& m);
void bind_bake(pybind11::module_& m);
void bind_dynamics(pybind11::module_& m);
void bind_inbetween(pybind11::module_& m);
void bind_shapes(pybind11::module_& m);

// Handles as the core takes them, from the list of int32 arrays the Python layer checked
// (modal_deform.core.solve._handles).
Handles to_handles(const std::vector<Eigen::VectorXi>& arrays);

}  // namespace modal_deform
