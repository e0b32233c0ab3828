// Secondary motion: the reduced dynamics (solve/reduced_dynamics.h).
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bindings/bindings.h"
#include "bindings/named_fields.h"
#include "solve/reduced_dynamics.h"
#include "solve/rig_forces.h"

namespace py = pybind11;

namespace modal_deform {

namespace {

// Skinning weights as the core keeps them, made from the compressed-row arrays that
// modal_deform.core.rig passes: pybind11 reads Eigen's sparse matrices from SciPy's, and Blender's
// Python has no SciPy.
struct RigWeights {
  SkinningWeights weights;
};

}  // namespace

void bind_dynamics(py::module_& m) {
  const auto simulation_options = [](auto visit) { for_each_simulation_option(visit); };
  m.attr("SIMULATION_OPTIONS") = option_table<SimulationOptions>(simulation_options);
  py::class_<RigWeights>(m, "SkinningWeights")
      .def(py::init([](int num_vertices, int num_bones, const Eigen::VectorXi& row_pointers,
                       const Eigen::VectorXi& columns, const Eigen::VectorXd& values) {
             return RigWeights{skinning_weights_from_rows(num_vertices, num_bones, row_pointers,
                                                          columns, values)};
           }),
           py::arg("num_vertices"), py::arg("num_bones"), py::arg("row_pointers"),
           py::arg("columns"), py::arg("values"))
      .def_property_readonly("num_bones", [](const RigWeights& rig) { return rig.weights.cols(); });
  m.def("check_bone_matrices", &check_bone_matrices, py::arg("bones"), py::arg("num_bones"));
  py::class_<ReducedDynamics>(m, "Simulation")
      .def(py::init([simulation_options](const Basis& basis,
                                         const std::vector<Eigen::VectorXi>& handles,
                                         const VectorRef& weights, const std::string& energy,
                                         const RigWeights* rig, const py::kwargs& keywords) {
             const SimulationOptions options =
                 from_keywords<SimulationOptions>(keywords, simulation_options, "Simulation");
             const EnergyKind kind = energy_kind(energy);
             py::gil_scoped_release release;
             return std::make_unique<ReducedDynamics>(basis, to_handles(handles), weights, options,
                                                      kind, rig ? &rig->weights : nullptr);
           }),
           py::arg("basis"), py::arg("handles"), py::arg("weights"), py::arg("energy"),
           py::arg("rig"), py::keep_alive<1, 2>())
      .def(
          "step",
          [](ReducedDynamics& simulation, const Transforms& transforms, const Transforms& bones) {
            SimulationStepStats stats;
            {
              py::gil_scoped_release release;
              stats = simulation.step(transforms, bones);
            }
            return to_dict(stats, [](auto visit) { for_each_simulation_stat(visit); });
          },
          py::arg("transforms"), py::arg("bones"))
      .def("set_state", &ReducedDynamics::set_state, py::arg("q"), py::arg("v"),
           py::arg("transforms"), py::arg("rig_previous"), py::arg("rig_current"))
      .def_property_readonly("rig_previous", &ReducedDynamics::rig_previous)
      .def_property_readonly("rig_current", &ReducedDynamics::rig_current)
      .def_property_readonly("num_bones", &ReducedDynamics::num_bones)
      .def_property_readonly("on_rig", &ReducedDynamics::on_rig)
      .def_property_readonly(
          "rig_acceleration",
          [](const ReducedDynamics& s) { return Eigen::VectorXd(s.rig_acceleration()); })
      .def("forget", &ReducedDynamics::forget)
      .def_property_readonly("remembered_frames", &ReducedDynamics::remembered_frames)
      .def_property_readonly("memory_frames", &ReducedDynamics::memory_frames)
      .def("positions", &ReducedDynamics::positions, py::arg("out").noconvert(),
           py::call_guard<py::gil_scoped_release>())
      .def("positions_of", &ReducedDynamics::positions_of, py::arg("q"), py::arg("out").noconvert(),
           py::call_guard<py::gil_scoped_release>())
      .def("displacement_of", &ReducedDynamics::displacement_of, py::arg("q"),
           py::arg("out").noconvert(), py::call_guard<py::gil_scoped_release>())
      .def_property_readonly("q", [](const ReducedDynamics& s) { return Eigen::VectorXd(s.q()); })
      .def_property_readonly("v", [](const ReducedDynamics& s) { return Eigen::VectorXd(s.v()); })
      .def("energy", &ReducedDynamics::energy)
      .def("kinetic_energy", &ReducedDynamics::kinetic_energy)
      .def("potential_energy", &ReducedDynamics::potential_energy)
      .def_property_readonly("dimension", &ReducedDynamics::dimension)
      .def_property_readonly("num_handles", &ReducedDynamics::num_handles)
      .def_property_readonly("mass_scale", &ReducedDynamics::mass_scale)
      .def_property_readonly(
          "lowest_mode", [](const ReducedDynamics& s) { return Eigen::VectorXd(s.lowest_mode()); });
}

}  // namespace modal_deform
