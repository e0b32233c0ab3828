// InputError (a std::invalid_argument) reaches Python as ValueError and NumericalError as
// RuntimeError through pybind11's standard translation; Cancelled and OutOfMemory (a MemoryError)
// get their own types.
#include <pybind11/pybind11.h>

#include "bindings/bindings.h"
#include "util/errors.h"

namespace py = pybind11;

namespace modal_deform {

void bind_errors(py::module_& m) {
  py::register_exception<Cancelled>(m, "Cancelled", PyExc_RuntimeError);
  py::register_exception<OutOfMemory>(m, "OutOfMemoryError", PyExc_MemoryError);
}

}  // namespace modal_deform
