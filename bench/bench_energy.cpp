// Energy stage: the discrete shells energy on the 100k-vertex dragon (scaled to the paper's
// extent of 10) and, for the reduced solver's ghost, value + gradient on a 1k-vertex tube.
// Targets on 2 cores: value + gradient <= 30 ms and Hessian <= 250 ms on the dragon, about
// 0.1 ms for value + gradient on the ghost.
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "energy/discrete_shells.h"
#include "mesh/normalization.h"
#include "mesh/primitives.h"
#include "mesh/read_mesh.h"

namespace modal_deform {
namespace {

const TriangleMesh& dragon() {
  static const TriangleMesh mesh = [] {
    TriangleMesh m = read_mesh(MODAL_DEFORM_SHARED_MESHES "/dragon_vrip_res2.ply.gz");
    m.V *= normalizing_scale(m.V);
    return m;
  }();
  return mesh;
}

const DiscreteShells& dragon_shells() {
  static const DiscreteShells energy(dragon().V, dragon().F);
  return energy;
}

// A smooth large deformation of the rest state: a twist about z and a stretch along x.
Eigen::VectorXd deformed(const RowMatrixX3d& V) {
  RowMatrixX3d X = V;
  for (Eigen::Index i = 0; i < X.rows(); ++i) {
    const double angle = 0.05 * V(i, 2);
    const double c = std::cos(angle), s = std::sin(angle);
    X(i, 0) = 1.2 * (c * V(i, 0) - s * V(i, 1));
    X(i, 1) = s * V(i, 0) + c * V(i, 1);
  }
  return Eigen::Map<const Eigen::VectorXd>(X.data(), X.size());
}

Eigen::MatrixXd random_columns(Eigen::Index rows, int columns) {
  std::mt19937 generator(7);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd Phi(rows, columns);
  for (Eigen::Index i = 0; i < Phi.size(); ++i) Phi.data()[i] = normal(generator);
  return Phi;
}

void BM_ShellsConstruct(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(DiscreteShells(dragon().V, dragon().F));
  state.counters["vertices"] = static_cast<double>(dragon().V.rows());
}
BENCHMARK(BM_ShellsConstruct)->Unit(benchmark::kMillisecond);

void BM_ShellsValue(benchmark::State& state) {
  const DiscreteShells& energy = dragon_shells();
  const Eigen::VectorXd x = deformed(dragon().V);
  for (auto _ : state) benchmark::DoNotOptimize(energy.value(x));
}
BENCHMARK(BM_ShellsValue)->Unit(benchmark::kMillisecond);

void BM_ShellsValueAndGradient(benchmark::State& state) {
  const DiscreteShells& energy = dragon_shells();
  const Eigen::VectorXd x = deformed(dragon().V);
  Eigen::VectorXd gradient(x.size());
  for (auto _ : state) benchmark::DoNotOptimize(energy.value_and_gradient(x, gradient));
}
BENCHMARK(BM_ShellsValueAndGradient)->Unit(benchmark::kMillisecond);

void BM_ShellsHessian(benchmark::State& state) {
  const DiscreteShells& energy = dragon_shells();
  const Eigen::VectorXd x = deformed(dragon().V);
  for (auto _ : state) benchmark::DoNotOptimize(energy.hessian(x));
}
BENCHMARK(BM_ShellsHessian)->Unit(benchmark::kMillisecond);

// What the bake asks: at rest f' = 0 and ∇²s is not needed.
void BM_ShellsHessianAtRest(benchmark::State& state) {
  const DiscreteShells& energy = dragon_shells();
  for (auto _ : state) benchmark::DoNotOptimize(energy.hessian(energy.rest()));
}
BENCHMARK(BM_ShellsHessianAtRest)->Unit(benchmark::kMillisecond);

void BM_ShellsThird(benchmark::State& state) {
  const DiscreteShells& energy = dragon_shells();
  const Eigen::VectorXd x = deformed(dragon().V);
  const Eigen::MatrixXd uw = random_columns(x.size(), 2);
  for (auto _ : state) benchmark::DoNotOptimize(energy.third(x, uw.col(0), uw.col(1)));
}
BENCHMARK(BM_ShellsThird)->Unit(benchmark::kMillisecond);

// What the bake asks at rest: 47 pairs i <= j of 10 modes (the paper's 67-dimensional basis
// minus the 20 modes).
void BM_ShellsThirdBatch47(benchmark::State& state) {
  const DiscreteShells& energy = dragon_shells();
  const Eigen::MatrixXd Phi = random_columns(energy.rest().size(), 10);
  std::vector<std::array<int, 2>> pairs;
  for (int j = 0; j < 10 && pairs.size() < 47; ++j)
    for (int i = 0; i <= j && pairs.size() < 47; ++i) pairs.push_back({i, j});
  for (auto _ : state) benchmark::DoNotOptimize(energy.third_batch(energy.rest(), Phi, pairs));
  state.counters["pairs"] = static_cast<double>(pairs.size());
}
BENCHMARK(BM_ShellsThirdBatch47)->Unit(benchmark::kMillisecond);

void BM_ShellsValueAndGradientGhost(benchmark::State& state) {
  TriangleMesh tube = cylinder(32, 31, 1.0, 4.0);  // 1024 vertices
  tube.V *= normalizing_scale(tube.V);
  const DiscreteShells energy(tube.V, tube.F);
  const Eigen::VectorXd x = deformed(tube.V);
  Eigen::VectorXd gradient(x.size());
  for (auto _ : state) benchmark::DoNotOptimize(energy.value_and_gradient(x, gradient));
  state.counters["vertices"] = static_cast<double>(tube.V.rows());
}
BENCHMARK(BM_ShellsValueAndGradientGhost)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace modal_deform
