// The energies: one Python class per energy, sharing the methods of the Energy interface.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings/bindings.h"
#include "energy/arap.h"
#include "energy/discrete_shells.h"
#include "energy/energy.h"
#include "util/errors.h"

namespace py = pybind11;

namespace modal_deform {

void bind_energy(py::module_& m) {
  // Shapes and dtypes are checked by modal_deform.core.energy; lengths here.
  auto check_length = [](const Energy& energy, const VectorRef& x, const char* name) {
    if (x.size() != 3 * energy.num_vertices())
      throw InputError(message(name, ": expected ", 3 * energy.num_vertices(), " values, got ", x.size()));
  };
  py::class_<Energy>(m, "Energy")
      .def_property_readonly("num_vertices", &Energy::num_vertices)
      .def(
          "value",
          [check_length](const Energy& energy, const VectorRef& x) {
            check_length(energy, x, "X");
            return energy.value(x);
          },
          py::arg("x"), py::call_guard<py::gil_scoped_release>())
      .def(
          "gradient",
          [check_length](const Energy& energy, const VectorRef& x) {
            check_length(energy, x, "X");
            Eigen::VectorXd gradient(x.size());
            energy.value_and_gradient(x, gradient);
            return gradient;
          },
          py::arg("x"), py::call_guard<py::gil_scoped_release>())
      .def(
          "hessian",
          [check_length](const Energy& energy, const VectorRef& x) {
            check_length(energy, x, "X");
            return energy.hessian(x);
          },
          py::arg("x"), py::call_guard<py::gil_scoped_release>())
      .def(
          "third",
          [check_length](const Energy& energy, const VectorRef& x, const VectorRef& u, const VectorRef& w) {
            check_length(energy, x, "X");
            check_length(energy, u, "U");
            check_length(energy, w, "W");
            return energy.third(x, u, w);
          },
          py::arg("x"), py::arg("u"), py::arg("w"), py::call_guard<py::gil_scoped_release>());

  // Each energy adds its class here, deriving from Energy.

  py::class_<Arap, Energy>(m, "Arap")
      .def(py::init<const VerticesRef&, const FacesRef&>(), py::arg("V"), py::arg("F"));
  py::class_<DiscreteShells, Energy>(m, "DiscreteShells")
      .def(py::init<const VerticesRef&, const FacesRef&, double, double>(), py::arg("V"), py::arg("F"),
           py::arg("bending") = 1.0, py::arg("membrane") = 1.0, py::call_guard<py::gil_scoped_release>())
      .def("third_batch", &DiscreteShells::third_batch, py::arg("x"), py::arg("Phi"), py::arg("pairs"),
           py::call_guard<py::gil_scoped_release>())
      .def_property_readonly("term_counts", [](const DiscreteShells& energy) {
        const auto counts = energy.term_counts();
        return py::dict(py::arg("edges") = counts.edges, py::arg("triangles") = counts.triangles,
                        py::arg("hinges") = counts.hinges);
      });
}

}  // namespace modal_deform
