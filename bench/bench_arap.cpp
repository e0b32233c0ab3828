// ARAP energy: value+gradient and Hessian on the 100k-vertex dragon, and value+gradient on a
// 1k-vertex tube (the size of the reduced solver's ghost mesh, evaluated every BFGS iteration).
#include <benchmark/benchmark.h>

#include <random>

#include "energy/arap.h"
#include "mesh/normalization.h"
#include "mesh/primitives.h"
#include "mesh/read_mesh.h"

namespace modal_deform {
namespace {

// The mesh scaled to the paper's frame, with the energy and a deformed state (rest + noise of a
// few per cent of an edge, so every cell rotates and stretches).
struct Setup {
  TriangleMesh mesh;
  Arap energy;
  Eigen::VectorXd x;

  explicit Setup(TriangleMesh m)
      : mesh(scaled(std::move(m))), energy(mesh.V, mesh.F), x(energy.rest()) {
    std::mt19937 random(1);
    std::normal_distribution<double> noise(0.0, 0.01);
    for (Eigen::Index i = 0; i < x.size(); ++i) x[i] += noise(random);
  }
  static TriangleMesh scaled(TriangleMesh m) {
    m.V *= normalizing_scale(m.V);
    return m;
  }
};

const Setup& dragon() {
  static const Setup setup(read_mesh(MODAL_DEFORM_SHARED_MESHES "/dragon_vrip_res2.ply.gz"));
  return setup;
}

const Setup& tube() {
  static const Setup setup(cylinder(32, 31, 1.0, 4.0));
  return setup;
}

void value_and_gradient(benchmark::State& state, const Setup& setup) {
  Eigen::VectorXd gradient(setup.x.size());
  for (auto _ : state) benchmark::DoNotOptimize(setup.energy.value_and_gradient(setup.x, gradient));
  state.counters["vertices"] = static_cast<double>(setup.mesh.V.rows());
}

void BM_ArapValueGradientDragon(benchmark::State& state) { value_and_gradient(state, dragon()); }
BENCHMARK(BM_ArapValueGradientDragon)->Unit(benchmark::kMillisecond);

void BM_ArapHessianDragon(benchmark::State& state) {
  const Setup& setup = dragon();
  for (auto _ : state) benchmark::DoNotOptimize(setup.energy.hessian(setup.x));
  state.counters["nonzeros"] = static_cast<double>(setup.energy.hessian(setup.x).nonZeros());
}
BENCHMARK(BM_ArapHessianDragon)->Unit(benchmark::kMillisecond);

void BM_ArapValueGradientTube1k(benchmark::State& state) { value_and_gradient(state, tube()); }
BENCHMARK(BM_ArapValueGradientTube1k)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace modal_deform
