// A Python progress(stage, fraction) callback as a native ProgressCallback.
#pragma once

#include <memory>

#include <pybind11/pybind11.h>

#include "util/progress.h"

namespace modal_deform {

// None gives no callback. The native side calls, copies and destroys the callback without the GIL
// (a Progress keeps its own copy): the Python object is held once behind a shared pointer, whose
// copies touch no Python reference count, and released under the GIL by the last of them; a call
// takes the GIL first. A false return cancels; None counts as "go on", so a callback that only
// prints does not stop the work; an exception raised by the callback propagates as itself.
inline ProgressCallback python_progress(const pybind11::object& callback) {
  if (callback.is_none()) return {};
  const std::shared_ptr<pybind11::object> held(new pybind11::object(callback),
                                               [](pybind11::object* object) {
                                                 pybind11::gil_scoped_acquire gil;
                                                 delete object;
                                               });
  return [held](const std::string& stage, double fraction) {
    pybind11::gil_scoped_acquire gil;
    const pybind11::object answer = (*held)(stage, fraction);
    if (answer.is_none()) return true;
    const int truth = PyObject_IsTrue(answer.ptr());
    if (truth < 0) throw pybind11::error_already_set();
    return truth == 1;
  };
}

}  // namespace modal_deform
