// Vibration modes, rigid motions and the modal-derivative solves, generic in (K, mass).
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <utility>

#include "bindings/bindings.h"
#include "modes/modal_derivatives.h"
#include "modes/rigid_motions.h"
#include "modes/vibration_modes.h"

namespace py = pybind11;

namespace modal_deform {

void bind_modes(py::module_& m) {
  using MatrixRef = Eigen::Ref<const Eigen::MatrixXd>;
  m.def(
      "vibration_modes",
      [](const SparseMatrix& K, const VectorRef& mass, int count, const MatrixRef& Z) {
        VibrationModes modes = vibration_modes(K, mass, count, Z);
        return std::make_pair(std::move(modes.eigenvalues), std::move(modes.modes));
      },
      py::arg("K"), py::arg("mass"), py::arg("count"), py::arg("Z"),
      py::call_guard<py::gil_scoped_release>());
  m.def(
      "rigid_motions",
      [](const VerticesRef& V, const Eigen::Ref<const Eigen::VectorXi>& labels,
         const VectorRef& mass) { return rigid_motions(V, labels, mass); },
      py::arg("V"), py::arg("labels"), py::arg("mass"), py::call_guard<py::gil_scoped_release>());
  m.def(
      "solve_in_range",
      [](const SparseMatrix& K, const VectorRef& mass, const MatrixRef& Z, const MatrixRef& B) {
        return solve_in_range(K, mass, Z, B);
      },
      py::arg("K"), py::arg("mass"), py::arg("Z"), py::arg("B"),
      py::call_guard<py::gil_scoped_release>());
}

}  // namespace modal_deform
