// The two maps of the reduced coordinates q that the pose and the simulation share (paper
// section 5): the ghost's energy, E(q) = E_ghost(s (x̄_s + U_s q)) in the normalised frame, which
// their minimisations evaluate, and the fine mesh's positions x̄ + U q, which they write out.
#pragma once

#include <memory>

#include "basis/basis.h"
#include "energy/energy.h"
#include "energy/make_energy.h"
#include "solve/quantized_vectors.h"

namespace modal_deform {

// x = rest + U q (x sized like rest) four columns at a time: one pass over x per four columns,
// where Eigen's column-major matrix-vector product (SSE, the wheel's baseline) makes one per
// column.
void add_columns(const Eigen::VectorXd& rest, const Eigen::MatrixXd& U, const Eigen::VectorXd& q,
                 Eigen::VectorXd& x);

// E(q) on the ghost: the basis's energy (with its weights, the ghost's painted stiffness the means
// of the fine weights), or ARAP, of the ghost mesh scaled by s = basis.scale. An evaluation costs
// O(#ghost vertices · r), whatever the size of the fine mesh. Not thread-safe (work space).
class GhostEnergy {
 public:
  // basis: validated by the caller; only its ghost is copied.
  GhostEnergy(const Basis& basis, EnergyKind energy);

  // E(q) with ∇E(q) (r) written into `gradient`; +inf where a ghost coordinate leaves the range
  // the energies take (kMaxCoordinate).
  double value_and_gradient(const Eigen::VectorXd& q, Eigen::VectorXd& gradient);
  // Whether every ghost coordinate at q is within that range.
  bool in_range(const Eigen::VectorXd& q);
  // s² U_sᵀ ∇²E_ghost(s x̄_s) U_s (r by r): the reduced Hessian at rest.
  Eigen::MatrixXd rest_hessian() const;

  int dimension() const { return static_cast<int>(vectors_.cols()); }

 private:
  std::unique_ptr<Energy> energy_;  // of the ghost, normalised frame
  Eigen::VectorXd rest_;            // s x̄_s (3g)
  Eigen::MatrixXd vectors_;         // s U_s (3g by r)
  Eigen::VectorXd x_, gradient_;    // work space (3g)
};

// x̄ + U q on the fine mesh (3#V, interleaved, mesh units) in single precision; x̄ + P U q for a
// basis on a proxy (prolongation.h). U q is read from 16-bit vectors (QuantizedVectors), each
// coordinate within kTolerance of the bounding-box diagonal of the float32 map's.
class FinePositions {
 public:
  // Within this fraction of the rest's bounding-box diagonal of the float32 map: a third of the
  // 1e-4 the pose may differ by, far below what shows (60 µm on 2 m).
  static constexpr double kTolerance = 3e-5;

  // basis: validated by the caller; it must outlive this, which keeps a reference to its fine
  // arrays. Starts at q = 0.
  explicit FinePositions(const Basis& basis);

  // The q that write() maps (r entries).
  void set(const Eigen::VectorXd& q) { q_ = q.cast<float>(); }
  // Writes the positions of the q set into `out`; rows are split over threads in blocks. Throws
  // InputError for a wrong size.
  void write(Eigen::Ref<Eigen::VectorXf> out) const { write(q_, out); }
  // The same for another q (r entries), leaving the one set alone.
  void write(const Eigen::VectorXf& q, Eigen::Ref<Eigen::VectorXf> out) const {
    write(q, rest_.data(), out);
  }
  // The displacement U q (P U q on a proxy) alone, within the same tolerance: exactly zero at
  // q = 0.
  void write_displacement(const Eigen::VectorXf& q, Eigen::Ref<Eigen::VectorXf> out) const {
    write(q, nullptr, out);
  }

 private:
  // rest + U q (rest null: U q alone) into `out`.
  void write(const Eigen::VectorXf& q, const float* rest, Eigen::Ref<Eigen::VectorXf> out) const;

  const Basis& basis_;
  // x̄ in single precision (3#V, interleaved), what Blender stores: the map reads half the bytes
  // of the double rest for it, a third of all it reads on a proxy.
  Eigen::VectorXf rest_;
  QuantizedVectors quantized_vectors_;  // U in 16 bits
  double tolerance_;                    // kTolerance times the rest's bounding-box diagonal
  Eigen::VectorXf q_;
  mutable Eigen::VectorXf proxy_displacement_;  // U q on a proxy's vertices
};

}  // namespace modal_deform
