// Lanes<L>: L doubles side by side, one per element, with the arithmetic the element quantities
// use (shell_elements.h: + − * / between lanes, * by a double, unary −, sqrt), so that code written
// once for a generic scalar evaluates L elements at once. Eigen's fixed-size arrays vectorise each
// operation (SSE2 or AVX packets) on every compiler; each lane is rounded exactly as a double is.
#pragma once

#include <Eigen/Core>

namespace modal_deform {

template <int L>
struct Lanes {
  using Values = Eigen::Array<double, L, 1>;
  Values v;

  Lanes() = default;
  explicit Lanes(double value) : v(Values::Constant(value)) {}
  explicit Lanes(const Values& values) : v(values) {}

  double operator[](int lane) const { return v[lane]; }
  double& operator[](int lane) { return v[lane]; }
};

template <int L>
Lanes<L> operator+(const Lanes<L>& a, const Lanes<L>& b) {
  return Lanes<L>(a.v + b.v);
}

template <int L>
Lanes<L> operator-(const Lanes<L>& a, const Lanes<L>& b) {
  return Lanes<L>(a.v - b.v);
}

template <int L>
Lanes<L> operator-(const Lanes<L>& a) {
  return Lanes<L>(-a.v);
}

template <int L>
Lanes<L> operator*(const Lanes<L>& a, const Lanes<L>& b) {
  return Lanes<L>(a.v * b.v);
}

template <int L>
Lanes<L> operator*(const Lanes<L>& a, double s) {
  return Lanes<L>(a.v * s);
}

template <int L>
Lanes<L> operator*(double s, const Lanes<L>& a) {
  return Lanes<L>(s * a.v);
}

template <int L>
Lanes<L> operator/(const Lanes<L>& a, const Lanes<L>& b) {
  return Lanes<L>(a.v / b.v);
}

template <int L>
Lanes<L> sqrt(const Lanes<L>& a) {
  return Lanes<L>(a.v.sqrt());
}

}  // namespace modal_deform
