#include "energy/arap.h"

#include <algorithm>
#include <cmath>

#include <Eigen/SVD>

#include "mesh/cotangent_weights.h"
#include "mesh/mesh_check.h"
#include "mesh/mesh_topology.h"
#include "util/errors.h"
#include "util/require_positions.h"

namespace modal_deform {
namespace {

// Below this many vertices the cells run on the calling thread. The reduced solver evaluates a
// ghost mesh of 500-5000 vertices every BFGS iteration; there a thread team saves at most half of
// a short call on idle cores, and doubles it on a loaded machine when the second thread is
// descheduled (every call waits for it at the barrier).
constexpr int kParallelVertices = 8192;

// Eigenvalues of f_ωω below this fraction of its largest, or of its value at rest, are treated as
// zero (pseudo-inverse): a cell whose edges are collinear can spin about their line at no cost,
// and one collapsed far below its rest size would give f_xω f_ωω⁻¹ f_ωx beyond double range.
constexpr double kSingularRotationRatio = 1e-10;

// The best rotation of a cell from its covariance S = U Σ Vᵀ (S&A eq. 6): R = V Uᵀ maximises
// tr(R S). When V Uᵀ is a reflection, the singular vector of the smallest singular value is
// flipped, giving the best proper rotation. U and the signed singular values (σ1, σ2, ±σ3) also
// diagonalise P = Rᵀ Sᵀ = U diag(s) Uᵀ, which the Hessian needs.
struct CellRotation {
  Eigen::Matrix3d rotation;
  Eigen::Matrix3d U;
  Eigen::Vector3d signed_singular_values;
};

CellRotation best_rotation(const Eigen::Matrix3d& S) {
  const Eigen::JacobiSVD<Eigen::Matrix3d, Eigen::NoQRPreconditioner> svd(
      S, Eigen::ComputeFullU | Eigen::ComputeFullV);
  CellRotation fit{Eigen::Matrix3d(), svd.matrixU(), svd.singularValues()};
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) {
    fit.U.col(2) = -fit.U.col(2);
    fit.signed_singular_values[2] = -fit.signed_singular_values[2];
  }
  fit.rotation = svd.matrixV() * fit.U.transpose();
  return fit;
}

Eigen::Matrix3d cross_matrix(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

}  // namespace

Arap::Arap(const VerticesRef& V, const FacesRef& F)
    : num_vertices_(static_cast<int>(V.rows())), parallel_(V.rows() >= kParallelVertices) {
  validate_mesh(V, F);
  rest_ = flatten(V);
  const MeshTopology topology = build_topology(V, F);
  const Eigen::VectorXd weights = cotangent_weights(V, F, topology);

  // Cells from the edges of positive weight, each edge in both of its vertices' cells.
  const int n = num_vertices_;
  cell_offsets_.assign(n + 1, 0);
  for (size_t e = 0; e < topology.edges.size(); ++e)
    if (weights[e] > 0)
      for (int v : topology.edges[e]) ++cell_offsets_[v + 1];
  for (int i = 0; i < n; ++i) cell_offsets_[i + 1] += cell_offsets_[i];
  cell_neighbors_.resize(cell_offsets_[n]);
  cell_weights_.resize(cell_offsets_[n]);
  std::vector<int> fill(cell_offsets_.begin(), cell_offsets_.end() - 1);
  for (size_t e = 0; e < topology.edges.size(); ++e) {
    if (!(weights[e] > 0)) continue;
    const auto [a, b] = topology.edges[e];
    cell_neighbors_[fill[a]] = b;
    cell_weights_[fill[a]++] = weights[e];
    cell_neighbors_[fill[b]] = a;
    cell_weights_[fill[b]++] = weights[e];
  }
  cell_twins_.resize(cell_offsets_[n]);
  for (int i = 0; i < n; ++i)
    for (int e = cell_offsets_[i]; e < cell_offsets_[i + 1]; ++e) {
      const int j = cell_neighbors_[e];
      const int* begin = &cell_neighbors_[cell_offsets_[j]];
      cell_twins_[e] =
          cell_offsets_[j] +
          static_cast<int>(std::find(begin, begin + (cell_offsets_[j + 1] - cell_offsets_[j]), i) -
                           begin);
    }

  // Cell i's rotation couples every pair of {i} ∪ N(i); vertex k meets the cells of {k} ∪ N(k).
  hessian_offsets_.assign(n + 1, 0);
  std::vector<int> coupled;
  for (int k = 0; k < n; ++k) {
    coupled.assign(1, k);
    auto add_cell = [&](int i) {
      coupled.push_back(i);
      coupled.insert(coupled.end(), cell_neighbors_.begin() + cell_offsets_[i],
                     cell_neighbors_.begin() + cell_offsets_[i + 1]);
    };
    add_cell(k);
    for (int e = cell_offsets_[k]; e < cell_offsets_[k + 1]; ++e) add_cell(cell_neighbors_[e]);
    std::sort(coupled.begin(), coupled.end());
    coupled.erase(std::unique(coupled.begin(), coupled.end()), coupled.end());
    hessian_rows_.insert(hessian_rows_.end(), coupled.begin(), coupled.end());
    hessian_offsets_[k + 1] = static_cast<int>(hessian_rows_.size());
  }
}

Eigen::Matrix3d Arap::covariance(int i, const VectorRef& x) const {
  Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
  for (int e = cell_offsets_[i]; e < cell_offsets_[i + 1]; ++e) {
    const int j = cell_neighbors_[e];
    const Eigen::Vector3d rest_edge = rest_.segment<3>(3 * i) - rest_.segment<3>(3 * j);
    const Eigen::Vector3d edge = x.segment<3>(3 * i) - x.segment<3>(3 * j);
    S.noalias() += cell_weights_[e] * rest_edge * edge.transpose();
  }
  return S;
}

double Arap::cell_energy(int i, const VectorRef& x, const Eigen::Matrix3d& rotation) const {
  double energy = 0;
  for (int e = cell_offsets_[i]; e < cell_offsets_[i + 1]; ++e) {
    const int j = cell_neighbors_[e];
    const Eigen::Vector3d rest_edge = rest_.segment<3>(3 * i) - rest_.segment<3>(3 * j);
    const Eigen::Vector3d edge = x.segment<3>(3 * i) - x.segment<3>(3 * j);
    energy += cell_weights_[e] * (edge - rotation * rest_edge).squaredNorm();
  }
  return energy;
}

double Arap::value(const VectorRef& x) const {
  require_positions(x, 3 * num_vertices_, "X");
  double energy = 0;
#pragma omp parallel for schedule(static) reduction(+ : energy) if (parallel_)
  for (int i = 0; i < num_vertices_; ++i)
    energy += cell_energy(i, x, best_rotation(covariance(i, x)).rotation);
  return energy;
}

double Arap::value_and_gradient(const VectorRef& x, Eigen::Ref<Eigen::VectorXd> gradient) const {
  require_positions(x, 3 * num_vertices_, "X");
  if (gradient.size() != x.size())
    throw InputError(message("gradient: expected ", x.size(), " values, got ", gradient.size()));
  // One 3x3 per vertex: allocating it per call costs microseconds, far below the SVDs.
  std::vector<Eigen::Matrix3d> rotations(num_vertices_);
  double energy = 0;
#pragma omp parallel for schedule(static) reduction(+ : energy) if (parallel_)
  for (int i = 0; i < num_vertices_; ++i) {
    rotations[i] = best_rotation(covariance(i, x)).rotation;
    energy += cell_energy(i, x, rotations[i]);
  }
  // Envelope theorem: each R_i minimises its cell, so ∂E/∂R_i = 0 and the gradient is that of
  // E(x, R) with R held fixed. Edge k–j appears in cell k and in cell j (with e_jk = −e_kj), so
  // ∂E/∂x_k = Σ_j 2 w_kj (2 e_kj − (R_k + R_j) ē_kj), gathered per vertex without write conflicts.
#pragma omp parallel for schedule(static) if (parallel_)
  for (int k = 0; k < num_vertices_; ++k) {
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (int e = cell_offsets_[k]; e < cell_offsets_[k + 1]; ++e) {
      const int j = cell_neighbors_[e];
      const Eigen::Vector3d rest_edge = rest_.segment<3>(3 * k) - rest_.segment<3>(3 * j);
      const Eigen::Vector3d edge = x.segment<3>(3 * k) - x.segment<3>(3 * j);
      g += 2 * cell_weights_[e] * (2 * edge - (rotations[k] + rotations[j]) * rest_edge);
    }
    gradient.segment<3>(3 * k) = g;
  }
  return energy;
}

// Cell i as a function of x and a rotation R = R_i exp([ω]×) around its optimum R_i:
//   f(x, ω) = Σ_j w_j (‖e_j‖² + ‖ē_j‖²) − 2 Σ_j w_j e_jᵀ R_i exp([ω]×) ē_j,   e_j = x_i − x_j.
// At ω = 0, with a_j = R_iᵀ e_j and P = Σ_j w_j a_j ē_jᵀ = U diag(s) Uᵀ (symmetric at the optimum):
//   f_ω     = −2 Σ_j w_j ē_j × a_j                       (= 0: R_i is optimal)
//   f_ωx_j  = 2 w_j [ē_j]× R_iᵀ =: G_j,   f_ωx_i = −Σ_j G_j
//   f_ωω    = 2 (tr P · I − P) = 2 U diag(Σs − s_k) Uᵀ    (from exp's second-order term ½[ω]×²)
// The reduced energy min_ω f has the Hessian f_xx − f_xω f_ωω⁻¹ f_ωx (implicit function theorem);
// f_ωω's eigenvalues 2(σ2 ± σ3), 2(σ1 ± σ3), 2(σ1 + σ2) are ≥ 0 at the optimum, and f_ωω is
// singular when the cell's edges are collinear (a free spin: f_ωx has no part along it, the
// pseudo-inverse is exact) or when σ2 = σ3 after a reflection fix (the best rotation jumps: E has a
// kink there). With K = f_ωω⁺ = ½ U diag(μ) Uᵀ, H_p = diag(√(μ/2)) Uᵀ G_p gives f_pω K f_ωq = H_pᵀ
// H_q.
void Arap::rotation_factors(int i, const VectorRef& x, Eigen::Matrix3d* out) const {
  const CellRotation fit = best_rotation(covariance(i, x));
  const Eigen::Vector3d& s = fit.signed_singular_values;
  const Eigen::Vector3d eigenvalues = 2 * (Eigen::Vector3d::Constant(s.sum()) - s);
  // At rest Σs = tr P = Σ_j w_j ‖ē_j‖², so f_ωω's eigenvalues are about twice that.
  double rest_size = 0;
  for (int e = cell_offsets_[i]; e < cell_offsets_[i + 1]; ++e)
    rest_size += std::abs(cell_weights_[e]) *
                 (rest_.segment<3>(3 * i) - rest_.segment<3>(3 * cell_neighbors_[e])).squaredNorm();
  const double cutoff = kSingularRotationRatio * std::max(eigenvalues.maxCoeff(), 2 * rest_size);
  Eigen::Vector3d scale;
  for (int k = 0; k < 3; ++k)
    scale[k] = eigenvalues[k] > cutoff ? std::sqrt(1.0 / eigenvalues[k]) : 0.0;
  const Eigen::Matrix3d scaled_Ut = scale.asDiagonal() * fit.U.transpose();
  out[0].setZero();
  for (int e = cell_offsets_[i]; e < cell_offsets_[i + 1]; ++e) {
    const int j = cell_neighbors_[e];
    const Eigen::Vector3d rest_edge = rest_.segment<3>(3 * i) - rest_.segment<3>(3 * j);
    Eigen::Matrix3d& factor = out[1 + e - cell_offsets_[i]];
    factor.noalias() =
        scaled_Ut * (2 * cell_weights_[e] * cross_matrix(rest_edge) * fit.rotation.transpose());
    out[0] -= factor;
  }
}

SparseMatrix Arap::hessian(const VectorRef& x) const {
  require_positions(x, 3 * num_vertices_, "X");
  const int n = num_vertices_;
  // Cell i's factors live at factors[cell_offsets_[i] + i ...]: vertex i, then its neighbours.
  std::vector<Eigen::Matrix3d> factors(cell_offsets_[n] + n);
#pragma omp parallel for schedule(static) if (parallel_)
  for (int i = 0; i < n; ++i) rotation_factors(i, x, &factors[cell_offsets_[i] + i]);

  // Block column k holds hessian_rows_ of k; its scalar column 3k + c starts at
  // 9 hessian_offsets_[k] + 3 c (number of blocks), row-sorted.
  SparseMatrix H(3 * n, 3 * n);
  H.resizeNonZeros(9 * hessian_offsets_[n]);
  int* outer = H.outerIndexPtr();
  int* inner = H.innerIndexPtr();
  double* values = H.valuePtr();
  outer[3 * n] = 9 * hessian_offsets_[n];
#pragma omp parallel if (parallel_)
  {
    std::vector<int> local(n, -1);
#pragma omp for schedule(dynamic, 256)
    for (int k = 0; k < n; ++k) {
      const int begin = hessian_offsets_[k];
      const int blocks = hessian_offsets_[k + 1] - begin;
      for (int t = 0; t < blocks; ++t) local[hessian_rows_[begin + t]] = t;
      for (int c = 0; c < 3; ++c) {
        const int start = 9 * begin + 3 * c * blocks;
        outer[3 * k + c] = start;
        for (int t = 0; t < blocks; ++t)
          for (int r = 0; r < 3; ++r) {
            inner[start + 3 * t + r] = 3 * hessian_rows_[begin + t] + r;
            values[start + 3 * t + r] = 0;
          }
      }
      auto add = [&](int row, const Eigen::Matrix3d& block) {
        const int t = local[row];
        for (int c = 0; c < 3; ++c)
          for (int r = 0; r < 3; ++r) values[9 * begin + 3 * c * blocks + 3 * t + r] += block(r, c);
      };
      // f_xx: each edge k–j contributes 2 w (a Laplacian block) in cell k and again in cell j.
      double diagonal = 0;
      for (int e = cell_offsets_[k]; e < cell_offsets_[k + 1]; ++e) {
        diagonal += 4 * cell_weights_[e];
        add(cell_neighbors_[e], -4 * cell_weights_[e] * Eigen::Matrix3d::Identity());
      }
      add(k, diagonal * Eigen::Matrix3d::Identity());
      // −f_xω f_ωω⁺ f_ωx of each cell that contains k: cell k (k in slot 0) and its neighbours'.
      auto subtract_rotation_term = [&](int i, int slot_of_k) {
        const Eigen::Matrix3d* cell = &factors[cell_offsets_[i] + i];
        const Eigen::Matrix3d& column = cell[slot_of_k];
        add(i, -cell[0].transpose() * column);
        for (int e = cell_offsets_[i]; e < cell_offsets_[i + 1]; ++e)
          add(cell_neighbors_[e], -cell[1 + e - cell_offsets_[i]].transpose() * column);
      };
      subtract_rotation_term(k, 0);
      for (int e = cell_offsets_[k]; e < cell_offsets_[k + 1]; ++e) {
        const int j = cell_neighbors_[e];
        subtract_rotation_term(j, 1 + cell_twins_[e] - cell_offsets_[j]);
      }
      for (int t = 0; t < blocks; ++t) local[hessian_rows_[begin + t]] = -1;
    }
  }
  return H;
}

Eigen::VectorXd Arap::third(const VectorRef&, const VectorRef&, const VectorRef&) const {
  throw InputError(
      "Arap: the ARAP energy has no third derivative here; modal derivatives need the shells "
      "energy "
      "(energy=\"shells\")");
}

}  // namespace modal_deform
