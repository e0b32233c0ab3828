// Physics in-betweens: the spacetime solve through a few keys (solve/inbetween.h).
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bindings/bindings.h"
#include "bindings/named_fields.h"
#include "solve/inbetween.h"

namespace py = pybind11;

namespace modal_deform {

void bind_inbetween(py::module_& m) {
  const auto inbetween_options = [](auto visit) { for_each_inbetween_option(visit); };
  m.attr("INBETWEEN_OPTIONS") = option_table<InbetweenOptions>(inbetween_options);
  m.attr("MAX_INBETWEEN_KEYS") = kMaxInbetweenKeys;
  py::class_<Inbetween>(m, "Inbetween")
      .def(py::init([inbetween_options](
                        const Basis& basis, const std::vector<Eigen::VectorXi>& handles,
                        const VectorRef& weights, const std::vector<int>& frames,
                        const std::vector<std::vector<std::optional<Eigen::Matrix4d>>>& transforms,
                        const std::string& energy, const py::kwargs& keywords) {
             const InbetweenOptions options =
                 from_keywords<InbetweenOptions>(keywords, inbetween_options, "Inbetween");
             const EnergyKind kind = energy_kind(energy);
             if (frames.size() != transforms.size())
               throw InputError("keys: one frame per key's transforms");
             std::vector<InbetweenKey> keys(frames.size());
             for (size_t k = 0; k < frames.size(); ++k) keys[k] = {frames[k], transforms[k]};
             py::gil_scoped_release release;
             return std::make_unique<Inbetween>(basis, to_handles(handles), weights,
                                                std::move(keys), options, kind);
           }),
           py::arg("basis"), py::arg("handles"), py::arg("weights"), py::arg("frames"),
           py::arg("transforms"), py::arg("energy"), py::keep_alive<1, 2>())
      .def("solve",
           [](Inbetween& inbetween) {
             InbetweenStats stats;
             {
               py::gil_scoped_release release;
               stats = inbetween.solve();
             }
             return to_dict(stats, [](auto visit) { for_each_inbetween_stat(visit); });
           })
      .def(
          "state",
          [](Inbetween& inbetween, int frame) {
            Eigen::VectorXd q, v;
            {
              py::gil_scoped_release release;
              inbetween.state(frame, q, v);
            }
            return py::make_tuple(q, v);
          },
          py::arg("frame"))
      .def("positions", &Inbetween::positions, py::arg("frame"), py::arg("out").noconvert(),
           py::call_guard<py::gil_scoped_release>())
      .def_property_readonly("solved", &Inbetween::solved)
      .def_property_readonly("dimension", &Inbetween::dimension)
      .def_property_readonly("num_handles", &Inbetween::num_handles)
      .def_property_readonly("first_frame", &Inbetween::first_frame)
      .def_property_readonly("last_frame", &Inbetween::last_frame)
      .def_property_readonly("mass_scale", &Inbetween::mass_scale);
}

}  // namespace modal_deform
