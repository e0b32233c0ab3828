#include "energy/discrete_shells.h"

#include <omp.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <type_traits>

#include "energy/dual.h"
#include "energy/lanes.h"
#include "mesh/mesh_check.h"
#include "mesh/mesh_topology.h"
#include "mesh/normalization.h"
#include "util/errors.h"
#include "util/parallel_for.h"
#include "util/require_positions.h"
#include "util/require_weight.h"

namespace modal_deform {
namespace {

using shells::DihedralAngle;
using shells::EdgeLength;
using shells::EdgeTerm;
using shells::HingeTerm;
using shells::TriangleArea;
using shells::TriangleTerm;

// Below this fraction of its rest size an element counts as collapsed (see the header).
constexpr double kCollapse = kDegenerateAreaRatio;

// Rest stiffness w ‖∇s‖² of a bending or area term on equilateral triangles (per unit α or β):
// a hinge of edge ē, w = 2√3, ‖∇θ‖² = 16 / (3 ē²); a triangle, w ‖∇A‖² = Σ ē² / (4 Ā) = √3.
double equilateral_hinge_stiffness(double edge_squared) {
  return 32 / (std::sqrt(3.0) * edge_squared);
}
constexpr double kEquilateralTriangleStiffness = 1.7320508075688772;

template <typename Term>
constexpr int kVerticesOf = Term::Quantity::kVertices;
// A term's coordinates relative to its first vertex (shell_elements.h).
template <typename Term>
constexpr int kDofsOf = 3 * (kVerticesOf<Term> - 1);

// A term's f and its derivatives with respect to s at the current s (the weight included), and
// whether s is differentiable there. For a faded hinge (header) s is the whole term itself:
// f = s, f' = 1, and gradients of s are those of the term (gradient_of).
struct Response {
  double f = 0, df = 0, d2f = 0, d3f = 0;
  bool differentiable = false;
  bool faded = false;
};

// f(s) = ½ w (s − s̄)² and f'(s) (any scalar).
template <typename T>
std::array<T, 2> quadratic_and_slope(const T& s, const T& rest, const T& weight) {
  const T d = s - rest;
  return {0.5 * weight * d * d, weight * d};
}

Response quadratic(double s, double rest, double weight, bool differentiable) {
  const auto [f, df] = quadratic_and_slope(s, rest, weight);
  return {f, df, weight, 0.0, differentiable};
}

bool differentiable(const EdgeTerm& term, double length) { return length > term.collapsed_length; }
bool differentiable(const TriangleTerm& term, double norm) { return norm > term.collapsed_norm; }

Response respond(const EdgeTerm& term, const EdgeLength::Frame<double>& frame) {
  return quadratic(EdgeLength::measure(frame), term.rest_length, term.weight,
                   differentiable(term, frame.length));
}

Response respond(const TriangleTerm& term, const TriangleArea::Frame<double>& frame) {
  return quadratic(TriangleArea::measure(frame), term.rest_area, term.weight,
                   differentiable(term, frame.norm));
}

// The hinge fade (header): φ(t) and φ'(t) for t = ‖n‖² / ‖n̄‖², the quintic smoothstep in
// u = t / kHingeFade², 1 from u = 1 on.
template <typename T>
struct Fade {
  T value, slope;
};

constexpr double kFadeEnd = kHingeFade * kHingeFade;

template <typename T>
Fade<T> fade(const T& t) {
  if (value_of(t) >= kFadeEnd) return {T(1.0), T(0.0)};
  const T u = t * (1 / kFadeEnd);
  const T uu = u * u, rest = T(1.0) - u;
  return {uu * u * (T(10.0) + u * (T(-15.0) + u * 6.0)), uu * rest * rest * (30 / kFadeEnd)};
}

// Below this t a triangle of a hinge counts as collapsed (the header's 1e-12 of its rest area).
constexpr double kCollapsedNormRatio = kCollapse * kCollapse;

bool hinge_collapsed(const HingeTerm& term, double n1n1, double n2n2) {
  return n1n1 <= kCollapsedNormRatio * term.rest_n1n1 ||
         n2n2 <= kCollapsedNormRatio * term.rest_n2n2;
}

bool hinge_faded(const HingeTerm& term, double n1n1, double n2n2) {
  return n1n1 < kFadeEnd * term.rest_n1n1 || n2n2 < kFadeEnd * term.rest_n2n2;
}

// ½ w (2 sin(δ/2))² = ½ w ‖(cos θ, sin θ) − (cos θ̄, sin θ̄)‖², the unfaded bending term, and
// w sin δ, its derivative in θ, from cos θ and sin θ (any scalar T) and the rest's cos θ̄, sin θ̄
// and w (doubles, or lanes as T is).
template <typename T, typename C>
std::array<T, 2> bending_and_slope(const T& cos_theta, const T& sin_theta, const C& cos_rest,
                                   const C& sin_rest, const C& weight) {
  const T dc = cos_theta - T(cos_rest), ds = sin_theta - T(sin_rest);
  return {(dc * dc + ds * ds) * (0.5 * weight),
          (sin_theta * cos_rest - cos_theta * sin_rest) * weight};
}

template <typename T>
std::array<T, 2> bending_and_slope(const HingeTerm& term, const DihedralAngle::Frame<T>& f) {
  const auto [cos_theta, sin_theta] = DihedralAngle::measure(f);
  return bending_and_slope(cos_theta, sin_theta, term.cos_rest, term.sin_rest, term.weight);
}

// The gradient of a faded hinge's whole term b(θ) φ(t1) φ(t2) over r = (a, b, c):
// φ1 φ2 b'(θ) ∇θ + b (φ1' φ2 ∇t1 + φ1 φ2' ∇t2), with ∇_a ‖n1‖² = 2 b × n1, ∇_b ‖n1‖² = 2 n1 × a,
// ∇_c ‖n2‖² = 2 a × n2, ∇_a ‖n2‖² = 2 n2 × c (n1 = a × b, n2 = c × a).
template <typename T>
void faded_hinge_gradient(const HingeTerm& term, const DihedralAngle::Frame<T>& f, T* g) {
  const auto [bending, slope] = bending_and_slope(term, f);
  const Fade<T> fade1 = fade(f.n1n1 * (1 / term.rest_n1n1)),
                fade2 = fade(f.n2n2 * (1 / term.rest_n2n2));
  DihedralAngle::gradient(f, g);
  const T along_theta = fade1.value * fade2.value * slope;
  const T c1 = bending * fade1.slope * fade2.value * (2 / term.rest_n1n1);
  const T c2 = bending * fade1.value * fade2.slope * (2 / term.rest_n2n2);
  using shells::cross;
  const shells::Vec3<T> a_from_n1 = cross(f.b, f.n1), b_from_n1 = cross(f.n1, f.a);
  const shells::Vec3<T> a_from_n2 = cross(f.n2, f.c), c_from_n2 = cross(f.a, f.n2);
  for (int i = 0; i < 3; ++i) {
    g[i] = g[i] * along_theta + c1 * a_from_n1[i] + c2 * a_from_n2[i];
    g[3 + i] = g[3 + i] * along_theta + c1 * b_from_n1[i];
    g[6 + i] = g[6 + i] * along_theta + c2 * c_from_n2[i];
  }
}

// f(θ) = ½ w (2 sin(δ/2))², δ = θ − θ̄. The factor (2 sin(δ/2))² is the squared distance
// between the points (cos θ, sin θ) and (cos θ̄, sin θ̄) of the unit circle: no cancellation at
// small δ, exactly 0 at rest. The derivatives in δ use the angle-difference formulas. This is
// the term where neither triangle is crushed (hinge_faded false).
Response unfaded_respond(const HingeTerm& term, const DihedralAngle::Frame<double>& frame) {
  const auto [cos_theta, sin_theta] = DihedralAngle::measure(frame);
  const auto [bending, slope] =
      bending_and_slope(cos_theta, sin_theta, term.cos_rest, term.sin_rest, term.weight);
  const double cos_delta = cos_theta * term.cos_rest + sin_theta * term.sin_rest;
  return {bending, slope, term.weight * cos_delta, -slope, true};
}

// A crushed triangle fades the bending term out (header); a collapsed one leaves nothing.
Response respond(const HingeTerm& term, const DihedralAngle::Frame<double>& frame) {
  if (hinge_collapsed(term, frame.n1n1, frame.n2n2)) return {};
  if (hinge_faded(term, frame.n1n1, frame.n2n2)) {
    const double faded = bending_and_slope(term, frame)[0] *
                         fade(frame.n1n1 / term.rest_n1n1).value *
                         fade(frame.n2n2 / term.rest_n2n2).value;
    return {faded, 1.0, 0.0, 0.0, true, true};
  }
  return unfaded_respond(term, frame);
}

// ∇s at `frame`: the element quantity's, or a faded hinge's whole term's (Response::faded).
template <typename Term, typename T>
void gradient_of(const Term& term, bool faded,
                 const typename Term::Quantity::template Frame<T>& frame, T* g) {
  if constexpr (std::is_same_v<Term, HingeTerm>) {
    if (faded) return faded_hinge_gradient(term, frame, g);
  }
  Term::Quantity::gradient(frame, g);
}

// r = (y_{v1} − y_{v0}, ..., y_{v_{K−1}} − y_{v0}) for the term's vertices v, y a flat 3n array.
template <typename Term>
void relative(const Term& term, const double* y, double* r) {
  const double* origin = y + 3 * term.vertices[0];
  for (int m = 1; m < kVerticesOf<Term>; ++m)
    for (int i = 0; i < 3; ++i) r[3 * (m - 1) + i] = y[3 * term.vertices[m] + i] - origin[i];
}

template <typename Term>
Response respond_at(const Term& term, const double* x, double* r) {
  relative(term, x, r);
  return respond(term, Term::Quantity::frame(r));
}

template <int N>
double dot(const double* a, const double* b) {
  double sum = 0;
  for (int i = 0; i < N; ++i) sum += a[i] * b[i];
  return sum;
}

// A vector over the relative coordinates as one over the K vertices: the first vertex gets
// minus the sum of the others (translation invariance).
template <int K>
void to_vertices(const double* rel, double* full) {
  for (int i = 0; i < 3; ++i) full[i] = 0;
  for (int m = 1; m < K; ++m)
    for (int i = 0; i < 3; ++i) {
      full[3 * m + i] = rel[3 * (m - 1) + i];
      full[i] -= rel[3 * (m - 1) + i];
    }
}

// ‖∇s‖² over all of a term's vertices (s of shell_elements.h at `frame`).
template <typename Term>
double squared_gradient_norm(const typename Term::Quantity::template Frame<double>& frame) {
  constexpr int K = kVerticesOf<Term>;
  double g[kDofsOf<Term>], full[3 * K];
  Term::Quantity::gradient(frame, g);
  to_vertices<K>(g, full);
  return dot<3 * K>(full, full);
}

// The weight w of a term, lowered where needed so that its rest stiffness w ‖∇s‖² stays within
// kMaxStiffnessRatio of `reference`, the stiffness of the same term on well-shaped triangles.
double bounded_weight(double weight, double squared_gradient, double reference) {
  return std::min(weight, kMaxStiffnessRatio * reference / squared_gradient);
}

// Every vertex, as a single part owns them: a VertexPartition::Range whose test is free.
struct AllVertices {
  static constexpr bool contains(int) { return true; }
};

// out[3v + i] += full[3m + i] for the term's vertices v = vertices[m] in `owned` (a
// VertexPartition::Range or AllVertices).
template <typename Term, typename Owned>
void add_owned(const Term& term, const double* full, Owned owned, double* out) {
  for (int m = 0; m < kVerticesOf<Term>; ++m) {
    const int v = term.vertices[m];
    if (!owned.contains(v)) continue;
    for (int i = 0; i < 3; ++i) out[3 * v + i] += full[3 * m + i];
  }
}

// Adds w f'(s) ∇s of `term` at x to `out` for its vertices in `owned`; returns w f(s).
template <typename Term, typename Owned>
double add_gradient(const Term& term, const double* x, Owned owned, double* out) {
  constexpr int K = kVerticesOf<Term>, N = kDofsOf<Term>;
  double r[N];
  relative(term, x, r);
  const auto frame = Term::Quantity::frame(r);
  const Response q = respond(term, frame);
  if (q.differentiable && q.df != 0) {
    double g[N], full[3 * K];
    gradient_of(term, q.faded, frame, g);
    for (double& gi : g) gi *= q.df;
    to_vertices<K>(g, full);
    add_owned(term, full, owned, out);
  }
  return q.f;
}

// Terms that add_gradients_in_lanes evaluates at once: one SSE2 packet of doubles, the wheel's
// baseline (4, two packets, are slower).
constexpr int kLanes = 2;
using TermLanes = Lanes<kLanes>;

// A field of kLanes consecutive terms, side by side.
template <typename Term>
TermLanes lanes_of(const Term* terms, double Term::* field) {
  TermLanes lanes;
  for (int l = 0; l < kLanes; ++l) lanes[l] = terms[l].*field;
  return lanes;
}

// w f(s) and w f'(s) of kLanes terms in their usual state (in_usual_state): an edge or a triangle
// not collapsed, a hinge not faded.
std::array<TermLanes, 2> usual_value_and_slope(const EdgeTerm* terms,
                                               const EdgeLength::Frame<TermLanes>& frame) {
  return quadratic_and_slope(EdgeLength::measure(frame), lanes_of(terms, &EdgeTerm::rest_length),
                             lanes_of(terms, &EdgeTerm::weight));
}
std::array<TermLanes, 2> usual_value_and_slope(const TriangleTerm* terms,
                                               const TriangleArea::Frame<TermLanes>& frame) {
  return quadratic_and_slope(TriangleArea::measure(frame),
                             lanes_of(terms, &TriangleTerm::rest_area),
                             lanes_of(terms, &TriangleTerm::weight));
}
std::array<TermLanes, 2> usual_value_and_slope(const HingeTerm* terms,
                                               const DihedralAngle::Frame<TermLanes>& frame) {
  const auto [cos_theta, sin_theta] = DihedralAngle::measure(frame);
  return bending_and_slope(cos_theta, sin_theta, lanes_of(terms, &HingeTerm::cos_rest),
                           lanes_of(terms, &HingeTerm::sin_rest),
                           lanes_of(terms, &HingeTerm::weight));
}

bool in_usual_state(const EdgeTerm& term, const EdgeLength::Frame<TermLanes>& frame, int lane) {
  return differentiable(term, frame.length[lane]);
}
bool in_usual_state(const TriangleTerm& term, const TriangleArea::Frame<TermLanes>& frame,
                    int lane) {
  return differentiable(term, frame.norm[lane]);
}
bool in_usual_state(const HingeTerm& term, const DihedralAngle::Frame<TermLanes>& frame, int lane) {
  return !hinge_faded(term, frame.n1n1[lane], frame.n2n2[lane]);  // a collapsed hinge is faded too
}

// Terms per chunk of add_gradients_in_lanes: all are evaluated before any is added to the
// gradient, so that their evaluations, independent of each other, overlap in the processor.
constexpr int kChunk = 16 * kLanes;

// add_gradient over all `terms` in order, every vertex owned, their values added to `energy`: the
// same sums, bit for bit, chunk by chunk. A chunk's terms are evaluated kLanes at a time, their
// frames, usual values, slopes and gradients at once (lanes.h), then added to `out` term by term;
// a term not in its usual state and the last terms go through add_gradient.
template <typename Term>
void add_gradients_in_lanes(const std::vector<Term>& terms, const double* x, double* out,
                            double& energy) {
  constexpr int K = kVerticesOf<Term>, N = kDofsOf<Term>, kGroups = kChunk / kLanes;
  const AllVertices all;
  const size_t count = terms.size(), whole = count - count % kLanes;
  for (size_t first = 0; first < whole; first += kChunk) {
    const Term* chunk = terms.data() + first;
    const int size = static_cast<int>(std::min<size_t>(kChunk, whole - first));
    TermLanes g[kGroups][N], f[kGroups], df[kGroups];
    bool usual[kChunk];
    for (int k = 0; k < size / kLanes; ++k) {
      const Term* group = chunk + k * kLanes;
      TermLanes r[N];
      for (int l = 0; l < kLanes; ++l) {
        double rl[N];
        relative(group[l], x, rl);
        for (int i = 0; i < N; ++i) r[i][l] = rl[i];
      }
      const auto frame = Term::Quantity::frame(r);
      const auto [value, slope] = usual_value_and_slope(group, frame);
      f[k] = value;
      df[k] = slope;
      Term::Quantity::gradient(frame, g[k]);
      for (TermLanes& gi : g[k]) gi = gi * df[k];
      for (int l = 0; l < kLanes; ++l) usual[k * kLanes + l] = in_usual_state(group[l], frame, l);
    }
    for (int e = 0; e < size; ++e) {
      const int k = e / kLanes, l = e % kLanes;
      if (!usual[e]) {
        energy += add_gradient(chunk[e], x, all, out);
        continue;
      }
      energy += f[k][l];
      if (df[k][l] == 0) continue;
      double gl[N], full[3 * K];
      for (int i = 0; i < N; ++i) gl[i] = g[k][i][l];
      to_vertices<K>(gl, full);
      add_owned(chunk[e], full, all, out);
    }
  }
  for (size_t e = whole; e < count; ++e) energy += add_gradient(terms[e], x, all, out);
}

// Calls visit(term, index) for the terms of `set` that `part` visits, in order.
template <typename Term, typename Visit>
void visit_part(const shells::TermSet<Term>& set, int part, Visit& visit) {
  if (set.by_part.empty()) {  // a single part visits every term
    for (int e = 0; e < static_cast<int>(set.terms.size()); ++e) visit(set.terms[e], e);
  } else {
    for (int e : set.by_part[part]) visit(set.terms[e], e);
  }
}

// ∇s and ∇²s (N by N, symmetrised, row-major) at r (s as gradient_of takes it): the gradient
// evaluated on dual numbers with one direction per coordinate.
template <typename Term, int N = kDofsOf<Term>>
void second_derivatives(const Term& term, bool faded, const double* r, double* gradient,
                        double* hessian) {
  using D = Dual<double, N>;
  D rd[N], g[N];
  for (int i = 0; i < N; ++i) {
    rd[i].v = r[i];
    rd[i].d[i] = 1.0;
  }
  gradient_of(term, faded, Term::Quantity::frame(rd), g);
  for (int i = 0; i < N; ++i) {
    gradient[i] = g[i].v;
    for (int j = 0; j < N; ++j) hessian[i * N + j] = 0.5 * (g[i].d[j] + g[j].d[i]);
  }
}

// ∇s, ∇²s u, ∇²s w and ∇³s(u, w) at r: the gradient evaluated on hyper-dual numbers
// r + ε1 u + ε2 w, read off at 1, ε2, ε1 and ε1ε2.
template <typename Term, int N = kDofsOf<Term>>
void third_derivatives(const Term& term, bool faded, const double* r, const double* u,
                       const double* w, double* gradient, double* hu, double* hw, double* tuw) {
  using H = Dual<Dual<double, 1>, 1>;
  H rh[N], g[N];
  for (int i = 0; i < N; ++i) {
    rh[i].v.v = r[i];
    rh[i].v.d[0] = w[i];
    rh[i].d[0].v = u[i];
  }
  gradient_of(term, faded, Term::Quantity::frame(rh), g);
  for (int i = 0; i < N; ++i) {
    gradient[i] = g[i].v.v;
    hw[i] = g[i].v.d[0];
    hu[i] = g[i].d[0].v;
    tuw[i] = g[i].d[0].d[0];
  }
}

// ∇³(w f(s))(u, w) in relative coordinates (the formula in the header); tuw = ∇³s(u, w) is
// only read when f' ≠ 0.
template <int N>
void third_of_term(const Response& q, const double* gradient, const double* hu, const double* hw,
                   const double* u, const double* w, const double* tuw, double* out) {
  const double su = dot<N>(gradient, u), sw = dot<N>(gradient, w);
  const double along_gradient = q.d3f * su * sw + q.d2f * dot<N>(u, hw);
  for (int i = 0; i < N; ++i)
    out[i] = along_gradient * gradient[i] + q.d2f * (su * hw[i] + sw * hu[i]);
  if (q.df != 0)
    for (int i = 0; i < N; ++i) out[i] += q.df * tuw[i];
}

// The N by N block at `full` + offset (row stride M) replaced by its projection onto the positive
// semidefinite matrices: V max(Λ, 0) Vᵀ. Exactly symmetric.
template <int N, int M>
void project_block(double* block) {
  Eigen::Matrix<double, N, N> A;
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j) A(i, j) = block[i * M + j];
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> eigen(A);
  if (eigen.eigenvalues()(0) >= 0) return;
  const auto& V = eigen.eigenvectors();
  A = V * eigen.eigenvalues().cwiseMax(0).asDiagonal() * V.transpose();
  for (int i = 0; i < N; ++i)
    for (int j = 0; j <= i; ++j) block[i * M + j] = block[j * M + i] = 0.5 * (A(i, j) + A(j, i));
}

// How ∇²(w f(s)) = f'' ∇s∇sᵀ + f' ∇²s enters the Hessian: the coefficients of ∇s∇sᵀ and ∇²s, and
// whether the block they make must still be projected onto the semidefinite matrices.
struct BlockCoefficients {
  double d2f, df;
  bool project;
};

// The exact block, or with `semidefinite` a positive semidefinite stand-in for it:
// - an edge's length ℓ has ∇²ℓ = (I − êêᵀ)/ℓ, semidefinite with ∇ℓ = ê in its kernel: f''∇ℓ∇ℓᵀ and
//   f'∇²ℓ are the block's eigenspaces, and projecting clamps f'' and f' at 0 (no eigensolver);
// - a hinge whose bending term is convex in θ there (f'' > 0: bent less than 90° from rest) takes
//   the Gauss–Newton block f''∇θ∇θᵀ. Its exact block is always indefinite away from rest (θ does
//   not change as the hinge is scaled, so ∇²θ couples the scaling to ∇θ), and the projection of
//   f'∇²θ keeps positive curvature that holds the mesh back (Newton takes several times the
//   iterations to the same minimum) and its 9 by 9 eigendecompositions would be most of the
//   assembly;
// - every other block is projected: its negative eigenvalues set to 0.
template <int K>
BlockCoefficients block_coefficients(const Response& q, bool semidefinite) {
  if (!semidefinite) return {q.d2f, q.df, false};
  if (K == 2) return {std::max(q.d2f, 0.0), std::max(q.df, 0.0), false};
  if (K == 4 && !q.faded && q.d2f > 0) return {q.d2f, 0.0, false};
  // Without the f' term the block is f'' ∇s∇sᵀ: semidefinite unless f'' < 0.
  return {q.d2f, q.df, q.df != 0 || q.d2f < 0};
}

// The block k.d2f ∇s∇sᵀ + k.df ∇²s over the relative coordinates (N by N), projected onto the
// positive semidefinite matrices when k.project, expanded to the 3K by 3K Hessian over the term's
// vertices (row-major). ∇²s is only read when k.df ≠ 0.
template <int K>
void term_hessian(const BlockCoefficients& k, const double* gradient, const double* hessian,
                  double* full) {
  constexpr int N = 3 * (K - 1), M = 3 * K;
  // Written so that the result is exactly symmetric (the assembled Hessian then is too).
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j) full[(3 + i) * M + 3 + j] = k.d2f * (gradient[i] * gradient[j]);
  if (k.df != 0)
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < N; ++j) full[(3 + i) * M + 3 + j] += k.df * hessian[i * N + j];
  if (k.project) project_block<N, M>(full + 3 * M + 3);
  // The first vertex's columns, then its rows: minus the sums over the other vertices.
  for (int i = 3; i < M; ++i)
    for (int c = 0; c < 3; ++c) {
      double sum = 0;
      for (int m = 1; m < K; ++m) sum += full[i * M + 3 * m + c];
      full[i * M + c] = -sum;
    }
  for (int c = 0; c < 3; ++c)
    for (int j = 0; j < M; ++j) {
      double sum = 0;
      for (int m = 1; m < K; ++m) sum += full[(3 * m + c) * M + j];
      full[c * M + j] = -sum;
    }
  for (int c = 0; c < 3; ++c)
    for (int d = 0; d < c; ++d)
      full[c * M + d] = full[d * M + c] = 0.5 * (full[c * M + d] + full[d * M + c]);
}

template <typename Term>
void add_vertex_pairs(const std::vector<Term>& terms, std::vector<std::array<int, 2>>& pairs) {
  for (const Term& term : terms)
    for (int p = 0; p < kVerticesOf<Term>; ++p)
      for (int q = p + 1; q < kVerticesOf<Term>; ++q)
        if (term.vertices[p] != term.vertices[q])
          pairs.push_back({term.vertices[p], term.vertices[q]});
}

template <typename Term>
void finish_set(shells::TermSet<Term>& set, const BlockSparsity& sparsity,
                const VertexPartition& partition) {
  constexpr int K = kVerticesOf<Term>;
  // In the order of their smallest vertex, so that sweeps move through the outputs in order: a
  // stable counting sort, linear (a comparison sort found each term's smallest vertex again for
  // every comparison).
  const auto smallest = [](const Term& term) {
    return *std::min_element(term.vertices.begin(), term.vertices.end());
  };
  std::vector<int> start(static_cast<size_t>(sparsity.num_vertices()) + 1, 0);
  for (const Term& term : set.terms) ++start[smallest(term) + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<Term> sorted(set.terms.size());
  for (const Term& term : set.terms) sorted[start[smallest(term)]++] = term;
  set.terms = std::move(sorted);
  // Each term's lookups are its own: in parallel, in chunks of terms.
  constexpr size_t kChunk = 4096;
  set.block_offsets.resize(set.terms.size());
  parallel_for((set.terms.size() + kChunk - 1) / kChunk, [&](size_t chunk) {
    for (size_t e = chunk * kChunk; e < std::min(set.terms.size(), (chunk + 1) * kChunk); ++e)
      for (int p = 0; p < K; ++p)
        for (int q = 0; q < K; ++q)
          set.block_offsets[e][p * K + q] =
              sparsity.offset(set.terms[e].vertices[p], set.terms[e].vertices[q]);
  });
  if (partition.parts() > 1) set.by_part = elements_by_part(partition, set.terms);
}

}  // namespace

template <typename Visit>
void DiscreteShells::for_each_term(int part, Visit&& visit) const {
  for_each_set([&](const auto& set) { visit_part(set, part, visit); });
}

DiscreteShells::DiscreteShells(const VerticesRef& V, const FacesRef& F, double bending,
                               double membrane, const StiffnessPaint& paint) {
  validate_mesh(V, F);
  require_weight(bending, "bending");
  require_weight(membrane, "membrane");
  require_stiffness_paint(paint, V.rows());
  rest_ = flatten(V);
  const double* x = rest_.data();
  const int n = static_cast<int>(V.rows());
  const MeshTopology topology = build_topology(V, F);
  // Elements below kCollapse of the mesh's extent have no terms: their derivatives would grow
  // as inverse powers of their size, out of double range.
  const double tiny = kCollapse * bounding_box_extent(V);
  std::vector<char> degenerate(F.rows());
  for (int f = 0; f < F.rows(); ++f)
    degenerate[f] =
        is_degenerate_face(V, F, f) || ((V.row(F(f, 1)) - V.row(F(f, 0))).norm() <= tiny &&
                                        (V.row(F(f, 2)) - V.row(F(f, 0))).norm() <= tiny);

  // The rest quantities come from the same code as the deformed ones, so at rest s = s̄ exactly.
  for (const auto& [a, b] : topology.edges) {
    EdgeTerm term{{a, b}, 0, 0, 0};
    double r[3];
    relative(term, x, r);
    const double length = EdgeLength::measure(EdgeLength::frame(r));
    if (length <= tiny) continue;
    term.rest_length = length;
    term.weight = paint.factor(term.vertices) * membrane / length;
    term.collapsed_length = kCollapse * length;
    edges_.terms.push_back(term);
  }
  std::vector<double> area(F.rows(), 0.0);
  for (int f = 0; f < F.rows(); ++f) {
    if (degenerate[f]) continue;
    TriangleTerm term{{F(f, 0), F(f, 1), F(f, 2)}, 0, 0, 0};
    double r[6];
    relative(term, x, r);
    const auto frame = TriangleArea::frame(r);
    area[f] = TriangleArea::measure(frame);
    term.rest_area = area[f];
    const double stretching = paint.factor(term.vertices) * membrane;
    term.weight = bounded_weight(stretching / area[f], squared_gradient_norm<TriangleTerm>(frame),
                                 stretching * kEquilateralTriangleStiffness);
    term.collapsed_norm = kCollapse * frame.norm;
    triangles_.terms.push_back(term);
  }
  for (const Hinge& hinge : topology.hinges) {
    if (degenerate[hinge.faces[0]] || degenerate[hinge.faces[1]]) continue;
    HingeTerm term{hinge.vertices, 0, 0, 0, 0, 0};
    double r[9];
    relative(term, x, r);
    const auto frame = DihedralAngle::frame(r);
    const auto [cos_rest, sin_rest] = DihedralAngle::measure(frame);
    term.cos_rest = cos_rest;
    term.sin_rest = sin_rest;
    const double bend = paint.factor(term.vertices) * bending;
    term.weight = bounded_weight(
        3 * bend * frame.aa / (area[hinge.faces[0]] + area[hinge.faces[1]]),
        squared_gradient_norm<HingeTerm>(frame), bend * equilateral_hinge_stiffness(frame.aa));
    term.rest_n1n1 = frame.n1n1;
    term.rest_n2n2 = frame.n2n2;
    hinges_.terms.push_back(term);
  }

  std::vector<std::array<int, 2>> pairs;
  std::vector<int> work(n, 0);
  for_each_set([&](const auto& set) {
    add_vertex_pairs(set.terms, pairs);
    for (const auto& term : set.terms)
      for (int v : term.vertices) work[v] += static_cast<int>(term.vertices.size());
  });
  sparsity_ = BlockSparsity(n, pairs);
  const size_t num_terms = edges_.terms.size() + triangles_.terms.size() + hinges_.terms.size();
  partition_ = balanced_partition(
      work, num_terms >= kParallelElements ? std::max(1, omp_get_max_threads()) : 1);
  finish_set(edges_, sparsity_, partition_);
  finish_set(triangles_, sparsity_, partition_);
  finish_set(hinges_, sparsity_, partition_);
}

DiscreteShells::TermMatch DiscreteShells::match_terms(const DiscreteShells& other) const {
  const auto match = [](const auto& mine, const auto& theirs) {
    using Vertices = decltype(mine.terms[0].vertices);
    std::map<Vertices, int> index;
    for (size_t e = 0; e < theirs.terms.size(); ++e)
      index.emplace(theirs.terms[e].vertices, static_cast<int>(e));
    std::vector<int> found(mine.terms.size(), -1);
    for (size_t e = 0; e < mine.terms.size(); ++e)
      if (const auto it = index.find(mine.terms[e].vertices); it != index.end())
        found[e] = it->second;
    return found;
  };
  return {match(edges_, other.edges_), match(triangles_, other.triangles_),
          match(hinges_, other.hinges_)};
}

void DiscreteShells::blend_rests(const std::vector<const DiscreteShells*>& rests,
                                 const std::vector<TermMatch>& matches,
                                 const std::vector<double>& c) {
  if (rests.size() != c.size() || matches.size() != c.size())
    throw InputError(message("blend_rests: ", rests.size(), " energies, ", matches.size(),
                             " matches, ", c.size(), " weights"));
  const size_t k = rests.size();
  // Σ_j c_j ½ w_j (s − s̄_j)²: weight W = Σ c_j w_j, rest S = Σ c_j w_j s̄_j / W.
  const auto blend_quadratic = [&](auto& terms, auto set_of, auto match_of, auto rest_of) {
    for (size_t e = 0; e < terms.size(); ++e) {
      double weight = 0, moment = 0;
      for (size_t j = 0; j < k; ++j) {
        const int m = match_of(matches[j])[e];
        if (m < 0 || c[j] == 0) continue;
        const auto& term = set_of(*rests[j])[static_cast<size_t>(m)];
        weight += c[j] * term.weight;
        moment += c[j] * term.weight * rest_of(term);
      }
      terms[e].weight = weight;
      if (weight != 0) rest_of(terms[e]) = moment / weight;
    }
  };
  blend_quadratic(
      edges_.terms, [](const DiscreteShells& s) -> auto& { return s.edges_.terms; },
      [](const TermMatch& m) -> auto& { return m.edges; },
      [](auto& term) -> auto& { return term.rest_length; });
  blend_quadratic(
      triangles_.terms, [](const DiscreteShells& s) -> auto& { return s.triangles_.terms; },
      [](const TermMatch& m) -> auto& { return m.triangles; },
      [](auto& term) -> auto& { return term.rest_area; });
  // Σ_j c_j ½ w_j ‖(cos θ, sin θ) − (cos θ̄_j, sin θ̄_j)‖² = ½ |Z| ‖(cos θ, sin θ) − Z/|Z|‖² + const.
  for (size_t e = 0; e < hinges_.terms.size(); ++e) {
    double re = 0, im = 0;
    for (size_t j = 0; j < k; ++j) {
      const int m = matches[j].hinges[e];
      if (m < 0 || c[j] == 0) continue;
      const HingeTerm& term = rests[j]->hinges_.terms[static_cast<size_t>(m)];
      re += c[j] * term.weight * term.cos_rest;
      im += c[j] * term.weight * term.sin_rest;
    }
    HingeTerm& term = hinges_.terms[e];
    const double norm = std::hypot(re, im);
    term.weight = norm;
    if (norm > 0) {
      term.cos_rest = re / norm;
      term.sin_rest = im / norm;
    }
  }
}

DiscreteShells::TermCounts DiscreteShells::term_counts() const {
  return {static_cast<int>(edges_.terms.size()), static_cast<int>(triangles_.terms.size()),
          static_cast<int>(hinges_.terms.size())};
}

double DiscreteShells::value(const VectorRef& x) const {
  require_positions(x, rest_.size(), "X");
  double energy = 0;
  for_each_set([&](const auto& set) {
    using Term = typename std::decay_t<decltype(set.terms)>::value_type;
    const int count = static_cast<int>(set.terms.size());
    if (!parallel()) {
      for (int e = 0; e < count; ++e) {
        double r[kDofsOf<Term>];
        energy += respond_at(set.terms[e], x.data(), r).f;
      }
      return;
    }
    // Blocks of a fixed size summed in their order: the same bits whatever the threads.
    constexpr int kBlock = 4096;
    std::vector<double> partial((count + kBlock - 1) / kBlock, 0.0);
#pragma omp parallel for schedule(static)
    for (int b = 0; b < static_cast<int>(partial.size()); ++b) {
      double sum = 0;
      for (int e = b * kBlock; e < std::min(count, (b + 1) * kBlock); ++e) {
        double r[kDofsOf<Term>];
        sum += respond_at(set.terms[e], x.data(), r).f;
      }
      partial[b] = sum;
    }
    for (double sum : partial) energy += sum;
  });
  return energy;
}

double DiscreteShells::value_and_gradient(const VectorRef& x,
                                          Eigen::Ref<Eigen::VectorXd> gradient) const {
  require_positions(x, rest_.size(), "X");
  if (gradient.size() != rest_.size())
    throw InputError(
        message("gradient: expected ", rest_.size(), " values, got ", gradient.size()));
  double energy = 0;
  if (!parallel()) {  // the reduced solver's ghost, for instance
    gradient.setZero();
    for_each_set([&](const auto& set) {
      add_gradients_in_lanes(set.terms, x.data(), gradient.data(), energy);
    });
    return energy;
  }
  // Each part's energy apart, summed in the parts' order: the same bits whatever the threads.
  std::vector<double> part_energy(partition_.parts(), 0.0);
#pragma omp parallel for schedule(static, 1)
  for (int part = 0; part < partition_.parts(); ++part) {
    const VertexPartition::Range owned = partition_.range(part);
    gradient.segment(3 * owned.first, 3 * (owned.last - owned.first)).setZero();
    for_each_term(part, [&](const auto& term, int) {
      const double f = add_gradient(term, x.data(), owned, gradient.data());
      if (owned.contains(term.vertices[0])) part_energy[part] += f;
    });
  }
  for (double e : part_energy) energy += e;
  return energy;
}

SparseMatrix DiscreteShells::hessian(const VectorRef& x) const {
  SparseMatrix H;
  hessian_into(x, false, H);
  return H;
}

SparseMatrix DiscreteShells::projected_hessian(const VectorRef& x) const {
  SparseMatrix H;
  hessian_into(x, true, H);
  return H;
}

void DiscreteShells::hessian_into(const VectorRef& x, bool projected, SparseMatrix& H) const {
  require_positions(x, rest_.size(), "X");
  sparsity_.allocate_matrix(H);
  double* values = H.valuePtr();
#pragma omp parallel for schedule(static, 1) if (parallel())
  for (int part = 0; part < partition_.parts(); ++part) {
    const VertexPartition::Range owned = partition_.range(part);
    sparsity_.zero_columns(H, owned.first, owned.last);
    for_each_term(part, [&](const auto& term, int e) {
      using Term = std::decay_t<decltype(term)>;
      constexpr int K = kVerticesOf<Term>, N = kDofsOf<Term>, M = 3 * K;
      double r[N];
      relative(term, x.data(), r);
      const auto frame = Term::Quantity::frame(r);
      const Response q = respond(term, frame);
      if (!q.differentiable) return;
      const BlockCoefficients coefficients = block_coefficients<K>(q, projected);
      double g[N], h[N * N], full[M * M];
      if (coefficients.df != 0)
        second_derivatives(term, q.faded, r, g, h);
      else  // at rest, for instance: ∇²s is not needed
        gradient_of(term, q.faded, frame, g);
      term_hessian<K>(coefficients, g, h, full);
      const auto& offsets = set_of(term).block_offsets[e];
      for (int b = 0; b < K; ++b) {
        const int column_vertex = term.vertices[b];
        if (!owned.contains(column_vertex)) continue;
        const int stride = sparsity_.column_stride(column_vertex);
        for (int a = 0; a < K; ++a) {
          double* block = values + offsets[a * K + b];
          for (int j = 0; j < 3; ++j)
            for (int i = 0; i < 3; ++i) block[j * stride + i] += full[(3 * a + i) * M + 3 * b + j];
        }
      }
    });
  }
}

Eigen::VectorXd DiscreteShells::third(const VectorRef& x, const VectorRef& u,
                                      const VectorRef& w) const {
  require_positions(x, rest_.size(), "X");
  require_positions(u, rest_.size(), "U");
  require_positions(w, rest_.size(), "W");
  Eigen::VectorXd out(rest_.size());
#pragma omp parallel for schedule(static, 1) if (parallel())
  for (int part = 0; part < partition_.parts(); ++part) {
    const VertexPartition::Range owned = partition_.range(part);
    out.segment(3 * owned.first, 3 * (owned.last - owned.first)).setZero();
    for_each_term(part, [&](const auto& term, int) {
      using Term = std::decay_t<decltype(term)>;
      constexpr int K = kVerticesOf<Term>, N = kDofsOf<Term>;
      double r[N];
      const Response q = respond_at(term, x.data(), r);
      if (!q.differentiable) return;
      double ur[N], wr[N], g[N], hu[N], hw[N], tuw[N], local[N], full[3 * K];
      relative(term, u.data(), ur);
      relative(term, w.data(), wr);
      third_derivatives(term, q.faded, r, ur, wr, g, hu, hw, tuw);
      third_of_term<N>(q, g, hu, hw, ur, wr, tuw, local);
      to_vertices<K>(local, full);
      add_owned(term, full, owned, out.data());
    });
  }
  return out;
}

RowMatrixXd DiscreteShells::third_batch(const VectorRef& x,
                                        const Eigen::Ref<const Eigen::MatrixXd>& Phi,
                                        const std::vector<std::array<int, 2>>& pairs) const {
  require_positions(x, rest_.size(), "X");
  if (Phi.rows() != rest_.size())
    throw InputError(message("Phi: expected ", rest_.size(), " rows, got ", Phi.rows()));
  if (!Phi.allFinite())
    for (Eigen::Index j = 0; j < Phi.cols(); ++j)
      for (Eigen::Index i = 0; i < Phi.rows(); ++i)
        if (!std::isfinite(Phi(i, j)))
          throw InputError(message("Phi[", i, ", ", j, "]: not finite (", Phi(i, j), ")"));
  // The columns the pairs use, each gathered once per element.
  std::vector<int> slot(Phi.cols(), -1), used;
  for (size_t p = 0; p < pairs.size(); ++p)
    for (int column : pairs[p]) {
      if (column < 0 || column >= Phi.cols())
        throw InputError(
            message("pairs[", p, "]: column ", column, " outside [0, ", Phi.cols(), ")"));
      if (slot[column] < 0) {
        slot[column] = static_cast<int>(used.size());
        used.push_back(column);
      }
    }
  const int num_used = static_cast<int>(used.size());
  const int num_pairs = static_cast<int>(pairs.size());
  // The result is row-major, each DOF's values side by side: an element then adds to a few runs
  // of memory, not to one place in each column.
  RowMatrixXd out(rest_.size(), num_pairs);
#pragma omp parallel for schedule(static, 1) if (parallel())
  for (int part = 0; part < partition_.parts(); ++part) {
    const VertexPartition::Range owned = partition_.range(part);
    auto rows = out.middleRows(3 * owned.first, 3 * (owned.last - owned.first));
    rows.setZero();
    // Φ over each element's relative coordinates (slot by slot) and ∇²s times it, and the
    // element's third derivative for each pair over its vertices.
    constexpr int kMaxDofs = kDofsOf<HingeTerm>, kMaxVertices = kVerticesOf<HingeTerm>;
    std::vector<double> phi(kMaxDofs * num_used), h_phi(kMaxDofs * num_used);
    std::vector<double> full(3 * kMaxVertices * static_cast<size_t>(num_pairs));
    for_each_term(part, [&](const auto& term, int) {
      using Term = std::decay_t<decltype(term)>;
      constexpr int K = kVerticesOf<Term>, N = kDofsOf<Term>;
      double r[N];
      const Response q = respond_at(term, x.data(), r);
      if (!q.differentiable) return;
      double g[N], h[N * N];
      second_derivatives(term, q.faded, r, g, h);
      for (int s = 0; s < num_used; ++s) {
        double* phi_s = &phi[N * s];
        relative(term, Phi.col(used[s]).data(), phi_s);
        for (int i = 0; i < N; ++i) h_phi[N * s + i] = dot<N>(&h[i * N], phi_s);
      }
      for (int p = 0; p < num_pairs; ++p) {
        const int i = slot[pairs[p][0]], j = slot[pairs[p][1]];
        double tuw[N], local[N];
        if (q.df != 0) {  // away from rest: ∇³s(Φ_i, Φ_j) too
          double unused_g[N], unused_hu[N], unused_hw[N];
          third_derivatives(term, q.faded, r, &phi[N * i], &phi[N * j], unused_g, unused_hu,
                            unused_hw, tuw);
        }
        third_of_term<N>(q, g, &h_phi[N * i], &h_phi[N * j], &phi[N * i], &phi[N * j], tuw, local);
        to_vertices<K>(local, &full[3 * K * p]);
      }
      for (int m = 0; m < K; ++m) {
        const int v = term.vertices[m];
        if (!owned.contains(v)) continue;
        for (int i = 0; i < 3; ++i) {
          double* row = rows.row(3 * (v - owned.first) + i).data();
          for (int p = 0; p < num_pairs; ++p) row[p] += full[3 * K * p + 3 * m + i];
        }
      }
    });
  }
  return out;
}

}  // namespace modal_deform
