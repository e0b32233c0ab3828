// The bake, and the Basis it produces with read-only numpy views of its arrays.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>
#include <type_traits>
#include <utility>

#include "bake/bake.h"
#include "bindings/bindings.h"
#include "bindings/named_fields.h"
#include "bindings/python_progress.h"
#include "util/bake_stages.h"

namespace py = pybind11;

namespace modal_deform {

namespace {

// How a stored field of the Basis looks in numpy: dtype, number of dimensions, a fixed number of
// columns (0: any) and whether it is column-major. Scalars are 0-d.
template <typename T, typename = void>
struct StoredLayout {
  using Scalar = T;
  static constexpr int ndim = 0, columns = 0;
  static constexpr bool fortran = false;
};

template <typename T>
struct StoredLayout<T, std::enable_if_t<std::is_base_of_v<Eigen::EigenBase<T>, T>>> {
  using Scalar = typename T::Scalar;
  static constexpr bool vector = T::IsVectorAtCompileTime;
  static constexpr int ndim = vector ? 1 : 2;
  static constexpr int columns =
      vector || T::ColsAtCompileTime == Eigen::Dynamic ? 0 : T::ColsAtCompileTime;
  static constexpr bool fortran = !vector && !T::IsRowMajor;
};

// The type of a stored field, from its accessor.
template <typename Field>
using FieldType = std::decay_t<decltype(std::declval<Field>()(std::declval<Basis&>()))>;

}  // namespace

void bind_bake(py::module_& m) {
  py::class_<Basis> basis(m, "Basis");
  // The keyword constructor, one read-only property per stored field, and the schema that
  // modal_deform.core stores and checks them by, all from for_each_stored_field.
  basis.def(py::init([](const py::kwargs& fields) {
    // Arrays arrive as copies (modal_deform.core checks their dtypes and dimensions first); a field
    // left out keeps its default (a basis stored before it existed); validated before anything
    // reads them.
    Basis b;
    int known = 0;
    for_each_stored_field([&](const char* name, int, auto field) {
      if (!fields.contains(name)) return;
      field(b) = fields[name].template cast<FieldType<decltype(field)>>();
      ++known;
    });
    if (known != static_cast<int>(fields.size()))
      for (const auto& item : fields) {
        bool stored = false;
        const auto key = item.first.cast<std::string>();
        for_each_stored_field([&](const char* name, int, auto) { stored = stored || key == name; });
        if (!stored) throw InputError(message("basis: ", key, " is not a field of a basis"));
      }
    validate_basis(b);
    return b;
  }));
  py::list schema;
  for_each_stored_field([&](const char* name, int since, auto field) {
    using T = FieldType<decltype(field)>;
    using Layout = StoredLayout<T>;
    schema.append(py::dict(py::arg("name") = name, py::arg("since") = since,
                           py::arg("dtype") = py::dtype::of<typename Layout::Scalar>(),
                           py::arg("ndim") = Layout::ndim, py::arg("columns") = Layout::columns,
                           py::arg("fortran") = Layout::fortran));
    // Const references: with def_property_readonly's reference_internal policy arrays become
    // read-only numpy views that keep the Basis alive.
    basis.def_property_readonly(name, [field](const Basis& b) -> const T& { return field(b); });
  });
  basis.attr("schema") = schema;
  basis.def_property_readonly("num_basis_vertices", &Basis::num_basis_vertices)
      .def_property_readonly("on_proxy", &Basis::on_proxy)
      .def_readonly("timings", &Basis::timings)
      .def_property_readonly("dimension", &Basis::dimension)
      .def_property_readonly("num_vertices", &Basis::num_vertices);

  py::tuple stages(kBakeStages.size());
  for (size_t i = 0; i < kBakeStages.size(); ++i) stages[i] = kBakeStages[i];
  m.attr("BAKE_STAGES") = stages;

  m.attr("BAKE_OPTIONS") =
      option_table<BakeOptions>([](auto visit) { for_each_bake_option(visit); });
  m.def(
      "bake",
      [](const VerticesRef& V, const FacesRef& F, const py::object& progress,
         const py::kwargs& keywords) {
        const auto options = from_keywords<BakeOptions>(
            keywords, [](auto visit) { for_each_bake_option(visit); }, "bake");
        Progress reporter(python_progress(progress));
        py::gil_scoped_release release;
        return bake(V, F, options, reporter);
      },
      py::arg("V"), py::arg("F"), py::kw_only(), py::arg("progress") = py::none());
}

}  // namespace modal_deform
