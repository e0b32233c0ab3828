// Options and statistics across the boundary by the names of their tables (for_each_bake_option,
// for_each_full_solve_option, for_each_full_solve_stat, ...): the keyword arguments a binding
// takes, the option tables it exports (name, default, range, doc: what the Python API builds its
// signatures from) and the dicts it returns, so that no name, default or limit is written twice.
// Enumerations cross as their names, empty arrays as None.
#pragma once

#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>
#include <type_traits>
#include <vector>

#include "energy/make_energy.h"
#include "solve/shifted_newton.h"
#include "util/errors.h"
#include "util/option.h"

namespace modal_deform {

inline const char* name_of(const char* name) { return name; }
inline const char* name_of(const Option& option) { return option.name; }

template <typename T>
pybind11::object to_python(const T& value) {
  return pybind11::cast(value);
}
inline pybind11::object to_python(EnergyKind kind) { return pybind11::str(energy_name(kind)); }
inline pybind11::object to_python(HessianModel model) {
  return pybind11::str(hessian_model_name(model));
}

// What a value of type T is called in messages and in the exported tables.
template <typename T>
const char* kind_name() {
  if constexpr (std::is_same_v<T, bool>)
    return "bool";
  else if constexpr (std::is_integral_v<T>)
    return "int";
  else if constexpr (std::is_floating_point_v<T>)
    return "float";
  else if constexpr (std::is_same_v<T, EnergyKind>)
    return "energy";
  else
    return "array";
}

// An array option's value: None is an empty array.
template <typename T>
constexpr bool kIsArray = !std::is_arithmetic_v<T> && !std::is_same_v<T, EnergyKind>;

// `field` from a Python value; throws InputError naming the option for a value of another type
// (a float for an int, a string for a number, a number for a flag).
template <typename T>
void from_python(pybind11::handle value, T& field, const char* name) {
  if constexpr (kIsArray<T>) {
    if (value.is_none()) {
      field = T();
      return;
    }
  }
  if constexpr (std::is_same_v<T, EnergyKind>) {
    if (!pybind11::isinstance<pybind11::str>(value))
      throw InputError(message(name, ": expected \"shells\" or \"arap\", got ",
                               pybind11::repr(value).cast<std::string>()));
    field = energy_kind(value.cast<std::string>());
    return;
  } else {
    // A flag takes only True or False (numpy's too); an integer only what has __index__ (no float
    // of any kind, which pybind11 would truncate) and no flag.
    const std::string type = pybind11::str(value.get_type().attr("__name__"));
    const bool flag = type == "bool" || type == "bool_";
    bool fits = true;
    if constexpr (std::is_same_v<T, bool>)
      fits = flag;
    else if constexpr (std::is_integral_v<T>)
      fits = !flag && PyIndex_Check(value.ptr());
    else if constexpr (std::is_arithmetic_v<T>)
      fits = !flag && !pybind11::isinstance<pybind11::str>(value);
    try {
      if (fits) {
        field = value.cast<T>();
        return;
      }
    } catch (const pybind11::cast_error&) {
    } catch (const pybind11::error_already_set&) {
    }
    const std::string expected = std::is_same_v<T, bool>       ? "True or False"
                                 : std::is_integral_v<T>       ? "an integer"
                                 : std::is_floating_point_v<T> ? "a number"
                                                               : "an array of numbers, or None";
    throw InputError(message(name, ": expected ", expected, ", got ",
                             pybind11::repr(value).cast<std::string>()));
  }
}

// {name: value} of every field of `fields` that the table `for_each` names.
template <typename Fields, typename ForEach>
pybind11::dict to_dict(const Fields& fields, ForEach for_each) {
  pybind11::dict dict;
  for_each([&](const auto& name, auto field) { dict[name_of(name)] = to_python(field(fields)); });
  return dict;
}

// The record of one option with its default, as the Python API reads it (core/_options.py):
// {name, default (None for an empty array), kind, doc, min, max, min_open, max_open}.
template <typename T>
pybind11::dict option_record(const Option& option, const T& default_value) {
  pybind11::object value = to_python(default_value);
  if constexpr (kIsArray<T>) value = pybind11::none();
  return pybind11::dict(pybind11::arg("name") = option.name, pybind11::arg("default") = value,
                        pybind11::arg("kind") = kind_name<T>(), pybind11::arg("doc") = option.doc,
                        pybind11::arg("min") = option.range.min,
                        pybind11::arg("max") = option.range.max,
                        pybind11::arg("min_open") = option.range.min_open,
                        pybind11::arg("max_open") = option.range.max_open);
}

// The table of Options{}: one option_record per option, in the table's order.
template <typename Options, typename ForEach>
pybind11::list option_table(ForEach for_each) {
  const Options defaults{};
  pybind11::list table;
  for_each([&](const Option& option, auto field) {
    table.append(option_record(option, field(defaults)));
  });
  return table;
}

// Options{} with the fields that `keywords` name set from them; throws InputError for a keyword
// that names no field of the table (`function` says whose) or a value of the wrong type.
template <typename Options, typename ForEach>
Options from_keywords(const pybind11::kwargs& keywords, ForEach for_each, const char* function) {
  Options options;
  size_t known = 0;
  for_each([&](const Option& option, auto field) {
    if (!keywords.contains(option.name)) return;
    from_python(keywords[option.name], field(options), option.name);
    ++known;
  });
  if (known != keywords.size())
    for (const auto& item : keywords) {
      const auto key = item.first.cast<std::string>();
      bool named = false;
      for_each([&](const Option& option, auto) { named = named || key == option.name; });
      if (!named) throw InputError(message(function, ": ", key, " is not an option"));
    }
  return options;
}

}  // namespace modal_deform
