// The ghost mesh and the restriction of fine vectors to it.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>

#include "bindings/bindings.h"
#include "bindings/python_progress.h"
#include "mesh/mass.h"
#include "mesh/mesh_check.h"
#include "reduction/ghost.h"

namespace py = pybind11;

namespace modal_deform {
void bind_reduction(py::module_& m) {
  m.def(
      "ghost_mesh",
      [](const VerticesRef& V, const FacesRef& F, int vertices, const py::object& progress) {
        validate_mesh(V, F);
        Progress reporter(python_progress(progress));
        Ghost ghost;
        {
          py::gil_scoped_release release;
          ghost = ghost_mesh(V, F, lumped_mass(V, F), vertices, &reporter);
        }
        return py::make_tuple(std::move(ghost.V), std::move(ghost.F), std::move(ghost.map));
      },
      py::arg("V"), py::arg("F"), py::arg("vertices"), py::arg("progress") = py::none());
  m.def(
      "restrict_to_ghost",
      [](const Eigen::Ref<const Eigen::VectorXi>& map, int num_ghost, const VectorRef& mass,
         const Eigen::Ref<const Eigen::MatrixXd>& U) {
        return restrict_to_ghost(map, num_ghost, mass, U);
      },
      py::arg("ghost_map"), py::arg("num_ghost"), py::arg("mass"), py::arg("U"),
      py::call_guard<py::gil_scoped_release>());
}

}  // namespace modal_deform
