// The discrete shells energy (Grinspun et al. 2003) as Hildebrandt et al. 2011 use it:
//
//   E = α E_F + β (E_L + E_A)      α = bending (hinges), β = membrane (edge lengths, areas)
//
// with α and β painted per element (stiffness_paint.h); V is taken as given (the bake scales it
// to the paper's frame first, normalization.h). Every term is w f(s(x)), s an element quantity of
// shell_elements.h and f a scalar function, so the derivatives follow by the chain rule, ∇²s and
// ∇³s(u, v) by dual numbers (dual.h). Degenerate rest elements have no term, near-degenerate ones
// are capped at kMaxStiffnessRatio times an equilateral term, and a hinge fades out as either of
// its triangles is crushed: every output stays finite. Large meshes run in parallel over vertex
// ranges (vertex_partition.h) with results independent of the thread count; small ones (the
// ghost) on the calling thread without allocating. All methods are const and thread-safe.
// The terms, their derivatives and each rule's reason: docs/design.md, "Discrete shells".
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
  DiscreteShells(const VerticesRef& V, const FacesRef& F, double bending = 1.0,
                 double membrane = 1.0, const StiffnessPaint& paint = {});

  int num_vertices() const override { return static_cast<int>(rest_.size() / 3); }
  const Eigen::VectorXd& rest() const override { return rest_; }

  // x, u, w: 3n. Throws InputError for a wrong length or a non-finite entry (naming it).
  double value(const VectorRef& x) const override;
  double value_and_gradient(const VectorRef& x,
                            Eigen::Ref<Eigen::VectorXd> gradient) const override;
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

  // For each term of this energy, the index of the term of `other` (an energy of the same faces at
  // another rest) over the same vertices, or −1 where `other` has none (an element degenerate in
  // one rest and not in the other has a term in one only).
  struct TermMatch {
    std::vector<int> edges, triangles, hinges;
  };
  TermMatch match_terms(const DiscreteShells& other) const;

  // The blend of energies of one mesh at several rests (shape_space.h): Σ_j c_j E_j with E_j =
  // *rests[j] and matches[j] = match_terms(*rests[j]), up to a constant, is again a shells energy:
  // per term, Σ_j c_j ½ w_j (s − s̄_j)² = ½ W (s − S)² + const with W = Σ_j c_j w_j and
  // S = Σ_j c_j w_j s̄_j / W, and for a hinge Σ_j c_j ½ w_j (2 sin((θ − θ̄_j)/2))² =
  // ½ |Z| (2 sin((θ − arg Z)/2))² + const with Z = Σ_j c_j w_j e^{iθ̄_j}. This energy's terms take
  // those rests and weights (a rest without the term adds nothing to it; collapse thresholds and
  // hinge fades stay this energy's): one evaluation costs what one energy's does, however many
  // rests are blended. W ≤ 0 (negative c_j) makes a term concave; W = 0 leaves it out.
  // O(#rests · #terms). Not thread-safe with evaluations.
  void blend_rests(const std::vector<const DiscreteShells*>& rests,
                   const std::vector<TermMatch>& matches, const std::vector<double>& c);

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
  const shells::TermSet<shells::TriangleTerm>& set_of(const shells::TriangleTerm&) const {
    return triangles_;
  }
  const shells::TermSet<shells::HingeTerm>& set_of(const shells::HingeTerm&) const {
    return hinges_;
  }
  bool parallel() const { return partition_.parts() > 1; }

  Eigen::VectorXd rest_;
  shells::TermSet<shells::EdgeTerm> edges_;
  shells::TermSet<shells::TriangleTerm> triangles_;
  shells::TermSet<shells::HingeTerm> hinges_;
  BlockSparsity sparsity_;
  VertexPartition partition_;
};

}  // namespace modal_deform
