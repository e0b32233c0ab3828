// Forward-mode dual numbers: exact derivatives of code written once for a generic scalar.
//
// Dual<T, N> carries a value and its derivatives along N directions. Evaluating a gradient
// with Dual<double, N> (one direction per input) gives the Hessian; nesting,
// Dual<Dual<double, 1>, 1>, gives a hyper-dual number whose mixed part is a second directional
// derivative (for the third derivative of an energy, the gradient's second derivative along u
// and w). Only what the element quantities use is defined: + − * / between duals, * by a
// double, unary −, sqrt.
#pragma once

#include <array>
#include <cmath>

namespace modal_deform {

template <typename T, int N>
struct Dual {
  T v{};                 // value
  std::array<T, N> d{};  // derivative along each direction

  Dual() = default;
  explicit Dual(double value) : v(value) {}

  Dual& operator+=(const Dual& b) {
    v += b.v;
    for (int i = 0; i < N; ++i) d[i] += b.d[i];
    return *this;
  }
  Dual& operator-=(const Dual& b) {
    v -= b.v;
    for (int i = 0; i < N; ++i) d[i] -= b.d[i];
    return *this;
  }
};

template <typename T, int N>
Dual<T, N> operator-(const Dual<T, N>& a) {
  Dual<T, N> r;
  r.v = -a.v;
  for (int i = 0; i < N; ++i) r.d[i] = -a.d[i];
  return r;
}

template <typename T, int N>
Dual<T, N> operator+(Dual<T, N> a, const Dual<T, N>& b) {
  return a += b;
}

template <typename T, int N>
Dual<T, N> operator-(Dual<T, N> a, const Dual<T, N>& b) {
  return a -= b;
}

template <typename T, int N>
Dual<T, N> operator*(const Dual<T, N>& a, const Dual<T, N>& b) {
  Dual<T, N> r;
  r.v = a.v * b.v;
  for (int i = 0; i < N; ++i) r.d[i] = a.d[i] * b.v + a.v * b.d[i];
  return r;
}

template <typename T, int N>
Dual<T, N> operator*(const Dual<T, N>& a, double s) {
  Dual<T, N> r;
  r.v = a.v * s;
  for (int i = 0; i < N; ++i) r.d[i] = a.d[i] * s;
  return r;
}

template <typename T, int N>
Dual<T, N> operator*(double s, const Dual<T, N>& a) {
  return a * s;
}

template <typename T, int N>
Dual<T, N> operator/(const Dual<T, N>& a, const Dual<T, N>& b) {
  const T inverse = T(1.0) / b.v;
  Dual<T, N> r;
  r.v = a.v * inverse;
  for (int i = 0; i < N; ++i) r.d[i] = (a.d[i] - r.v * b.d[i]) * inverse;
  return r;
}

template <typename T, int N>
Dual<T, N> sqrt(const Dual<T, N>& a) {
  using std::sqrt;
  Dual<T, N> r;
  r.v = sqrt(a.v);
  const T half_inverse = T(0.5) / r.v;
  for (int i = 0; i < N; ++i) r.d[i] = a.d[i] * half_inverse;
  return r;
}

// The plain value of a scalar, dual or not (to branch on it).
inline double value_of(double a) { return a; }

template <typename T, int N>
double value_of(const Dual<T, N>& a) {
  return value_of(a.v);
}

}  // namespace modal_deform
