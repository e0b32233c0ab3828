#include "solve/shape_space.h"

#include <Eigen/Cholesky>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "mesh/normalization.h"
#include "reduction/ghost.h"
#include "solve/bfgs.h"
#include "util/errors.h"
#include "util/require_positions.h"

namespace modal_deform {
namespace {

double milliseconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

// A key's displacement relative to the basis's norm below this fraction is no displacement.
constexpr double kNoDisplacement = 1e-7;
// A key's column is dependent when less than this fraction of it is left after the projection.
constexpr double kDependent = 1e-5;

// Floats of `out` per block of the residuals' sum (write_positions): 16 KB, in the L1 cache.
constexpr Eigen::Index kResidualBlock = 4096;

// The prolongation as a sparse #V by #P matrix (one scalar weight per proxy vertex).
SparseMatrix prolongation_matrix(const Prolongation& P, Eigen::Index num_proxy) {
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<size_t>(3 * P.size()));
  for (Eigen::Index i = 0; i < P.size(); ++i)
    for (int k = 0; k < 3; ++k)
      if (P.weights(i, k) != 0) entries.emplace_back(i, P.vertices(i, k), P.weights(i, k));
  SparseMatrix matrix(P.size(), num_proxy);
  matrix.setFromTriplets(entries.begin(), entries.end());
  return matrix;
}

// Each column of D (3#V by k, fine) as the proxy field u (3#P) whose prolongation P u is nearest
// in the fine mass norm: (Pᵀ M P) u = Pᵀ M d per coordinate. `proxy_mass` receives Pᵀ m (#P).
Eigen::MatrixXd restrict_to_proxy(const Basis& basis, const Eigen::MatrixXd& D,
                                  Eigen::VectorXd& proxy_mass) {
  const Eigen::Index p = basis.num_basis_vertices(), n = basis.num_vertices();
  const SparseMatrix P = prolongation_matrix(basis.prolongation, p);
  const SparseMatrix PtM = P.transpose() * basis.mass.asDiagonal();
  SparseMatrix A = PtM * P;
  proxy_mass = PtM * Eigen::VectorXd::Ones(n);
  // A proxy vertex no fine vertex weighs gets a unit diagonal (and a zero field).
  for (Eigen::Index v = 0; v < p; ++v)
    if (proxy_mass[v] <= 0) A.coeffRef(v, v) += 1.0;
  const Eigen::SimplicialLDLT<SparseMatrix> ldlt(A);
  if (ldlt.info() != Eigen::Success)
    throw NumericalError("shape space: the keys' restriction to the proxy failed");
  Eigen::MatrixXd U(3 * p, D.cols());
  Eigen::MatrixXd rhs(n, 3);
  for (Eigen::Index j = 0; j < D.cols(); ++j) {
    for (int c = 0; c < 3; ++c)
      rhs.col(c) =
          Eigen::Map<const Eigen::VectorXd, 0, Eigen::InnerStride<3>>(D.col(j).data() + c, n);
    const Eigen::MatrixXd u = ldlt.solve(PtM * rhs);
    for (int c = 0; c < 3; ++c)
      Eigen::Map<Eigen::VectorXd, 0, Eigen::InnerStride<3>>(U.col(j).data() + c, p) = u.col(c);
  }
  return U;
}

// P u on the fine vertices (3#V) of a proxy field u (3#P).
Eigen::VectorXd prolongate(const Prolongation& P, const Eigen::VectorXd& u) {
  Eigen::VectorXd fine = Eigen::VectorXd::Zero(3 * P.size());
  for (Eigen::Index i = 0; i < P.size(); ++i)
    for (int k = 0; k < 3; ++k)
      fine.segment<3>(3 * i) +=
          static_cast<double>(P.weights(i, k)) * u.segment<3>(3 * P.vertices(i, k));
  return fine;
}

std::string key_name(Eigen::Index i) { return "shapes[" + std::to_string(i) + "]"; }

}  // namespace

ShapeSpace::ShapeSpace(const Basis& basis, const std::vector<RowMatrixX3d>& keys) {
  validate_basis(basis);
  if (basis.region.size() > 0)
    throw InputError(
        "basis: a region bake cannot blend shape keys (keys move the whole mesh); bake the whole "
        "mesh");
  const Eigen::Index k = static_cast<Eigen::Index>(keys.size());
  if (k == 0) throw InputError("shapes: expected at least one key, got none");
  if (k > kMaxShapeKeys)
    throw InputError(
        message("shapes: a shape space takes up to ", kMaxShapeKeys, " keys, got ", k));
  const Eigen::Index n = basis.num_vertices();
  for (Eigen::Index i = 0; i < k; ++i) {
    if (keys[i].rows() != n)
      throw InputError(
          message(key_name(i), ": expected ", n, " vertices (the basis's), got ", keys[i].rows()));
    require_positions(flatten(keys[i]), 3 * n, key_name(i).c_str());
  }
  if (basis.on_proxy() && 3.0 * n * k * sizeof(float) > 4e9)
    throw InputError(message("shapes: ", k, " keys of ", n,
                             " vertices need more than 4 GB for their detail on the proxy; use "
                             "fewer keys"));
  // The displacements, on the basis's vertices, with the masses there.
  Eigen::MatrixXd D(3 * n, k);
  for (Eigen::Index i = 0; i < k; ++i) D.col(i) = flatten(keys[i]) - flatten(basis.rest);
  Eigen::VectorXd mass = basis.mass;
  Eigen::MatrixXd fine_D;
  if (basis.on_proxy()) {
    fine_D = std::move(D);
    D = restrict_to_proxy(basis, fine_D, mass);
  }
  const Eigen::Index p = basis.num_basis_vertices();
  Eigen::VectorXd dof_mass(3 * p);
  for (Eigen::Index v = 0; v < p; ++v) dof_mass.segment<3>(3 * v).setConstant(mass[v]);

  // Key columns M-orthogonal to the basis (twice, for rounding) and to each other.
  const Eigen::MatrixXd U = basis.vectors.cast<double>();
  const Eigen::Index r0 = U.cols();
  const Eigen::MatrixXd MU = dof_mass.asDiagonal() * U;
  const Eigen::MatrixXd G = U.transpose() * MU;
  const Eigen::LDLT<Eigen::MatrixXd> gram(G);
  const double unit = std::sqrt(G.diagonal().mean());  // a basis column's M-norm
  std::vector<Eigen::VectorXd> added;
  for (Eigen::Index i = 0; i < k; ++i) {
    Eigen::VectorXd e = D.col(i);
    const double norm = std::sqrt(e.dot(dof_mass.cwiseProduct(e)));
    if (!(norm > kNoDisplacement * unit)) continue;
    for (int pass = 0; pass < 2; ++pass) {
      e -= U * gram.solve(MU.transpose() * e);
      for (const Eigen::VectorXd& a : added)
        e -= a * (a.dot(dof_mass.cwiseProduct(e)) / (unit * unit));
    }
    const double left = std::sqrt(e.dot(dof_mass.cwiseProduct(e)));
    if (!(left > kDependent * norm)) continue;
    added.push_back(e * (unit / left));
  }
  const Eigen::Index added_count = static_cast<Eigen::Index>(added.size()), r = r0 + added_count;
  Basis& space = data_.basis;
  space = basis;
  space.timings.clear();
  space.vectors.resize(3 * p, r);
  space.vectors.leftCols(r0) = basis.vectors;
  for (Eigen::Index j = 0; j < added_count; ++j)
    space.vectors.col(r0 + j) = added[static_cast<size_t>(j)].cast<float>();
  data_.base_dimension = static_cast<int>(r0);
  // The ghost's vectors of the key columns: mass-weighted means of their fine fields.
  space.ghost_vectors.conservativeResize(Eigen::NoChange, r);
  const int g = static_cast<int>(basis.ghost_vertices.rows());
  for (Eigen::Index j = 0; j < added_count; ++j) {
    Eigen::VectorXd column = space.vectors.col(r0 + j).cast<double>();
    if (basis.on_proxy()) column = prolongate(basis.prolongation, column);
    space.ghost_vectors.col(r0 + j) = restrict_to_ghost(basis.ghost_map, g, basis.mass, column);
  }
  // Each key's coordinates: its M-projection onto the stored (float32) columns.
  const Eigen::MatrixXd A = space.vectors.cast<double>();
  const Eigen::MatrixXd MA = dof_mass.asDiagonal() * A;
  const Eigen::LDLT<Eigen::MatrixXd> normal(A.transpose() * MA);
  data_.coordinates = normal.solve(MA.transpose() * D);
  if (basis.on_proxy()) {
    data_.residuals.resize(k, 3 * n);
    for (Eigen::Index i = 0; i < k; ++i)
      data_.residuals.row(i) =
          (fine_D.col(i) - prolongate(basis.prolongation, A * data_.coordinates.col(i)))
              .cast<float>()
              .transpose();
  }
  validate_basis(space);
  prepare();
}

ShapeSpace::ShapeSpace(ShapeSpaceData data) : data_(std::move(data)) {
  const Basis& basis = data_.basis;
  validate_basis(basis);
  if (basis.region.size() > 0) throw InputError("basis: a shape space has no region");
  const Eigen::Index r = basis.dimension(), k = data_.coordinates.cols();
  if (data_.base_dimension <= basis.num_rigid || data_.base_dimension > r)
    throw InputError(message("base_dimension: expected a value in (", basis.num_rigid, ", ", r,
                             "], got ", data_.base_dimension));
  if (data_.coordinates.rows() != r || k < 1 || k > kMaxShapeKeys)
    throw InputError(message("coordinates: expected ", r, " rows and 1 to ", kMaxShapeKeys,
                             " columns, got ", data_.coordinates.rows(), " by ", k));
  if (!data_.coordinates.allFinite() || (data_.coordinates.array().abs() > kMaxCoordinate).any())
    throw InputError("coordinates: an entry is not finite or too large");
  const Eigen::Index residual_rows = basis.on_proxy() ? k : 0,
                     residual_cols = basis.on_proxy() ? 3 * basis.num_vertices() : 0;
  if (data_.residuals.rows() != residual_rows || data_.residuals.cols() != residual_cols)
    throw InputError(message("residuals: expected ", residual_rows, " by ", residual_cols,
                             " (one row per key on a proxy, none otherwise), got ",
                             data_.residuals.rows(), " by ", data_.residuals.cols()));
  if (!data_.residuals.allFinite() ||
      (data_.residuals.array().abs() > static_cast<float>(kMaxCoordinate)).any())
    throw InputError("residuals: an entry is not finite or too large");
  prepare();
}

void ShapeSpace::prepare() {
  const Basis& basis = data_.basis;
  const Eigen::Index r = basis.dimension(), k = data_.coordinates.cols();
  num_rigid_ = basis.num_rigid;
  const double s = basis.scale;
  ghost_rest_ = s * flatten(basis.ghost_vertices);
  ghost_vectors_ = s * basis.ghost_vectors;
  const Material material = ghost_material(basis);
  const Eigen::Index g = basis.ghost_vertices.rows();
  energies_.clear();
  for (Eigen::Index j = 0; j <= k; ++j) {
    Eigen::VectorXd rest = ghost_rest_;
    if (j > 0) rest += ghost_vectors_ * data_.coordinates.col(j - 1);
    if (!positions_in_range(rest))
      throw InputError(message(key_name(j - 1), ": its shape is out of range"));
    const RowMatrixX3d V = Eigen::Map<const RowMatrixX3d>(rest.data(), g, 3);
    energies_.push_back(std::make_unique<DiscreteShells>(V, basis.ghost_faces, material.bending,
                                                         material.membrane, material.paint));
  }
  blended_ = std::make_unique<DiscreteShells>(
      Eigen::Map<const RowMatrixX3d>(ghost_rest_.data(), g, 3), basis.ghost_faces, material.bending,
      material.membrane, material.paint);
  matches_.clear();
  for (const auto& energy : energies_) matches_.push_back(blended_->match_terms(*energy));
  const Eigen::MatrixXd free = ghost_vectors_.rightCols(r - num_rigid_);
  rest_hessians_.clear();
  for (Eigen::Index j = 0; j <= k; ++j) {
    const SparseMatrix H = energies_[j]->hessian(energies_[j]->rest());
    const Eigen::MatrixXd HU = H * free;
    rest_hessians_.push_back(free.transpose() * HU);
  }
  map_ = std::make_unique<FinePositions>(basis);
  q_ = Eigen::VectorXd::Zero(r);
  x_.resize(ghost_rest_.size());
  energy_gradient_.resize(ghost_rest_.size());
}

double ShapeSpace::objective(const Eigen::VectorXd& z, Eigen::VectorXd& gradient) {
  q_.tail(z.size()) = z;
  add_columns(ghost_rest_, ghost_vectors_, q_, x_);
  if (!positions_in_range(x_)) return std::numeric_limits<double>::infinity();
  const double value = blended_->value_and_gradient(x_, energy_gradient_);
  gradient.noalias() = ghost_vectors_.rightCols(z.size()).transpose() * energy_gradient_;
  return value;
}

void ShapeSpace::blend(const VectorRef& weights, Eigen::Ref<Eigen::VectorXf> out,
                       const BlendOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  check_options(options, [](auto visit) { for_each_blend_option(visit); });
  const Eigen::Index k = num_keys(), r = dimension(), free = r - num_rigid_;
  if (weights.size() != k)
    throw InputError(message("weights: expected ", k, " (one per key), got ", weights.size()));
  for (Eigen::Index i = 0; i < k; ++i)
    if (!(std::abs(weights[i]) <= kMaxWeight))
      throw InputError(message("weights[", i, "]: expected a number in [", -kMaxWeight, ", ",
                               kMaxWeight, "], got ", weights[i]));
  const Eigen::Index fine_rows = 3 * static_cast<Eigen::Index>(num_vertices());
  if (out.size() != fine_rows)
    throw InputError(
        message("out: expected ", fine_rows, " values (3 per vertex), got ", out.size()));
  // The blended energy: the rest weighted 1 − Σ w_i.
  std::vector<double> c(static_cast<size_t>(k) + 1);
  std::vector<const DiscreteShells*> rests(c.size());
  c[0] = 1.0 - weights.sum();
  for (Eigen::Index i = 0; i < k; ++i) c[static_cast<size_t>(i) + 1] = weights[i];
  for (size_t j = 0; j < c.size(); ++j) rests[j] = energies_[j].get();
  blended_->blend_rests(rests, matches_, c);
  // From the linear blend, rigid coordinates held, with (Σ |c_j| H_j)⁻¹.
  const Eigen::VectorXd linear = data_.coordinates * weights;
  q_ = linear;
  stats_ = {};
  if (free == 0) {  // nothing but rigid coordinates: the linear blend is the blend
    stats_.converged = true;
    write_positions(weights, out, start);
    return;
  }
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(free, free);
  for (size_t j = 0; j < c.size(); ++j)
    if (c[j] != 0) H += std::abs(c[j]) * rest_hessians_[j];
  H = 0.5 * (H + H.transpose()).eval();
  const double largest = H.diagonal().maxCoeff();
  H.diagonal().array() += largest > 0 ? 1e-8 * largest : 1.0;
  Eigen::LLT<Eigen::MatrixXd> llt(H);
  Eigen::MatrixXd inverse = Eigen::MatrixXd::Identity(free, free);
  if (llt.info() == Eigen::Success) inverse = llt.solve(inverse);
  inverse = 0.5 * (inverse + inverse.transpose()).eval();
  Bfgs bfgs;
  bfgs.start(linear.tail(free), inverse);
  const auto solve_start = std::chrono::steady_clock::now();
  const BfgsResult result =
      bfgs.minimize([this](const Eigen::VectorXd& z,
                           Eigen::VectorXd& gradient) { return objective(z, gradient); },
                    options.max_iterations, options.tolerance);
  q_.head(num_rigid_) = linear.head(num_rigid_);
  q_.tail(free) = bfgs.x();
  stats_.iterations = result.iterations;
  stats_.evaluations = result.evaluations;
  stats_.converged = result.converged;
  stats_.stalled = result.stalled;
  stats_.energy = bfgs.value();
  stats_.gradient_norm = bfgs.gradient().norm();
  stats_.solve_ms = milliseconds_since(solve_start);
  // Weights whose rest weight 1 − Σ w_i is negative can leave the energy without a minimum (two
  // keys at 1 that stretch the same elements): a blend that ran off farther than the model's size
  // from the linear blend is none, and the linear blend is returned instead.
  const double moved = (ghost_vectors_ * (q_ - linear)).cwiseAbs().maxCoeff();
  if (!(moved <= kMaxBlendDeparture)) {
    q_ = linear;
    stats_.converged = false;
    stats_.diverged = true;
  }
  write_positions(weights, out, start);
}

void ShapeSpace::write_positions(const VectorRef& weights, Eigen::Ref<Eigen::VectorXf> out,
                                 std::chrono::steady_clock::time_point start) {
  const auto map_start = std::chrono::steady_clock::now();
  map_->write(q_.cast<float>(), out);
  // On a proxy, Σ_i w_i r_i over the keys of non-zero weight in one pass over `out`, in blocks
  // split over threads: the sum is memory-bound (each residual is 3#V floats).
  std::vector<Eigen::Index> keys;
  for (Eigen::Index i = 0; i < data_.residuals.rows(); ++i)
    if (weights[i] != 0) keys.push_back(i);
  if (!keys.empty()) {
    const Eigen::Index size = out.size(), blocks = (size + kResidualBlock - 1) / kResidualBlock;
    float* const o = out.data();
#pragma omp parallel for schedule(static)
    for (Eigen::Index b = 0; b < blocks; ++b) {
      const Eigen::Index begin = b * kResidualBlock, end = std::min(size, begin + kResidualBlock);
      for (const Eigen::Index i : keys) {
        const float w = static_cast<float>(weights[i]);
        const float* const r = data_.residuals.row(i).data();
        for (Eigen::Index j = begin; j < end; ++j) o[j] += w * r[j];
      }
    }
  }
  stats_.map_ms = milliseconds_since(map_start);
  stats_.ms = milliseconds_since(start);
}

}  // namespace modal_deform
