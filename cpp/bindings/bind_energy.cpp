// The energies: one Python class per energy, sharing the methods of the Energy interface.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings/bindings.h"
#include "bindings/named_fields.h"
#include "energy/arap.h"
#include "energy/discrete_shells.h"
#include "energy/energy.h"
#include "energy/material.h"

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

  py::class_<Arap, Energy>(m, "Arap").def(py::init<const VerticesRef&, const FacesRef&>(),
                                          py::arg("V"), py::arg("F"), release);
  const auto material_options = [](auto visit) { for_each_material_field(visit); };
  m.attr("MATERIAL_OPTIONS") = option_table<Material>(material_options);
  py::class_<DiscreteShells, Energy>(m, "DiscreteShells")
      .def(py::init([material_options](const VerticesRef& V, const FacesRef& F,
                                       const py::kwargs& keywords) {
             const Material material =
                 from_keywords<Material>(keywords, material_options, "DiscreteShells");
             py::gil_scoped_release unlocked;
             return DiscreteShells(V, F, material.bending, material.membrane, material.paint);
           }),
           py::arg("V"), py::arg("F"))
      .def("third_batch", &DiscreteShells::third_batch, py::arg("x"), py::arg("Phi"),
           py::arg("pairs"), release)
      .def_property_readonly("term_counts", [](const DiscreteShells& energy) {
        const auto counts = energy.term_counts();
        return py::dict(py::arg("edges") = counts.edges, py::arg("triangles") = counts.triangles,
                        py::arg("hinges") = counts.hinges);
      });
}

}  // namespace modal_deform
