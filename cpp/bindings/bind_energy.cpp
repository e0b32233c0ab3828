// The energies: one Python class per energy, sharing the methods of the Energy interface.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings/bindings.h"
#include "energy/arap.h"
#include "energy/discrete_shells.h"
#include "energy/energy.h"

namespace py = pybind11;

namespace modal_deform {

void bind_energy(py::module_& m) {
  // Shapes and dtypes are checked by modal_deform.core.energy, lengths and values natively.
  const auto release = py::call_guard<py::gil_scoped_release>();
  py::class_<Energy>(m, "Energy")
      .def_property_readonly("num_vertices", &Energy::num_vertices)
      .def("value", &Energy::value, py::arg("x"), release)
      .def(
          "gradient",
          [](const Energy& energy, const VectorRef& x) {
            Eigen::VectorXd gradient(x.size());
            energy.value_and_gradient(x, gradient);
            return gradient;
          },
          py::arg("x"), release)
      .def("hessian", &Energy::hessian, py::arg("x"), release)
      .def("third", &Energy::third, py::arg("x"), py::arg("u"), py::arg("w"), release);

  // Each energy adds its class here, deriving from Energy.

  py::class_<Arap, Energy>(m, "Arap")
      .def(py::init<const VerticesRef&, const FacesRef&>(), py::arg("V"), py::arg("F"), release);
  py::class_<DiscreteShells, Energy>(m, "DiscreteShells")
      .def(py::init([](const VerticesRef& V, const FacesRef& F, double bending, double membrane,
                       const Eigen::VectorXd& stiffness_weights, double max_stiffness) {
             return DiscreteShells(V, F, bending, membrane, {stiffness_weights, max_stiffness});
           }),
           py::arg("V"), py::arg("F"), py::arg("bending"), py::arg("membrane"), py::arg("stiffness_weights"),
           py::arg("max_stiffness"), release)
      .def("third_batch", &DiscreteShells::third_batch, py::arg("x"), py::arg("Phi"), py::arg("pairs"), release)
      .def_property_readonly("term_counts", [](const DiscreteShells& energy) {
        const auto counts = energy.term_counts();
        return py::dict(py::arg("edges") = counts.edges, py::arg("triangles") = counts.triangles,
                        py::arg("hinges") = counts.hinges);
      });
}

}  // namespace modal_deform
