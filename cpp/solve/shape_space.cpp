#include "solve/shape_space.h"

#include <Eigen/Cholesky>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "mesh/normalization.h"
#include "reduction/ghost.h"
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
  prepare(true);
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
  const Cubature& cubature = data_.cubature;
  if (cubature.weights.size() != cubature.terms.size())
    throw InputError(message("cubature: ", cubature.terms.size(), " terms but ",
                             cubature.weights.size(), " weights"));
  for (size_t i = 0; i < cubature.terms.size(); ++i) {
    if (cubature.terms[i] < 0 || (i > 0 && cubature.terms[i] <= cubature.terms[i - 1]))
      throw InputError(message("cubature: terms[", i, "] = ", cubature.terms[i],
                               " is negative or not above the term before it"));
    if (!(std::isfinite(cubature.weights[i]) && cubature.weights[i] > 0))
      throw InputError(message("cubature: weights[", i, "] = ", cubature.weights[i],
                               " is not a finite number > 0"));
  }
  prepare(false);  // checks the terms against the ghost's
}

namespace {

// The ghost's energy at `rest` (3g, normalised frame) with the basis's material.
std::unique_ptr<DiscreteShells> ghost_energy(const Basis& basis, const Eigen::VectorXd& rest) {
  const Material material = ghost_material(basis);
  const Eigen::Index g = basis.ghost_vertices.rows();
  return std::make_unique<DiscreteShells>(Eigen::Map<const RowMatrixX3d>(rest.data(), g, 3),
                                          basis.ghost_faces, material.bending, material.membrane,
                                          material.paint);
}

// Term t of `from`'s numbering (term_vertices) in `to`'s, by match = from.match_terms(to), and
// `counts` of each; −1 where `to` has no such term.
int matched_term(int t, const DiscreteShells::TermMatch& match,
                 const DiscreteShells::TermCounts& from, const DiscreteShells::TermCounts& to) {
  if (t < from.edges) return match.edges[t];
  t -= from.edges;
  if (t < from.triangles) {
    const int m = match.triangles[t];
    return m < 0 ? -1 : to.edges + m;
  }
  const int m = match.hinges[t - from.triangles];
  return m < 0 ? -1 : to.edges + to.triangles + m;
}

// Training blends of the cubature: each key alone at ½ (the first kTrainingKeys), then
// kTrainingMixes random mixes (each weight in [0, 1], kept with probability ½), a fixed sequence.
constexpr int kTrainingKeys = 16;
const int kTrainingMixes = std::getenv("MD_MIX") ? std::atoi(std::getenv("MD_MIX")) : 24;
// Points of each training blend's minimisation the fit takes: evenly along its evaluations, from
// the linear blend to the minimum.
const int kTrainingPoints = std::getenv("MD_PTS") ? std::atoi(std::getenv("MD_PTS")) : 4;
// The cubature's fit: the relative residual of the reduced gradients it stops at, and its terms
// at most.
constexpr CubatureOptions kCubatureFit{600, 0.02};

std::vector<Eigen::VectorXd> training_weights(Eigen::Index k) {
  std::vector<Eigen::VectorXd> weights;
  for (Eigen::Index i = 0; i < std::min<Eigen::Index>(k, kTrainingKeys); ++i)
    weights.push_back(0.5 * Eigen::VectorXd::Unit(k, i));
  std::mt19937 random(52);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (int b = 0; b < kTrainingMixes; ++b) {
    Eigen::VectorXd w(k);
    for (Eigen::Index i = 0; i < k; ++i) {
      const double value = uniform(random);
      w[i] = uniform(random) < 0.5 ? value : 0.0;
    }
    weights.push_back(w);
  }
  return weights;
}

}  // namespace

void ShapeSpace::prepare(bool fit) {
  const Basis& basis = data_.basis;
  const Eigen::Index r = basis.dimension(), k = data_.coordinates.cols();
  num_rigid_ = basis.num_rigid;
  const double s = basis.scale;
  ghost_vectors_ = s * basis.ghost_vectors;
  // Every term of the ghost at each rest.
  BlendedEnergy full;
  full.rest = s * flatten(basis.ghost_vertices);
  full.vectors = ghost_vectors_;
  for (Eigen::Index j = 0; j <= k; ++j) {
    Eigen::VectorXd rest = full.rest;
    if (j > 0) rest += ghost_vectors_ * data_.coordinates.col(j - 1);
    if (!positions_in_range(rest))
      throw InputError(message(key_name(j - 1), ": its shape is out of range"));
    full.rests.push_back(ghost_energy(basis, rest));
  }
  const Eigen::MatrixXd free = ghost_vectors_.rightCols(r - num_rigid_);
  rest_hessians_.clear();
  for (Eigen::Index j = 0; j <= k; ++j) {
    const SparseMatrix H = full.rests[j]->hessian(full.rests[j]->rest());
    const Eigen::MatrixXd HU = H * free;
    rest_hessians_.push_back(free.transpose() * HU);
  }
  map_ = std::make_unique<FinePositions>(basis);
  q_ = Eigen::VectorXd::Zero(r);
  full.blended = ghost_energy(basis, full.rest);
  for (const auto& energy : full.rests) full.matches.push_back(full.blended->match_terms(*energy));
  full.x.resize(full.rest.size());
  full.gradient.resize(full.rest.size());
  if (fit) fit_cubature(full);
  // The cubature's energies: its terms at each rest, on its terms' vertices (ascending).
  const Cubature& cubature = data_.cubature;
  const DiscreteShells& basis_energy = *full.rests[0];
  const DiscreteShells::TermCounts counts = basis_energy.term_counts();
  const int total = counts.edges + counts.triangles + counts.hinges;
  if (!cubature.terms.empty() && cubature.terms.back() >= total)
    throw InputError(message("cubature: term ", cubature.terms.back(), " is not among the ghost's ",
                             total, " terms"));
  const std::vector<std::array<int, 4>> term_vertices = basis_energy.term_vertices();
  std::vector<int> vertices;
  for (int t : cubature.terms)
    for (int v : term_vertices[t])
      if (v >= 0) vertices.push_back(v);
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
  BlendedEnergy& energy = cubature_energy_;
  const Eigen::Index m = static_cast<Eigen::Index>(vertices.size());
  energy.rest.resize(3 * m);
  energy.vectors.resize(3 * m, r);
  for (Eigen::Index i = 0; i < m; ++i) {
    energy.rest.segment<3>(3 * i) = full.rest.segment<3>(3 * vertices[i]);
    energy.vectors.middleRows<3>(3 * i) = ghost_vectors_.middleRows<3>(3 * vertices[i]);
  }
  energy.rests.clear();
  energy.matches.clear();
  for (Eigen::Index j = 0; j <= k; ++j) {
    const DiscreteShells& rest = *full.rests[j];
    const DiscreteShells::TermMatch match = basis_energy.match_terms(rest);
    std::vector<int> terms;
    std::vector<double> factors;
    for (size_t i = 0; i < cubature.terms.size(); ++i) {
      const int t = matched_term(cubature.terms[i], match, counts, rest.term_counts());
      if (t < 0) continue;
      terms.push_back(t);
      factors.push_back(cubature.weights[i]);
    }
    energy.rests.push_back(
        std::make_unique<DiscreteShells>(rest.select_terms(terms, factors, vertices)));
  }
  energy.blended = std::make_unique<DiscreteShells>(
      basis_energy.select_terms(cubature.terms, cubature.weights, vertices));
  for (const auto& rest : energy.rests) energy.matches.push_back(energy.blended->match_terms(*rest));
  energy.x.resize(3 * m);
  energy.gradient.resize(3 * m);
  ghost_energy_ = std::move(full);
}

void ShapeSpace::fit_cubature(BlendedEnergy& full) {
  const Eigen::Index free = dimension() - num_rigid_;
  data_.cubature = {};
  if (free == 0) return;
  std::vector<CubatureSample> samples;
  std::vector<Eigen::VectorXd> visited;
  Eigen::VectorXd gradient;
  for (const Eigen::VectorXd& weights : training_weights(num_keys())) {
    visited.clear();
    minimize(weights, {&full}, {}, &visited);
    if (visited.empty()) continue;
    // Each point's equations weigh one over the reduced gradient's norm at the linear blend.
    objective(full, visited.front(), gradient);
    const double start_norm = gradient.norm();
    if (!(start_norm > 0)) continue;
    const size_t count = visited.size();
    for (int i = 0; i < kTrainingPoints; ++i) {
      const size_t at = count == 1 ? 0 : i * (count - 1) / (kTrainingPoints - 1);
      if (i > 0 && at == (i - 1) * (count - 1) / (kTrainingPoints - 1)) continue;
      objective(full, visited[at], gradient);
      samples.push_back({full.blended->term_gradients(full.x), 1.0 / start_norm});
    }
  }
  CubatureOptions fit_options = kCubatureFit;
  if (std::getenv("MD_CUB_TERMS")) fit_options.max_terms = std::atoi(std::getenv("MD_CUB_TERMS"));
  if (std::getenv("MD_CUB_TOL")) fit_options.tolerance = std::atof(std::getenv("MD_CUB_TOL"));
  const auto t0 = std::chrono::steady_clock::now();
  // Coordinates in which the rest's reduced Hessian is the identity: a gradient error e moves the
  // minimum by about H⁻¹ e, so the fit weighs errors along soft directions more.
  Eigen::MatrixXd H0 = rest_hessians_[0];
  H0.diagonal().array() += 1e-8 * H0.diagonal().maxCoeff();
  const Eigen::LLT<Eigen::MatrixXd> llt(H0);
  Eigen::MatrixXd whitened = full.vectors.rightCols(free);
  if (std::getenv("MD_CUB_WHITE") && llt.info() == Eigen::Success)
    whitened = llt.matrixL().solve(Eigen::MatrixXd(whitened.transpose())).transpose();
  data_.cubature = modal_deform::fit_cubature(whitened,
                                              full.blended->term_vertices(), samples, fit_options)
                       .cubature;
  if (std::getenv("MD_CUB_LOG")) std::fprintf(stderr, "samples %zu fit %g ms\n", samples.size(), milliseconds_since(t0));
}

double ShapeSpace::objective(BlendedEnergy& energy, const Eigen::VectorXd& z,
                             Eigen::VectorXd& gradient) {
  q_.tail(z.size()) = z;
  add_columns(energy.rest, energy.vectors, q_, energy.x);
  if (!positions_in_range(energy.x)) return std::numeric_limits<double>::infinity();
  const double value = energy.blended->value_and_gradient(energy.x, energy.gradient);
  gradient.noalias() = energy.vectors.rightCols(z.size()).transpose() * energy.gradient;
  return value;
}

BfgsResult ShapeSpace::minimize(const VectorRef& weights,
                                const std::vector<BlendedEnergy*>& energies,
                                const BlendOptions& options, std::vector<Eigen::VectorXd>* visited) {
  const Eigen::Index k = num_keys(), free = dimension() - num_rigid_;
  // The blended energy: the rest weighted 1 − Σ w_i.
  std::vector<double> c(static_cast<size_t>(k) + 1);
  std::vector<const DiscreteShells*> rests(c.size());
  c[0] = 1.0 - weights.sum();
  for (Eigen::Index i = 0; i < k; ++i) c[static_cast<size_t>(i) + 1] = weights[i];
  for (BlendedEnergy* energy : energies) {
    for (size_t j = 0; j < c.size(); ++j) rests[j] = energy->rests[j].get();
    energy->blended->blend_rests(rests, energy->matches, c);
  }
  // From the linear blend, rigid coordinates held, with (Σ |c_j| H_j)⁻¹.
  const Eigen::VectorXd linear = data_.coordinates * weights;
  q_ = linear;
  stats_ = {};
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
  BfgsResult result;
  const double loose = std::getenv("MD_LOOSE") ? std::atof(std::getenv("MD_LOOSE")) : 1e-6;
  for (size_t e = 0; e < energies.size(); ++e) {
    BlendedEnergy& energy = *energies[e];
    bfgs.objective_changed();
    const BfgsResult stage = bfgs.minimize(
        [&](const Eigen::VectorXd& z, Eigen::VectorXd& gradient) {
          if (visited) visited->push_back(z);
          return objective(energy, z, gradient);
        },
        options.max_iterations, e + 1 < energies.size() ? std::max(loose, options.tolerance) : options.tolerance);
    if (std::getenv("MD_CUB_LOG")) std::fprintf(stderr, "stage %zu its %d\n", e, stage.iterations);
    result.iterations += stage.iterations;
    result.evaluations += stage.evaluations;
    result.converged = stage.converged;
    result.stalled = stage.stalled;
  }
  q_.head(num_rigid_) = linear.head(num_rigid_);
  q_.tail(free) = bfgs.x();
  stats_.iterations = result.iterations;
  stats_.evaluations = result.evaluations;
  stats_.converged = result.converged;
  stats_.stalled = result.stalled;
  stats_.energy = bfgs.value();
  stats_.gradient_norm = bfgs.gradient().norm();
  stats_.solve_ms = milliseconds_since(solve_start);
  return result;
}

void ShapeSpace::blend(const VectorRef& weights, Eigen::Ref<Eigen::VectorXf> out,
                       const BlendOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  check_options(options, [](auto visit) { for_each_blend_option(visit); });
  const Eigen::Index k = num_keys(), free = dimension() - num_rigid_;
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
  const Eigen::VectorXd linear = data_.coordinates * weights;
  // Nothing but rigid coordinates, or no term with a gradient at any training blend (keys that
  // are rigid motions of the basis): the linear blend is the blend.
  if (free == 0 || data_.cubature.terms.empty()) {
    q_ = linear;
    stats_ = {};
    stats_.converged = true;
    write_positions(weights, out, start);
    return;
  }
  if (std::getenv("MD_TWO"))
    minimize(weights, {&cubature_energy_, &ghost_energy_}, options);
  else
    minimize(weights, {&cubature_energy_}, options);
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
