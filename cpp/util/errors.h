// Errors the native core reports instead of crashing.
//
// InputError: the caller's data is wrong (becomes ValueError in Python); the message names the
// argument and the first offending index. NumericalError: a solver failed on valid input
// (becomes RuntimeError). OutOfMemory: not enough memory (becomes MemoryError). Cancelled: a
// progress callback asked to stop (becomes mdc.Cancelled).
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

namespace modal_deform {

struct InputError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

struct NumericalError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Not enough memory for a step (CHOLMOD out of memory, an allocation refused, or the bake's
// estimate above what is available): becomes mdc.OutOfMemoryError, a MemoryError. Kept apart from
// NumericalError so that a lack of memory never reads as a matrix that is not positive definite.
struct OutOfMemory : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Cancelled : std::runtime_error {
  Cancelled() : std::runtime_error("cancelled") {}
};

// Builds a message from streamable parts: throw InputError(message("F[", f, "] ..."));
template <typename... Parts>
std::string message(const Parts&... parts) {
  std::ostringstream out;
  (out << ... << parts);
  return out.str();
}

}  // namespace modal_deform
