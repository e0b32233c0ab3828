// Shape blending: the shape space of the artist's keys (solve/shape_space.h).
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <vector>

#include "bindings/bindings.h"
#include "bindings/named_fields.h"
#include "solve/shape_space.h"

namespace py = pybind11;

namespace modal_deform {

void bind_shapes(py::module_& m) {
  const auto blend_options = [](auto visit) { for_each_blend_option(visit); };
  m.attr("BLEND_OPTIONS") = option_table<BlendOptions>(blend_options);
  m.attr("MAX_SHAPE_KEYS") = kMaxShapeKeys;
  py::class_<ShapeSpace>(m, "ShapeSpace")
      .def(py::init([](const Basis& basis, const std::vector<RowMatrixX3d>& keys) {
             py::gil_scoped_release release;
             return std::make_unique<ShapeSpace>(basis, keys);
           }),
           py::arg("basis"), py::arg("keys"))
      // A stored space: its basis (validated when made) and its own arrays.
      .def(py::init([](const Basis& basis, int base_dimension, const Eigen::MatrixXd& coordinates,
                       const RowMatrixXf& residuals) {
             py::gil_scoped_release release;
             return std::make_unique<ShapeSpace>(
                 ShapeSpaceData{basis, base_dimension, coordinates, residuals});
           }),
           py::arg("basis"), py::arg("base_dimension"), py::arg("coordinates"),
           py::arg("residuals"))
      .def(
          "blend",
          [blend_options](ShapeSpace& space, const VectorRef& weights,
                          Eigen::Ref<Eigen::VectorXf> out, const py::kwargs& keywords) {
            const auto options = from_keywords<BlendOptions>(keywords, blend_options, "blend");
            py::gil_scoped_release release;
            space.blend(weights, out, options);
          },
          py::arg("weights"), py::arg("out").noconvert())
      .def_property_readonly("stats",
                             [](const ShapeSpace& space) {
                               return to_dict(space.stats(),
                                              [](auto visit) { for_each_blend_stat(visit); });
                             })
      .def_property_readonly("q", [](const ShapeSpace& s) { return Eigen::VectorXd(s.q()); })
      // The augmented basis (a copy), and the stored arrays.
      .def_property_readonly("basis", [](const ShapeSpace& s) { return s.data().basis; })
      .def_property_readonly("base_dimension",
                             [](const ShapeSpace& s) { return s.data().base_dimension; })
      .def_property_readonly("coordinates",
                             [](const ShapeSpace& s) { return s.data().coordinates; })
      .def_property_readonly("residuals", [](const ShapeSpace& s) { return s.data().residuals; })
      .def_property_readonly("num_keys", &ShapeSpace::num_keys)
      .def_property_readonly("dimension", &ShapeSpace::dimension)
      .def_property_readonly("num_vertices", &ShapeSpace::num_vertices);
}

}  // namespace modal_deform
