// Posing: the reduced solver and the full-space reference solve.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bindings/bindings.h"
#include "bindings/python_progress.h"
#include "solve/full_solver.h"
#include "solve/reduced_solver.h"
#include "util/errors.h"

namespace py = pybind11;

namespace modal_deform {
namespace {

// Handles arrive as a list of int32 arrays (checked by modal_deform.core.solve).
Handles to_handles(const std::vector<Eigen::VectorXi>& arrays) {
  Handles handles;
  handles.reserve(arrays.size());
  for (const Eigen::VectorXi& a : arrays) handles.emplace_back(a.data(), a.data() + a.size());
  return handles;
}

}  // namespace

void bind_solve(py::module_& m) {
  m.attr("FULL_SOLVE_MAX_ITERATIONS") = FullSolveOptions{}.max_iterations;
  py::class_<ReducedSolver>(m, "ReducedSolver")
      .def(py::init([](const Basis& basis, const std::vector<Eigen::VectorXi>& handles, const VectorRef& weights,
                       double stiffness, const std::string& energy, bool warm_start) {
             py::gil_scoped_release release;
             return std::make_unique<ReducedSolver>(basis, to_handles(handles), weights, stiffness,
                                                    energy_kind(energy), warm_start);
           }),
           py::arg("basis"), py::arg("handles"), py::arg("weights"), py::arg("stiffness"), py::arg("energy"),
           py::arg("warm_start"), py::keep_alive<1, 2>())
      .def("set_transforms", &ReducedSolver::set_transforms, py::arg("transforms"))
      .def(
          "solve",
          [](ReducedSolver& solver, int max_iterations, double tolerance, double budget_ms) {
            ReducedSolveStats stats;
            {
              py::gil_scoped_release release;
              stats = solver.solve(max_iterations, tolerance, budget_ms);
            }
            return py::dict(py::arg("iterations") = stats.iterations, py::arg("energy") = stats.energy,
                            py::arg("converged") = stats.converged, py::arg("ms") = stats.milliseconds,
                            py::arg("evaluations") = stats.evaluations, py::arg("gradient_norm") = stats.gradient_norm,
                            py::arg("stalled") = stats.stalled,
                            py::arg("line_search_failures") = stats.line_search_failures);
          },
          py::arg("max_iterations"), py::arg("tolerance"), py::arg("budget_ms"))
      .def("reset", &ReducedSolver::reset)
      .def(
          "objective",
          [](ReducedSolver& solver, const Eigen::VectorXd& q) {
            if (q.size() != solver.dimension())
              throw InputError(message("q: expected ", solver.dimension(), " reduced coordinates, got ", q.size()));
            Eigen::VectorXd gradient(q.size());
            double value;
            {
              py::gil_scoped_release release;
              value = solver.objective(q, gradient);
            }
            return py::make_tuple(value, std::move(gradient));
          },
          py::arg("q"))
      .def("positions", &ReducedSolver::positions, py::arg("out").noconvert(), py::call_guard<py::gil_scoped_release>())
      .def_property_readonly("q", [](const ReducedSolver& solver) { return Eigen::VectorXd(solver.q()); })
      .def_property_readonly("dimension", &ReducedSolver::dimension)
      .def_property_readonly("num_handles", &ReducedSolver::num_handles);

  m.def(
      "solve_full",
      [](const VerticesRef& V, const FacesRef& F, const std::vector<Eigen::VectorXi>& handles,
         const Transforms& transforms, const VectorRef& weights, double stiffness, const std::string& energy,
         double bending, double membrane, const Eigen::VectorXd& stiffness_weights, double max_stiffness,
         double tolerance, int max_iterations, const std::optional<RowMatrixX3d>& initial,
         const py::object& progress, const std::vector<int>& held) {
        FullSolveOptions options;
        options.energy = energy_kind(energy);
        options.bending = bending;
        options.membrane = membrane;
        options.paint = {stiffness_weights, max_stiffness};
        options.tolerance = tolerance;
        options.max_iterations = max_iterations;
        options.progress = python_progress(progress);
        options.held = held;
        FullSolveResult result;
        {
          py::gil_scoped_release release;
          result = solve_full(V, F, to_handles(handles), weights, transforms, stiffness, options,
                              initial ? &*initial : nullptr);
        }
        py::dict stats(py::arg("steps") = result.steps, py::arg("iterations") = result.iterations,
                       py::arg("energy") = result.energy, py::arg("converged") = result.converged,
                       py::arg("gradient_norm") = result.gradient_norm,
                       py::arg("gradient_scale") = result.gradient_scale,
                       py::arg("factorizations") = result.factorizations,
                       py::arg("initial_energy") = result.initial_energy,
                       py::arg("relaxed_vertices") = result.relaxed_vertices, py::arg("seconds") = result.seconds,
                       py::arg("stalled") = result.stalled);
        // Per iteration: the Hessian model, τ, the step and why it was cut, the model's accuracy.
        py::list history;
        for (const NewtonIteration& it : result.history)
          history.append(py::dict(py::arg("model") = it.exact ? "exact" : "projected", py::arg("shift") = it.shift,
                                  py::arg("step") = it.step, py::arg("guarded") = it.guarded,
                                  py::arg("ratio") = it.ratio, py::arg("cg_iterations") = it.cg_iterations,
                                  py::arg("progress") = it.progress,
                                  py::arg("energy") = it.value, py::arg("gradient_norm") = it.gradient_norm));
        stats["history"] = history;
        return py::make_tuple(std::move(result.positions), stats);
      },
      py::arg("V"), py::arg("F"), py::arg("handles"), py::arg("transforms"), py::arg("weights"), py::arg("stiffness"),
      py::arg("energy"), py::arg("bending"), py::arg("membrane"), py::arg("stiffness_weights"),
      py::arg("max_stiffness"), py::arg("tolerance"), py::arg("max_iterations"),
      py::arg("initial"), py::arg("progress"), py::arg("held"));
}

}  // namespace modal_deform
