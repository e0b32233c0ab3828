// Mathematical constants of the native core.
#pragma once

namespace modal_deform {

inline constexpr double kPi = 3.14159265358979323846;

}  // namespace modal_deform
