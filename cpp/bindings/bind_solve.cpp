// Posing: the reduced solver and the full-space reference solve.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bindings/bindings.h"
#include "bindings/named_fields.h"
#include "bindings/python_progress.h"
#include "solve/full_solver.h"
#include "solve/reduced_solver.h"
#include "solve/refine.h"
#include "util/errors.h"

namespace py = pybind11;

namespace modal_deform {

Handles to_handles(const std::vector<Eigen::VectorXi>& arrays) {
  Handles handles;
  handles.reserve(arrays.size());
  for (const Eigen::VectorXi& a : arrays) handles.emplace_back(a.data(), a.data() + a.size());
  return handles;
}

namespace {

// solve_full's and refine's keywords: the pull μ (their argument in the core) and the options.
struct FullSolveKeywords {
  double pull = kDefaultPull;
  FullSolveOptions options;
};

template <typename Visit>
void for_each_full_solve_keyword(Visit&& visit) {
  visit(kPull, [](auto& k) -> auto& { return k.pull; });
  for_each_full_solve_option([&](const Option& option, auto field) {
    visit(option, [field](auto& k) -> auto& { return field(k.options); });
  });
}

}  // namespace

void bind_solve(py::module_& m) {
  const auto solver_options = [](auto visit) { for_each_reduced_solver_option(visit); };
  const auto solve_options = [](auto visit) { for_each_reduced_solve_option(visit); };
  const auto full_solve_keywords = [](auto visit) { for_each_full_solve_keyword(visit); };
  m.attr("REDUCED_SOLVER_OPTIONS") = option_table<ReducedSolverOptions>(solver_options);
  m.attr("REDUCED_SOLVE_OPTIONS") = option_table<ReducedSolveOptions>(solve_options);
  m.attr("FULL_SOLVE_OPTIONS") = option_table<FullSolveKeywords>(full_solve_keywords);
  py::class_<ReducedSolver>(m, "ReducedSolver")
      .def(
          py::init([solver_options](const Basis& basis, const std::vector<Eigen::VectorXi>& handles,
                                    const VectorRef& weights, const py::kwargs& keywords) {
            const auto options =
                from_keywords<ReducedSolverOptions>(keywords, solver_options, "ReducedSolver");
            py::gil_scoped_release release;
            return std::make_unique<ReducedSolver>(basis, to_handles(handles), weights, options);
          }),
          py::arg("basis"), py::arg("handles"), py::arg("weights"), py::keep_alive<1, 2>())
      .def("set_transforms", &ReducedSolver::set_transforms, py::arg("transforms"))
      .def("solve",
           [solve_options](ReducedSolver& solver, const py::kwargs& keywords) {
             const auto options =
                 from_keywords<ReducedSolveOptions>(keywords, solve_options, "solve");
             ReducedSolveStats stats;
             {
               py::gil_scoped_release release;
               stats = solver.solve(options);
             }
             return to_dict(stats, [](auto visit) { for_each_reduced_solve_stat(visit); });
           })
      .def("reset", &ReducedSolver::reset)
      .def(
          "objective",
          [](ReducedSolver& solver, const Eigen::VectorXd& q) {
            if (q.size() != solver.dimension())
              throw InputError(message("q: expected ", solver.dimension(),
                                       " reduced coordinates, got ", q.size()));
            Eigen::VectorXd gradient(q.size());
            double value;
            {
              py::gil_scoped_release release;
              value = solver.objective(q, gradient);
            }
            return py::make_tuple(value, std::move(gradient));
          },
          py::arg("q"))
      .def("positions", &ReducedSolver::positions, py::arg("out").noconvert(),
           py::call_guard<py::gil_scoped_release>())
      .def_property_readonly(
          "q", [](const ReducedSolver& solver) { return Eigen::VectorXd(solver.q()); })
      .def_property_readonly("dimension", &ReducedSolver::dimension)
      .def_property_readonly("num_handles", &ReducedSolver::num_handles);
  m.def("nearest_rigid", &nearest_rigid, py::arg("matrix"), py::arg("centre"));

  // solve_full and refine: the same arguments and options; (positions, stats) with the stats of
  // their tables and "history", one dict per Newton iteration.
  const auto keywords_of = [full_solve_keywords](const py::kwargs& keywords,
                                                 const py::object& progress, const char* function) {
    auto given = from_keywords<FullSolveKeywords>(keywords, full_solve_keywords, function);
    given.options.progress = python_progress(progress);
    return given;
  };
  const auto positions_and_stats = [](auto& result, auto stats_table) {
    py::dict stats = to_dict(result, stats_table);
    py::list history;
    for (const NewtonIteration& it : result.history)
      history.append(to_dict(it, [](auto visit) { for_each_newton_iteration_field(visit); }));
    stats["history"] = history;
    return py::make_tuple(std::move(result.positions), stats);
  };
  m.def(
      "solve_full",
      [keywords_of, positions_and_stats](const VerticesRef& V, const FacesRef& F,
                                         const std::vector<Eigen::VectorXi>& handles,
                                         const Transforms& transforms, const VectorRef& weights,
                                         const std::optional<RowMatrixX3d>& initial,
                                         const py::object& progress, const py::kwargs& keywords) {
        const FullSolveKeywords given = keywords_of(keywords, progress, "solve_full");
        FullSolveResult result;
        {
          py::gil_scoped_release release;
          result = solve_full(V, F, to_handles(handles), weights, transforms, given.pull,
                              given.options, initial ? &*initial : nullptr);
        }
        return positions_and_stats(result, [](auto visit) { for_each_full_solve_stat(visit); });
      },
      py::arg("V"), py::arg("F"), py::arg("handles"), py::arg("transforms"), py::arg("weights"),
      py::kw_only(), py::arg("initial") = py::none(), py::arg("progress") = py::none());
  m.def(
      "refine",
      [keywords_of, positions_and_stats](
          const VerticesRef& V, const FacesRef& F, const std::vector<Eigen::VectorXi>& handles,
          const Transforms& transforms, const VectorRef& weights, const RowMatrixX3d& initial,
          const py::object& progress, const py::kwargs& keywords) {
        const FullSolveKeywords given = keywords_of(keywords, progress, "refine");
        RefineResult result;
        {
          py::gil_scoped_release release;
          result = refine(V, F, to_handles(handles), weights, transforms, given.pull, given.options,
                          initial);
        }
        return positions_and_stats(result, [](auto visit) { for_each_refine_stat(visit); });
      },
      py::arg("V"), py::arg("F"), py::arg("handles"), py::arg("transforms"), py::arg("weights"),
      py::kw_only(), py::arg("initial"), py::arg("progress") = py::none());
}

}  // namespace modal_deform
