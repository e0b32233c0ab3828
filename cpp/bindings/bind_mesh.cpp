#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings/bindings.h"
#include "mesh/mass.h"
#include "mesh/mesh_check.h"
#include "mesh/primitives.h"
#include "mesh/read_mesh.h"

namespace py = pybind11;

namespace modal_deform {
namespace {

py::tuple as_tuple(TriangleMesh mesh) {
  return py::make_tuple(std::move(mesh.V), std::move(mesh.F));
}

py::dict report_to_dict(const MeshReport& report) {
  py::dict out;
  out["vertices"] = report.num_vertices;
  out["faces"] = report.num_faces;
  out["edges"] = report.num_edges;
  out["components"] = report.num_components;
  out["component_sizes"] = report.component_sizes;
  out["vertex_component"] =
      Eigen::Map<const Eigen::VectorXi>(report.vertex_component.data(),
                                        static_cast<Eigen::Index>(report.vertex_component.size()))
          .eval();
  for (const auto& finding : report.findings)
    out[finding.name.c_str()] =
        py::dict(py::arg("count") = finding.count, py::arg("first") = finding.examples);
  return out;
}

}  // namespace

void bind_mesh(py::module_& m) {
  m.def(
      "check",
      [](const VerticesRef& V, const FacesRef& F) { return report_to_dict(check_mesh(V, F)); },
      py::arg("V"), py::arg("F"));
  m.def(
      "mass",
      [](const VerticesRef& V, const FacesRef& F) {
        validate_mesh(V, F);
        return lumped_mass(V, F);
      },
      py::arg("V"), py::arg("F"));
  m.def(
      "read_mesh",
      [](const std::string& path) {
        TriangleMesh mesh;
        {
          py::gil_scoped_release release;
          mesh = read_mesh(path);
        }
        return as_tuple(std::move(mesh));
      },
      py::arg("path"));
  m.def("grid", [](int nx, int ny, double w, double h) { return as_tuple(grid(nx, ny, w, h)); });
  m.def("bumpy_plane", [](int n, double size, int bumps, double amplitude, std::uint32_t seed) {
    return as_tuple(bumpy_plane(n, size, bumps, amplitude, seed));
  });
  m.def("cylinder", [](int around, int along, double r, double length) {
    return as_tuple(cylinder(around, along, r, length));
  });
  m.def("bar", [](int nx, int ny, int nz, double sx, double sy, double sz) {
    return as_tuple(bar(nx, ny, nz, sx, sy, sz));
  });
}

}  // namespace modal_deform
