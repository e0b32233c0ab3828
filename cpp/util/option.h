// An option of the core as its tables declare it once (for_each_bake_option, ...): the keyword
// the Python API takes, what it means and the values it accepts. The bindings export the tables
// (named_fields.h), the Python API builds its signatures and docstrings from them and the add-on
// its properties' defaults, limits and tooltips; check_option refuses a value out of range.
#pragma once

#include <limits>
#include <type_traits>

#include "util/errors.h"

namespace modal_deform {

// The values a numeric option accepts: an interval, each end closed or open (infinite: no bound).
struct Range {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = false;
  bool max_open = false;

  bool contains(double value) const {
    return (min_open ? value > min : value >= min) && (max_open ? value < max : value <= max);
  }
};

constexpr Range any_value() { return {}; }
constexpr Range at_least(double min) {
  return {min, std::numeric_limits<double>::infinity(), false, false};
}
constexpr Range closed(double min, double max) { return {min, max, false, false}; }
// (min, max]
constexpr Range above_up_to(double min, double max) { return {min, max, true, false}; }
// (min, max)
constexpr Range between_open(double min, double max) { return {min, max, true, true}; }

struct Option {
  const char* name;
  const char* doc;  // one or two sentences, the Python API's and the tooltips' source
  Range range = {};
};

// Throws InputError naming the option when `value` (a number) is outside its range (NaN is).
template <typename T>
void check_option(const Option& option, const T& value) {
  if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
    const Range& r = option.range;
    if (r.contains(static_cast<double>(value))) return;
    const bool bounded_below = r.min > -std::numeric_limits<double>::infinity();
    const bool bounded_above = r.max < std::numeric_limits<double>::infinity();
    if (bounded_below && !bounded_above)
      throw InputError(message(option.name, ": expected ", r.min_open ? "more than " : "at least ",
                               r.min, ", got ", value));
    if (!bounded_below && bounded_above)
      throw InputError(message(option.name, ": expected ", r.max_open ? "less than " : "at most ",
                               r.max, ", got ", value));
    throw InputError(message(option.name, ": expected a value in ", r.min_open ? "(" : "[", r.min,
                             ", ", r.max, r.max_open ? ")" : "]", ", got ", value));
  }
}

// check_option for every option of a table (visit(option, accessor), as for_each_bake_option).
template <typename Options, typename ForEach>
void check_options(const Options& options, ForEach for_each) {
  for_each([&](const Option& option, auto field) { check_option(option, field(options)); });
}

}  // namespace modal_deform
