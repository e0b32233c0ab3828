// The element quantities of the discrete shells energy, each written once for any scalar type T
// (double, Dual<double, N> for Hessians, Dual<Dual<double, 1>, 1> for third derivatives):
// edge length, triangle area, dihedral angle.
//
// Each quantity s takes its K vertices relative to the first one, r = (x1 − x0, ..., x_{K−1} − x0)
// (3(K − 1) values), so it is exactly invariant under translation: ∂s/∂x_m = ∂s/∂r_m for m ≥ 1
// and ∂s/∂x0 = −Σ_m ∂s/∂r_m. A quantity provides
//   Frame<T> frame(r)              the intermediate vectors shared by value and gradient,
//   gradient(frame, g)             ∇s with respect to r (3(K − 1) values),
// and a measure of its value (for a hinge, cos θ and sin θ). Gradients divide by the element's
// size (length, normal): callers check the frame first (see discrete_shells.h for what a collapsed
// element does).
#pragma once

#include <array>
#include <cmath>

namespace modal_deform::shells {

template <typename T>
using Vec3 = std::array<T, 3>;

template <typename T>
Vec3<T> load3(const T* p) {
  return {p[0], p[1], p[2]};
}

template <typename T>
Vec3<T> cross(const Vec3<T>& a, const Vec3<T>& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

template <typename T>
T dot(const Vec3<T>& a, const Vec3<T>& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// ℓ = ‖x1 − x0‖; r = a = x1 − x0.
struct EdgeLength {
  static constexpr int kVertices = 2;

  template <typename T>
  struct Frame {
    Vec3<T> a;
    T length;  // ‖a‖
  };

  template <typename T>
  static Frame<T> frame(const T* r) {
    using std::sqrt;
    const Vec3<T> a = load3(r);
    return {a, sqrt(dot(a, a))};
  }

  template <typename T>
  static T measure(const Frame<T>& f) {
    return f.length;
  }

  // ∇ℓ = a / ‖a‖.
  template <typename T>
  static void gradient(const Frame<T>& f, T* g) {
    const T inverse_length = T(1.0) / f.length;
    for (int i = 0; i < 3; ++i) g[i] = f.a[i] * inverse_length;
  }
};

// A = ½‖(x1 − x0) × (x2 − x0)‖; r = (a, b) = (x1 − x0, x2 − x0).
struct TriangleArea {
  static constexpr int kVertices = 3;

  template <typename T>
  struct Frame {
    Vec3<T> a, b, n;  // n = a × b, twice the area times the unit normal
    T norm;           // ‖n‖ = 2A
  };

  template <typename T>
  static Frame<T> frame(const T* r) {
    using std::sqrt;
    const Vec3<T> a = load3(r), b = load3(r + 3);
    const Vec3<T> n = cross(a, b);
    return {a, b, n, sqrt(dot(n, n))};
  }

  template <typename T>
  static T measure(const Frame<T>& f) {
    return 0.5 * f.norm;
  }

  // With the unit normal u = n / ‖n‖: ∇_a A = ½ b × u, ∇_b A = ½ u × a.
  template <typename T>
  static void gradient(const Frame<T>& f, T* g) {
    const T half_inverse_norm = T(0.5) / f.norm;
    const Vec3<T> u{f.n[0] * half_inverse_norm, f.n[1] * half_inverse_norm,
                    f.n[2] * half_inverse_norm};
    const Vec3<T> ga = cross(f.b, u), gb = cross(u, f.a);
    for (int i = 0; i < 3; ++i) {
      g[i] = ga[i];
      g[3 + i] = gb[i];
    }
  }
};

// The dihedral angle θ of a hinge (x0, x1, x2, x3): the edge x0 → x1 as it runs in the first
// triangle (x0, x1, x2), x3 the opposite vertex of the second triangle. θ is the signed angle,
// about the edge, from the first triangle's normal n1 = a × b to n2 = c × a, the second
// triangle's normal oriented as if it ran x1 → x0 (so the faces' own orientations do not
// matter); θ = 0 when the hinge is flat. r = (a, b, c) = (x1 − x0, x2 − x0, x3 − x0).
//
// The energy needs θ only through cos θ and sin θ, taken from the unnormalised normals without
// any inverse trigonometric function: exact for every angle, including a hinge folded flat (±π).
struct DihedralAngle {
  static constexpr int kVertices = 4;

  template <typename T>
  struct Frame {
    Vec3<T> a, b, c, n1, n2;
    T aa, length, n1n1, n2n2;  // ‖a‖², ‖a‖, ‖n1‖², ‖n2‖²
    T inverse_product;         // 1 / (‖a‖²‖n1‖²‖n2‖²): the one division a hinge needs
  };

  template <typename T>
  static Frame<T> frame(const T* r) {
    using std::sqrt;
    Frame<T> f;
    f.a = load3(r);
    f.b = load3(r + 3);
    f.c = load3(r + 6);
    f.n1 = cross(f.a, f.b);
    f.n2 = cross(f.c, f.a);
    f.aa = dot(f.a, f.a);
    f.length = sqrt(f.aa);
    f.n1n1 = dot(f.n1, f.n1);
    f.n2n2 = dot(f.n2, f.n2);
    f.inverse_product = T(1.0) / (f.aa * f.n1n1 * f.n2n2);
    return f;
  }

  // (cos θ, sin θ): cos θ = n1·n2 / (‖n1‖‖n2‖), sin θ = (n1 × n2)·a / (‖n1‖‖n2‖‖a‖)
  // = −(n1·c) ‖a‖ / (‖n1‖‖n2‖), since n1 × n2 = −((a × b)·c) a.
  template <typename T>
  static std::array<T, 2> measure(const Frame<T>& f) {
    using std::sqrt;
    const T inverse = sqrt(f.inverse_product);  // 1 / (‖a‖‖n1‖‖n2‖)
    return {dot(f.n1, f.n2) * f.length * inverse, -(dot(f.n1, f.c) * f.aa * inverse)};
  }

  // The classic hinge gradient (e.g. Wardetzky et al. 2007, "Discrete quadratic curvature
  // energies"): the opposite vertices move θ along their triangle's normal,
  // ∇_b θ = −‖a‖ n1 / ‖n1‖², ∇_c θ = −‖a‖ n2 / ‖n2‖², and the edge's end x1 by the share
  // t_b = a·b / ‖a‖², t_c = a·c / ‖a‖² (where x2, x3 project onto the edge) of each:
  // ∇_a θ = −(t_b ∇_b θ + t_c ∇_c θ).
  template <typename T>
  static void gradient(const Frame<T>& f, T* g) {
    const T length_aa = f.length * f.aa * f.inverse_product;
    const T inverse_aa = f.n1n1 * f.n2n2 * f.inverse_product;
    const T sb = -(length_aa * f.n2n2), sc = -(length_aa * f.n1n1);
    const T tb = dot(f.a, f.b) * inverse_aa, tc = dot(f.a, f.c) * inverse_aa;
    for (int i = 0; i < 3; ++i) {
      const T gb = f.n1[i] * sb, gc = f.n2[i] * sc;
      g[i] = -(gb * tb + gc * tc);
      g[3 + i] = gb;
      g[6 + i] = gc;
    }
  }
};

}  // namespace modal_deform::shells
