// Secondary motion: the reduced dynamics (solve/reduced_dynamics.h).
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <string>
#include <vector>

#include "bindings/bindings.h"
#include "solve/reduced_dynamics.h"

namespace py = pybind11;

namespace modal_deform {
namespace {

// Handles arrive as a list of int32 arrays (checked by modal_deform.core.dynamics).
Handles to_handles(const std::vector<Eigen::VectorXi>& arrays) {
  Handles handles;
  for (const Eigen::VectorXi& a : arrays) handles.emplace_back(a.data(), a.data() + a.size());
  return handles;
}

py::dict to_dict(const SimulationStepStats& stats) {
  return py::dict(py::arg("substeps") = stats.substeps, py::arg("iterations") = stats.iterations,
                  py::arg("evaluations") = stats.evaluations, py::arg("converged") = stats.converged,
                  py::arg("stalled") = stats.stalled, py::arg("line_search_failures") = stats.line_search_failures,
                  py::arg("implicit_euler") = stats.implicit_euler, py::arg("energy_removed") = stats.energy_removed,
                  py::arg("ms") = stats.milliseconds);
}

}  // namespace

void bind_dynamics(py::module_& m) {
  const SimulationOptions defaults;
  m.attr("SIMULATION_DEFAULTS") =
      py::dict(py::arg("stiffness") = defaults.stiffness, py::arg("period") = defaults.period,
               py::arg("damping") = defaults.damping, py::arg("fps") = defaults.fps,
               py::arg("substeps") = defaults.substeps, py::arg("max_iterations") = defaults.max_iterations,
               py::arg("tolerance") = defaults.tolerance);
  m.attr("MIN_PERIOD_FRAMES") = kMinPeriodFrames;
  m.attr("MAX_SUBSTEPS") = kMaxSubsteps;
  py::class_<ReducedDynamics>(m, "Simulation")
      .def(py::init([](const Basis& basis, const std::vector<Eigen::VectorXi>& handles, const VectorRef& weights,
                       double stiffness, double period, double damping, double fps, int substeps, int max_iterations,
                       double tolerance, const std::string& energy) {
             SimulationOptions options;
             options.stiffness = stiffness;
             options.period = period;
             options.damping = damping;
             options.fps = fps;
             options.substeps = substeps;
             options.max_iterations = max_iterations;
             options.tolerance = tolerance;
             const EnergyKind kind = energy_kind(energy);
             py::gil_scoped_release release;
             return std::make_unique<ReducedDynamics>(basis, to_handles(handles), weights, options, kind);
           }),
           py::arg("basis"), py::arg("handles"), py::arg("weights"), py::arg("stiffness"), py::arg("period"),
           py::arg("damping"), py::arg("fps"), py::arg("substeps"), py::arg("max_iterations"), py::arg("tolerance"),
           py::arg("energy"), py::keep_alive<1, 2>())
      .def(
          "step",
          [](ReducedDynamics& simulation, const Transforms& transforms) {
            SimulationStepStats stats;
            {
              py::gil_scoped_release release;
              stats = simulation.step(transforms);
            }
            return to_dict(stats);
          },
          py::arg("transforms"))
      .def("set_state", &ReducedDynamics::set_state, py::arg("q"), py::arg("v"), py::arg("transforms"))
      .def("positions", &ReducedDynamics::positions, py::arg("out").noconvert(),
           py::call_guard<py::gil_scoped_release>())
      .def_property_readonly("q", [](const ReducedDynamics& s) { return Eigen::VectorXd(s.q()); })
      .def_property_readonly("v", [](const ReducedDynamics& s) { return Eigen::VectorXd(s.v()); })
      .def("energy", &ReducedDynamics::energy)
      .def("kinetic_energy", &ReducedDynamics::kinetic_energy)
      .def("potential_energy", &ReducedDynamics::potential_energy)
      .def_property_readonly("dimension", &ReducedDynamics::dimension)
      .def_property_readonly("num_handles", &ReducedDynamics::num_handles)
      .def_property_readonly("mass_scale", &ReducedDynamics::mass_scale)
      .def_property_readonly("lowest_mode", [](const ReducedDynamics& s) { return Eigen::VectorXd(s.lowest_mode()); });
}

}  // namespace modal_deform
