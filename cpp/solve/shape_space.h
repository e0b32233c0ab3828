// Rotation-aware blending of shapes (von Tycowicz, Schulz, Seidel, Hildebrandt, "Real-time
// Nonlinear Shape Interpolation", ACM TOG 34(3), 2015): the blend of keys x_1 … x_k with weights
// w is the shape x that minimises
//
//   Σ_i w_i W[x_i, x] + w_0 W[x̄, x],        w_0 = 1 − Σ_i w_i,
//
// W[y, x] the Discrete Shells energy of x with y as the rest, computed in a subspace on a ghost:
//
// - Subspace: the basis of the rest mesh x̄ (bake.h: rigid motions, modes, modal derivatives; a
//   proxy's above the proxy threshold) augmented by the keys' displacements x_i − x̄, M-orthogonal
//   to it and to each other (a key that adds nothing, such as one equal to the basis or to a
//   combination of others, adds no column), so that every key is x̄ + U q_i exactly (on a proxy:
//   its least-squares part P U q_i, the rest of it, fine detail the proxy cannot hold, added
//   linearly: Σ_i w_i r_i).
// - Energy: each key's Discrete Shells energy on the basis's ghost with the key's ghost shape
//   x̄_s + U_s q_i as the rest; the weighted sum of them is a single shells energy of blended rest
//   quantities (DiscreteShells::blend_rests), so an evaluation costs one ghost energy whatever k.
// - Solve: BFGS on the non-rigid coordinates from the linear blend's q = Σ_i w_i q_i, with the
//   initial inverse Hessian (Σ_i |w_i| H_i)⁻¹ (H_i the reduced Hessian of key i's energy at its
//   rest): a fixed start, so a blend is a function of the weights alone. The rigid coordinates (the
//   basis's num_rigid first columns) are held at the linear blend's: the blend is placed like the
//   linear blend (the same centre of mass and no linearised rotation from it), without drift.
//   Not Newton: the exact reduced Hessian U_sᵀ ∇²E U_s costs O(nnz(∇²E) r + #ghost vertices · r²),
//   some 50 energy evaluations on the dragon's ghost, and Newton from the linear blend still takes
//   about 20 steps there where BFGS takes 45 to 55.
//   Not an optimized cubature (An, Kim, James 2008; the 2015 paper evaluates its energy so): on
//   the dragon's ghost a cubature fitted by greedy NNLS to the reduced gradients of training
//   blends keeps the blend where the ghost's energy puts it only when it touches nearly every
//   ghost vertex, so the projections, a third of an evaluation, do not shrink: the ghost is
//   already the energy's reduction (docs/design.md, "Not a cubature"; the experiment: 0e3b170).
//
// Cost of a blend, k keys, r = basis dimension + k: O(k · #ghost terms) to blend the rests,
// O(k r²) + r³ for the initial inverse Hessian, then per BFGS iteration (their count grows with r)
// an energy evaluation on the ghost, O(#ghost terms + #ghost vertices · r), and O(r²); the map
// O(#V · r) (16-bit vectors, FinePositions), plus O(#V) per key with a non-zero weight on a
// proxy. k enters through r and the rests' blend.
//
// Not thread-safe: one space per thread.
#pragma once

#include <chrono>
#include <memory>
#include <vector>

#include "basis/basis.h"
#include "energy/discrete_shells.h"
#include "solve/reduced_map.h"
#include "util/option.h"

namespace modal_deform {

// Keys a space takes at most.
constexpr int kMaxShapeKeys = 1000;

// The farthest a blend may move a ghost vertex from the linear blend, in the normalised frame
// (the model's longest side is 10): beyond, the blend has run off (BlendStats::diverged).
constexpr double kMaxBlendDeparture = 20.0;

struct BlendStats {
  int iterations = 0;        // BFGS steps of the last blend
  int evaluations = 0;       // evaluations of the blended energy
  bool converged = false;    // the stopping test holds at the blend returned
  bool stalled = false;      // not converged, and no step decreases the energy
  bool diverged = false;     // ran off with no minimum in reach: the linear blend was returned
  double energy = 0;         // the blended energy at the blend (up to a constant)
  double gradient_norm = 0;  // ‖∇f‖ over the non-rigid coordinates
  double solve_ms = 0;       // the minimisation, milliseconds
  double map_ms = 0;         // the map to the fine mesh (and the keys' residuals), milliseconds
  double ms = 0;             // the whole blend, the map included, milliseconds
};

template <typename Visit>
void for_each_blend_stat(Visit&& visit) {
  visit("iterations", [](auto& s) -> auto& { return s.iterations; });
  visit("converged", [](auto& s) -> auto& { return s.converged; });
  visit("ms", [](auto& s) -> auto& { return s.ms; });
  visit("solve_ms", [](auto& s) -> auto& { return s.solve_ms; });
  visit("map_ms", [](auto& s) -> auto& { return s.map_ms; });
  visit("evaluations", [](auto& s) -> auto& { return s.evaluations; });
  visit("energy", [](auto& s) -> auto& { return s.energy; });
  visit("gradient_norm", [](auto& s) -> auto& { return s.gradient_norm; });
  visit("stalled", [](auto& s) -> auto& { return s.stalled; });
  visit("diverged", [](auto& s) -> auto& { return s.diverged; });
}

// What one blend may spend.
struct BlendOptions {
  int max_iterations = 200;
  double tolerance = 1e-9;
};

template <typename Visit>
void for_each_blend_option(Visit&& visit) {
  visit(Option{"max_iterations", "BFGS iterations a blend takes at most.", at_least(0)},
        [](auto& o) -> auto& { return o.max_iterations; });
  visit(Option{"tolerance", "ε of the Gill-Murray-Wright stopping test of a blend's minimisation.",
               between_open(0, 1)},
        [](auto& o) -> auto& { return o.tolerance; });
}

// The space's own arrays besides its basis (the stored form; the keys themselves are not kept).
struct ShapeSpaceData {
  // The augmented basis: the rest's basis with the keys' columns appended (num_rigid, num_modes,
  // ghost and prolongation the rest's).
  Basis basis;
  int base_dimension = 0;       // columns of the rest's basis; the keys' follow
  Eigen::MatrixXd coordinates;  // r by k: q_i, key i = x̄ + U q_i (+ residual i on a proxy)
  RowMatrixXf residuals;  // on a proxy, k by 3#V: what of each key P U cannot hold; else 0 by 0
};

class ShapeSpace {
 public:
  // basis: of the rest mesh, validated here; keys: k ≥ 1 arrays #V by 3 (mesh units), finite, in
  // range. Throws InputError naming the key that is wrong: another vertex count, a non-finite
  // coordinate, more than kMaxShapeKeys keys, a region basis. A key's element of zero size (its
  // rest has no term there) leaves the key out of that element's blend.
  ShapeSpace(const Basis& basis, const std::vector<RowMatrixX3d>& keys);
  // A space stored as `data` (validated: InputError naming what is wrong).
  explicit ShapeSpace(ShapeSpaceData data);
  ShapeSpace(const ShapeSpace&) = delete;
  ShapeSpace& operator=(const ShapeSpace&) = delete;

  // The blend for `weights` (k, finite, |w_i| ≤ kMaxWeight) written into `out` (3#V, mesh
  // units). Weights outside [0, 1] give the stationary point BFGS reaches from the linear blend
  // (stats().converged says whether it did). Throws InputError naming a bad weight.
  void blend(const VectorRef& weights, Eigen::Ref<Eigen::VectorXf> out,
             const BlendOptions& options = {});
  // The reduced coordinates of the last blend (r).
  const Eigen::VectorXd& q() const { return q_; }
  const BlendStats& stats() const { return stats_; }

  // The largest |weight| a blend takes: far beyond it the concave terms of a negative weight
  // dominate and there is no shape to reach.
  static constexpr double kMaxWeight = 10.0;

  const ShapeSpaceData& data() const { return data_; }
  int num_keys() const { return static_cast<int>(data_.coordinates.cols()); }
  int dimension() const { return data_.basis.dimension(); }
  int num_vertices() const { return data_.basis.num_vertices(); }

 private:
  // x̄ + U q_ (+ the weighted residuals on a proxy) into `out`; the time since `start` in stats_.
  void write_positions(const VectorRef& weights, Eigen::Ref<Eigen::VectorXf> out,
                       std::chrono::steady_clock::time_point start);
  void prepare();
  double objective(const Eigen::VectorXd& z, Eigen::VectorXd& gradient);

  ShapeSpaceData data_;
  int num_rigid_ = 0;
  // Ghost, normalised frame: rest s x̄_s (3g), vectors s U_s (3g by r).
  Eigen::VectorXd ghost_rest_;
  Eigen::MatrixXd ghost_vectors_;
  // Energies of the ghost with the rest (0) and each key (1 … k) as the rest, and the blend.
  std::vector<std::unique_ptr<DiscreteShells>> energies_;
  std::unique_ptr<DiscreteShells> blended_;
  std::vector<DiscreteShells::TermMatch> matches_;  // the blend's terms in each energy
  // Reduced Hessians at each rest over the non-rigid coordinates ((r − num_rigid)², k + 1).
  std::vector<Eigen::MatrixXd> rest_hessians_;
  std::unique_ptr<FinePositions> map_;
  // Work space and the last blend.
  Eigen::VectorXd q_, x_, energy_gradient_;
  BlendStats stats_;
};

}  // namespace modal_deform
