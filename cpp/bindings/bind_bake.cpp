// The bake, and the Basis it produces with read-only numpy views of its arrays.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>
#include <utility>

#include "bindings/bindings.h"
#include "bindings/python_progress.h"
#include "bake/bake.h"

namespace py = pybind11;

namespace modal_deform {

void bind_bake(py::module_& m) {
  // Getters return const references: with def_property_readonly's reference_internal policy they
  // become read-only numpy views that keep the Basis alive.
  py::class_<Basis>(m, "Basis")
      .def(py::init([](RowMatrixX3d rest, Eigen::VectorXd mass, RowMatrixXf vectors, int num_rigid, int num_modes,
                       int num_floppy, Eigen::VectorXd eigenvalues, RowMatrixX3d ghost_vertices,
                       RowMatrixX3i ghost_faces, Eigen::VectorXi ghost_map, Eigen::MatrixXd ghost_vectors, double scale,
                       double bending, double membrane, int num_dropped, RowMatrixX3i prolongation_vertices,
                       RowMatrixX3f prolongation_weights) {
             // Arrays arrive as copies (modal_deform.core checks their dtypes first); validated
             // before anything reads them.
             Basis b;
             b.rest = std::move(rest);
             b.mass = std::move(mass);
             b.vectors = std::move(vectors);
             b.num_rigid = num_rigid;
             b.num_modes = num_modes;
             b.num_floppy = num_floppy;
             b.eigenvalues = std::move(eigenvalues);
             b.ghost_vertices = std::move(ghost_vertices);
             b.ghost_faces = std::move(ghost_faces);
             b.ghost_map = std::move(ghost_map);
             b.ghost_vectors = std::move(ghost_vectors);
             b.scale = scale;
             b.bending = bending;
             b.membrane = membrane;
             b.num_dropped = num_dropped;
             b.prolongation.vertices = std::move(prolongation_vertices);
             b.prolongation.weights = std::move(prolongation_weights);
             validate_basis(b);
             return b;
           }),
           py::arg("rest"), py::arg("mass"), py::arg("vectors"), py::arg("num_rigid"), py::arg("num_modes"),
           py::arg("num_floppy"), py::arg("eigenvalues"), py::arg("ghost_vertices"), py::arg("ghost_faces"),
           py::arg("ghost_map"), py::arg("ghost_vectors"), py::arg("scale"), py::arg("bending"), py::arg("membrane"),
           py::arg("num_dropped"), py::arg("prolongation_vertices"), py::arg("prolongation_weights"))
      .def_property_readonly("rest", [](const Basis& b) -> const RowMatrixX3d& { return b.rest; })
      .def_property_readonly("mass", [](const Basis& b) -> const Eigen::VectorXd& { return b.mass; })
      .def_property_readonly("vectors", [](const Basis& b) -> const RowMatrixXf& { return b.vectors; })
      .def_property_readonly("eigenvalues", [](const Basis& b) -> const Eigen::VectorXd& { return b.eigenvalues; })
      .def_property_readonly("ghost_vertices", [](const Basis& b) -> const RowMatrixX3d& { return b.ghost_vertices; })
      .def_property_readonly("ghost_faces", [](const Basis& b) -> const RowMatrixX3i& { return b.ghost_faces; })
      .def_property_readonly("ghost_map", [](const Basis& b) -> const Eigen::VectorXi& { return b.ghost_map; })
      .def_property_readonly("ghost_vectors", [](const Basis& b) -> const Eigen::MatrixXd& { return b.ghost_vectors; })
      .def_readonly("num_rigid", &Basis::num_rigid)
      .def_readonly("num_modes", &Basis::num_modes)
      .def_readonly("num_floppy", &Basis::num_floppy)
      .def_readonly("num_dropped", &Basis::num_dropped)
      .def_readonly("scale", &Basis::scale)
      .def_readonly("bending", &Basis::bending)
      .def_readonly("membrane", &Basis::membrane)
      .def_property_readonly("prolongation_vertices",
                             [](const Basis& b) -> const RowMatrixX3i& { return b.prolongation.vertices; })
      .def_property_readonly("prolongation_weights",
                             [](const Basis& b) -> const RowMatrixX3f& { return b.prolongation.weights; })
      .def_property_readonly("num_basis_vertices", &Basis::num_basis_vertices)
      .def_property_readonly("on_proxy", &Basis::on_proxy)
      .def_readonly("timings", &Basis::timings)
      .def_property_readonly("dimension", &Basis::dimension)
      .def_property_readonly("num_vertices", &Basis::num_vertices);

  m.def(
      "bake",
      [](const VerticesRef& V, const FacesRef& F, int modes, int derivatives, int ghost, const std::string& energy,
         double bending, double membrane, bool rotation_pairs, int proxy_above, int proxy,
         const py::object& progress) {
        const BakeOptions options{modes,   derivatives, ghost,          energy_kind(energy), bending,
                                  membrane, rotation_pairs, proxy_above, proxy};
        Progress reporter(python_progress(progress));
        py::gil_scoped_release release;
        return bake(V, F, options, reporter);
      },
      py::arg("V"), py::arg("F"), py::arg("modes"), py::arg("derivatives"), py::arg("ghost"), py::arg("energy"),
      py::arg("bending"), py::arg("membrane"), py::arg("rotation_pairs"), py::arg("proxy_above"), py::arg("proxy"),
      py::arg("progress"));
}

}  // namespace modal_deform
