// Posing: BFGS iterations and the fine-mesh mapping on the 100k-vertex dragon with a 1k ghost
// (67 and 130 dimensions), and the full-space reference solve on the generated test shapes.
#include <benchmark/benchmark.h>

#include <cmath>
#include <map>

#include "bake/bake.h"
#include "mesh/primitives.h"
#include "mesh/read_mesh.h"
#include "solve/full_solver.h"
#include "solve/quantized_vectors.h"
#include "solve/reduced_solver.h"

namespace modal_deform {
namespace {

constexpr double kPi = 3.14159265358979323846;

// x ↦ R (x − centre) + centre + t, R a rotation by `angle` about `axis`.
Eigen::Matrix4d rigid(const Eigen::Vector3d& axis, double angle, const Eigen::Vector3d& centre,
                      const Eigen::Vector3d& t = Eigen::Vector3d::Zero()) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = R;
  T.topRightCorner<3, 1>() = centre + t - R * centre;
  return T;
}

// A rod along z (length L, axis through `axis`): its two end rings or faces as handles, the
// far one bent by `bend` into a circular arc in the y-z plane and twisted by `twist`.
struct Rod {
  TriangleMesh mesh;
  Handles handles{{}, {}};
  Transforms transforms;
  Rod(TriangleMesh m, double L, const Eigen::Vector3d& axis, double bend, double twist)
      : mesh(std::move(m)) {
    for (int v = 0; v < mesh.V.rows(); ++v) {
      if (mesh.V(v, 2) < 1e-9) handles[0].push_back(v);
      if (mesh.V(v, 2) > L - 1e-9) handles[1].push_back(v);
    }
    Eigen::Matrix4d down = Eigen::Matrix4d::Identity();
    down(2, 3) = -L;
    const Eigen::Matrix4d end = rigid({-1, 0, 0}, bend, axis + Eigen::Vector3d(0, L / bend, 0)) *
                                down * rigid({0, 0, 1}, twist, axis);
    transforms = {Eigen::Matrix4d::Identity(), end};
  }
};

// dragon_vrip_res2 baked once with 25 modes and 105 derivatives: 130 columns (it has no zero
// modes since its doubled triangles are attached; with them, 20 + 104 made 130). The
// 67-dimensional basis is its first 67 columns (a prefix stays M-orthonormal).
const Basis& dragon_basis(int dimension) {
  static std::map<int, Basis> bases;
  if (bases.empty()) {
    const TriangleMesh mesh = read_mesh(MODAL_DEFORM_SHARED_MESHES "/dragon_vrip_res2.ply.gz");
    Progress quiet;
    Basis full =
        bake(mesh.V, mesh.F, BakeOptions{25, 105, 1000, EnergyKind::kShells, {1.0, 1.0}}, quiet);
    Basis prefix = full;
    prefix.vectors = full.vectors.leftCols(67);
    prefix.ghost_vectors = full.ghost_vectors.leftCols(67);
    bases.emplace(full.dimension(), std::move(full));
    bases.emplace(67, std::move(prefix));
  }
  return bases.at(dimension);
}

// The dragon's tail held and its head pulled and turned, in 60 frames of up to 10 iterations.
struct DragonPose {
  Handles handles{{}, {}};
  Eigen::Vector3d head_centre = Eigen::Vector3d::Zero();
  double length;
  explicit DragonPose(const Basis& basis) {
    const RowMatrixX3d& V = basis.rest;
    const double x0 = V.col(0).minCoeff(), x1 = V.col(0).maxCoeff();
    length = x1 - x0;
    for (int v = 0; v < V.rows(); ++v) {
      if (V(v, 0) < x0 + 0.1 * length) handles[0].push_back(v);
      if (V(v, 0) > x1 - 0.1 * length) {
        handles[1].push_back(v);
        head_centre += V.row(v).transpose();
      }
    }
    head_centre /= static_cast<double>(handles[1].size());
  }
  Transforms at(double t) const {
    return {Eigen::Matrix4d::Identity(),
            rigid({0, 0, 1}, 0.6 * t, head_centre, {0, 0.25 * length * t, 0})};
  }
};

void BM_BfgsIteration(benchmark::State& state) {
  const Basis& basis = dragon_basis(static_cast<int>(state.range(0)));
  const DragonPose pose(basis);
  ReducedSolver solver(basis, pose.handles, Eigen::VectorXd(), 1000);
  int iterations = 0, evaluations = 0;
  double milliseconds = 0;
  for (auto _ : state) {
    state.PauseTiming();
    solver.reset();
    state.ResumeTiming();
    for (int frame = 1; frame <= 60; ++frame) {
      solver.set_transforms(pose.at(frame / 60.0));
      const ReducedSolveStats stats = solver.solve(10, 1e-6);
      iterations += stats.iterations;
      evaluations += stats.evaluations;
      milliseconds += stats.ms;
    }
  }
  state.counters["dimension"] = basis.dimension();
  state.counters["ghost_vertices"] = static_cast<double>(basis.ghost_vertices.rows());
  state.counters["evaluations_per_iteration"] = static_cast<double>(evaluations) / iterations;
  // Time per BFGS iteration, the unit the paper reports (solve() alone, not set_transforms).
  state.counters["ms_per_iteration"] = milliseconds / iterations;
  state.counters["iterations_per_frame"] = iterations / (60.0 * state.iterations());
}
BENCHMARK(BM_BfgsIteration)->Arg(67)->Arg(130)->Unit(benchmark::kMillisecond);

void BM_Positions(benchmark::State& state) {
  const Basis& basis = dragon_basis(static_cast<int>(state.range(0)));
  const DragonPose pose(basis);
  ReducedSolver solver(basis, pose.handles, Eigen::VectorXd(), 1000);
  solver.set_transforms(pose.at(1));
  solver.solve(20, 1e-6);
  Eigen::VectorXf out(3 * basis.num_vertices());
  for (auto _ : state) solver.positions(out);
  state.counters["vertices"] = basis.num_vertices();
  state.counters["dimension"] = basis.dimension();
  state.SetBytesProcessed(state.iterations() * basis.vectors.size() *
                          static_cast<int64_t>(sizeof(float)));
}
BENCHMARK(BM_Positions)->Arg(67)->Arg(130)->Unit(benchmark::kMillisecond);

// x̄ + U q at 67 dimensions, the pose of BM_Positions, read from 16 bits within positions()'s
// tolerance (Arg 16) or from float32 alone (Arg 32: tolerance 0 sends every block to float32, the
// map as it was before the 16-bit copy). Run with --benchmark_enable_random_interleaving.
void BM_MapBits(benchmark::State& state) {
  const Basis& basis = dragon_basis(67);
  const DragonPose pose(basis);
  ReducedSolver solver(basis, pose.handles, Eigen::VectorXd(), 1000);
  solver.set_transforms(pose.at(1));
  solver.solve(20, 1e-6);
  const Eigen::VectorXf q = solver.q().cast<float>();
  const QuantizedVectors quantized(basis.vectors);
  const double diagonal =
      (basis.rest.colwise().maxCoeff() - basis.rest.colwise().minCoeff()).norm();
  const double tolerance = state.range(0) == 16 ? FinePositions::kTolerance * diagonal : 0.0;
  Eigen::VectorXf out(3 * basis.num_vertices());
  const Eigen::VectorXf rest = flatten(basis.rest).cast<float>();
  Eigen::Index from_float32 = 0;
  for (auto _ : state)
    from_float32 = quantized.map(basis.vectors, q, rest.data(), tolerance, out.data());
  state.counters["blocks_from_float32"] = static_cast<double>(from_float32) / quantized.blocks();
}
BENCHMARK(BM_MapBits)->Arg(32)->Arg(16)->Unit(benchmark::kMillisecond);

void run(benchmark::State& state, const Rod& rod) {
  const EnergyKind energy = state.range(0) == 0 ? EnergyKind::kShells : EnergyKind::kArap;
  FullSolveResult result;
  for (auto _ : state)
    result = solve_full(rod.mesh.V, rod.mesh.F, rod.handles, Eigen::VectorXd(), rod.transforms,
                        1000, FullSolveOptions{energy, {1.0, 1.0}, 1e-8, 200});
  state.SetLabel(energy == EnergyKind::kShells ? "shells" : "arap");
  state.counters["vertices"] = static_cast<double>(rod.mesh.V.rows());
  state.counters["steps"] = result.steps;
  state.counters["iterations"] = result.iterations;
  state.counters["factorizations"] = result.factorizations;
  state.counters["converged"] = result.converged;
}

// A closed 1 x 1 x 10 bar (1.5k vertices) bent by 90 degrees.
void BM_SolveFullBar(benchmark::State& state) {
  static const Rod rod(bar(6, 6, 60, 1, 1, 10), 10, {0.5, 0.5, 0}, kPi / 2, 0);
  run(state, rod);
}
BENCHMARK(BM_SolveFullBar)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// An open tube of radius 1 and length 8 (2k vertices) bent by 60 and twisted by 90 degrees.
void BM_SolveFullCylinder(benchmark::State& state) {
  static const Rod rod(cylinder(32, 60, 1.0, 8.0), 8, {0, 0, 0}, kPi / 3, kPi / 2);
  run(state, rod);
}
BENCHMARK(BM_SolveFullCylinder)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace modal_deform
