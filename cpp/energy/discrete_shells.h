// The discrete shells energy (Grinspun et al. 2003) as Hildebrandt et al. 2011 use it:
//
//   E   = α E_F + β (E_L + E_A)                       α = bending, β = membrane
//   E_F = ½ Σ_hinges 3‖ē‖²/Ā_e · (2 sin((θ − θ̄)/2))²  θ dihedral angle, Ā_e combined rest area
//                                                      of the hinge's two triangles
//   E_L = ½ Σ_edges (‖e‖ − ‖ē‖)² / ‖ē‖
//   E_A = ½ Σ_triangles (A − Ā)² / Ā
//
// Barred quantities are measured on the rest mesh. α and β may be painted per element
// (stiffness_paint.h). The three parts have different units (E_F
// none, E_L length, E_A length²), which is why the paper scales every model to a longest
// bounding-box edge of 10 (normalization.h) before α and β apply; this class takes V as given.
//
// Every term is w f(s(x)) with s an element quantity of shell_elements.h (edge length, triangle
// area, dihedral angle) and f a scalar function with known f', f'', f''', so
//   ∇E = w f' ∇s,   ∇²E = w (f'' ∇s∇sᵀ + f' ∇²s),
//   ∇³E(u, v) = w [f''' (∇s·u)(∇s·v) ∇s + f'' ((uᵀ∇²s v) ∇s + (∇s·u) ∇²s v + (∇s·v) ∇²s u)
//               + f' ∇³s(u, v)],
// with ∇s written by hand and ∇²s, ∇³s(u, v) from it by dual numbers (dual.h). A bending term,
// f = ½ w (2 sin(δ/2))² = w (1 − cos δ) with δ = θ − θ̄, needs θ only through cos θ and sin θ,
// which the same function gives for θ and θ̄ from the unnormalised normals: (2 sin(δ/2))² is the
// squared chord between (cos θ, sin θ) and (cos θ̄, sin θ̄) on the unit circle, and f', f'', f'''
// are ±w sin δ, w cos δ. So δ is wrapped into (−π, π] by construction, the derivatives agree
// across ±π, and no atan2 or sine is evaluated (they would cost as much as all the rest of
// value and gradient on a small mesh).
// At rest f' = 0 for every term, so ∇²E(x̄) = Σ w f'' ∇s∇sᵀ is positive semi-definite and
// ∇³E(x̄) needs only ∇s and ∇²s (what third_batch exploits).
//
// Which elements have terms:
// - every edge a length term; an interior edge a bending term. A non-manifold edge with k faces
//   gets k bending terms, one per pair of faces adjacent in the angular order around it at rest
//   (MeshTopology::hinges), each with its own θ̄ and Ā_e: the sheets meeting there bend as if
//   welded pairwise. Boundary edges have no bending term.
// - degenerate rest elements have no term, since their rest quantity or weight is undefined: a
//   triangle for which is_degenerate_face holds, or whose edges are no longer than 1e-12 times
//   the mesh's extent (the longest side of its bounding box), has no area term, a hinge with
//   such a triangle no bending term, and an edge no longer than 1e-12 times the extent no length
//   term. Vertices in no term (unreferenced ones, those only in degenerate faces) get zero
//   gradient entries and zero (but present) diagonal Hessian blocks.
// - near-degenerate rest elements (slivers, needles) keep their terms, but a bending or area term
//   is no stiffer at rest than kMaxStiffnessRatio times the same term on equilateral triangles
//   (a hinge of the same edge length): its weight w is lowered to
//   min(w, kMaxStiffnessRatio · k_equilateral / ‖∇s‖²). A hinge's stiffness w ‖∇θ‖² grows as the
//   cube of its triangles' thinness (between two slivers of shape ratio 1e-3: about 3e8 times an
//   equilateral hinge's). Those outliers, a discretisation artefact rather than the surface's
//   physics, dominate tr K, which sets the eigensolver's shift (a grid with such sliver pairs
//   failed its bake: the shift fell far below the modes), and they leave small pivots of K − σM
//   to rounding. Measured ratio to the equilateral stiffness: the bunny's largest hinge 46,
//   dragon_vrip_res2's median 2.5, 99th percentile 210, largest 2.9e8.
// - a hinge's angle jumps by π when one of its triangles passes through zero area (its normal
//   turns over), which would make a bending term, and so E, jump by up to 2w there, and the reduced
//   solver's line search stall on ghost triangles crushed during strong poses. So a
//   bending term fades out as either triangle is crushed: it is multiplied by φ(t1) φ(t2), with
//   t_k = ‖n_k‖² / ‖n̄_k‖² (the squared ratio of deformed to rest area) and the quintic
//   smoothstep φ(t) = u³(10 − 15u + 6u²), u = t / kHingeFade², for t below kHingeFade², 1
//   above. φ and its first two derivatives are continuous, and near t = 0 φ ∝ ‖n_k‖⁶ outweighs
//   ∇θ ∝ 1/‖n_k‖ and ∇²θ ∝ 1/‖n_k‖², so the term, its gradient and Hessian go to 0 continuously
//   as a triangle collapses and turns over (the membrane terms stay continuous there, their
//   gradients bounded). At rest (t = 1) φ = 1 with zero derivatives: K and ∇³E(x̄) do not change.
// - a deformed element that collapses (edge length, triangle area or, for a hinge, either
//   triangle's area below 1e-12 times its rest value) is not differentiable there: an edge or a
//   triangle keeps its value but contributes no derivatives (its value is continuous there); a
//   hinge, faded out, contributes nothing. Every output stays finite.
//
// Meshes with at least kParallelElements terms are evaluated in parallel (OpenMP) over vertex
// ranges (vertex_partition.h), with the same results for any number of threads (but for the
// order in which value sums); smaller ones, such as the reduced solver's ghost mesh, run on the
// calling thread without allocating (value, value_and_gradient), the gradient two terms of a kind
// at a time in SIMD lanes (lanes.h) with the same sums, bit for bit. All methods are const and
// safe to call concurrently.
#pragma once

#include <array>
#include <vector>

#include "energy/energy.h"
#include "energy/shell_elements.h"
#include "energy/stiffness_paint.h"
#include "energy/vertex_partition.h"
#include "linalg/block_sparsity.h"

namespace modal_deform {

namespace shells {

// f(ℓ) = ½ w (ℓ − ℓ̄)², w = β / ℓ̄.
struct EdgeTerm {
  using Quantity = EdgeLength;
  std::array<int, 2> vertices;
  double rest_length, weight;
  double collapsed_length;  // length at or below which the edge counts as collapsed
};

// f(A) = ½ w (A − Ā)², w = β / Ā.
struct TriangleTerm {
  using Quantity = TriangleArea;
  std::array<int, 3> vertices;
  double rest_area, weight;
  double collapsed_norm;  // ‖n‖ = 2A at or below which the triangle counts as collapsed
};

// f(θ) = ½ w (2 sin((θ − θ̄)/2))² φ(t1) φ(t2), w = 3 α ‖ē‖² / Ā_e, t_k = ‖n_k‖² / ‖n̄_k‖² (the
// fade, above).
struct HingeTerm {
  using Quantity = DihedralAngle;
  std::array<int, 4> vertices;  // as in Hinge::vertices
  double cos_rest, sin_rest, weight;
  double rest_n1n1, rest_n2n2;  // ‖n̄1‖², ‖n̄2‖²: four times the rest areas squared
};

// The terms of one kind with what assembly needs: the value-array offset of each of a term's
// K² Hessian blocks (row-major over the term's vertex pairs), and the terms each vertex range
// visits.
template <typename Term>
struct TermSet {
  static constexpr int K = Term::Quantity::kVertices;
  std::vector<Term> terms;
  std::vector<std::array<int, K * K>> block_offsets;
  std::vector<std::vector<int>> by_part;  // empty when a single part visits every term
};

}  // namespace shells

// A bending or area term's rest stiffness is at most this multiple of its equilateral one (above).
constexpr double kMaxStiffnessRatio = 100.0;
// A bending term fades out once either triangle's area falls below this fraction of its rest area.
constexpr double kHingeFade = 0.1;

class DiscreteShells final : public Energy {
 public:
  // Meshes with fewer terms are evaluated on the calling thread.
  static constexpr int kParallelElements = 20000;

  // V: #V by 3 rest positions; F: #F by 3 triangles; bending (α) and membrane (β) weights,
  // finite and ≥ 0, each element's multiplied by its factor of `paint` (stiffness_paint.h).
  // Throws InputError for an unusable mesh (validate_mesh), a bad weight or paint.
  DiscreteShells(const VerticesRef& V, const FacesRef& F, double bending = 1.0, double membrane = 1.0,
                 const StiffnessPaint& paint = {});

  int num_vertices() const override { return static_cast<int>(rest_.size() / 3); }
  const Eigen::VectorXd& rest() const override { return rest_; }

  // x, u, w: 3n. Throws InputError for a wrong length or a non-finite entry (naming it).
  double value(const VectorRef& x) const override;
  double value_and_gradient(const VectorRef& x, Eigen::Ref<Eigen::VectorXd> gradient) const override;
  // Exactly symmetric; its pattern (vertex blocks of every vertex pair sharing a term, and all
  // diagonal blocks) is the same at every x.
  SparseMatrix hessian(const VectorRef& x) const override;
  // Each term's Hessian projected onto the positive semidefinite cone (an eigendecomposition of
  // its 3(K−1) by 3(K−1) block over the relative coordinates of its K vertices; an edge's in
  // closed form), but for hinges bent less than 90° from rest, which take the Gauss–Newton block
  // f''(θ)∇θ∇θᵀ (discrete_shells.cpp, block_coefficients, says why).
  SparseMatrix projected_hessian(const VectorRef& x) const override;
  void hessian_into(const VectorRef& x, bool projected, SparseMatrix& H) const override;
  Eigen::VectorXd third(const VectorRef& x, const VectorRef& u, const VectorRef& w) const override;

  // The third derivative contracted with pairs of columns of Phi (3n by k, e.g. vibration
  // modes): column p of the 3n by #pairs result is ∇³E(x)(Φ_i, Φ_j) for {i, j} = pairs[p]
  // (row-major: that is the order in which elements write it).
  // One pass over the elements serves all pairs. Throws InputError for a bad shape, a
  // non-finite entry or a column index outside [0, k).
  RowMatrixXd third_batch(const VectorRef& x, const Eigen::Ref<const Eigen::MatrixXd>& Phi,
                          const std::vector<std::array<int, 2>>& pairs) const;

  struct TermCounts {
    int edges, triangles, hinges;
  };
  // How many length, area and bending terms the mesh has (degenerate rest elements have none).
  TermCounts term_counts() const;

 private:
  template <typename Visit>
  void for_each_set(Visit&& visit) const {
    visit(edges_);
    visit(triangles_);
    visit(hinges_);
  }
  // Calls visit(term, index in its set) for every term that `part` visits: edges, triangles,
  // then hinges, each in order.
  template <typename Visit>
  void for_each_term(int part, Visit&& visit) const;
  const shells::TermSet<shells::EdgeTerm>& set_of(const shells::EdgeTerm&) const { return edges_; }
  const shells::TermSet<shells::TriangleTerm>& set_of(const shells::TriangleTerm&) const { return triangles_; }
  const shells::TermSet<shells::HingeTerm>& set_of(const shells::HingeTerm&) const { return hinges_; }
  bool parallel() const { return partition_.parts() > 1; }

  Eigen::VectorXd rest_;
  shells::TermSet<shells::EdgeTerm> edges_;
  shells::TermSet<shells::TriangleTerm> triangles_;
  shells::TermSet<shells::HingeTerm> hinges_;
  BlockSparsity sparsity_;
  VertexPartition partition_;
};

}  // namespace modal_deform
