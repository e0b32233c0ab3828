// Options and statistics across the boundary by the names of their tables (for_each_bake_option,
// for_each_full_solve_option, for_each_full_solve_stat, ...): the keyword arguments a binding
// takes, the defaults it exports and the dicts it returns, so that no name or default is written
// twice. Enumerations cross as their names.
#pragma once

#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>

#include "energy/make_energy.h"
#include "solve/shifted_newton.h"
#include "util/errors.h"

namespace modal_deform {

template <typename T>
pybind11::object to_python(const T& value) {
  return pybind11::cast(value);
}
inline pybind11::object to_python(EnergyKind kind) { return pybind11::str(energy_name(kind)); }
inline pybind11::object to_python(HessianModel model) { return pybind11::str(hessian_model_name(model)); }

template <typename T>
void from_python(pybind11::handle value, T& field) {
  field = value.cast<T>();
}
inline void from_python(pybind11::handle value, EnergyKind& kind) { kind = energy_kind(value.cast<std::string>()); }

// {name: value} of every field of `fields` that the table `for_each` names.
template <typename Fields, typename ForEach>
pybind11::dict to_dict(const Fields& fields, ForEach for_each) {
  pybind11::dict dict;
  for_each([&](const char* name, auto field) { dict[name] = to_python(field(fields)); });
  return dict;
}

// The defaults of an options struct: {name: value} of Options{}.
template <typename Options, typename ForEach>
pybind11::dict defaults(ForEach for_each) {
  return to_dict(Options{}, for_each);
}

// Options{} with the fields that `keywords` name set from them; throws InputError for a keyword
// that names no field of the table (`function` says whose).
template <typename Options, typename ForEach>
Options from_keywords(const pybind11::kwargs& keywords, ForEach for_each, const char* function) {
  Options options;
  size_t known = 0;
  for_each([&](const char* name, auto field) {
    if (!keywords.contains(name)) return;
    from_python(keywords[name], field(options));
    ++known;
  });
  if (known != keywords.size())
    for (const auto& item : keywords) {
      const auto key = item.first.cast<std::string>();
      bool named = false;
      for_each([&](const char* name, auto) { named = named || key == name; });
      if (!named) throw InputError(message(function, ": ", key, " is not an option"));
    }
  return options;
}

}  // namespace modal_deform
