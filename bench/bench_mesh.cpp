// Mesh stage: topology and mass on the 100k-vertex dragon.
#include <benchmark/benchmark.h>

#include "mesh/mass.h"
#include "mesh/mesh_topology.h"
#include "mesh/read_mesh.h"

namespace modal_deform {
namespace {

const TriangleMesh& dragon() {
  static const TriangleMesh mesh = read_mesh(MODAL_DEFORM_SHARED_MESHES "/dragon_vrip_res2.ply.gz");
  return mesh;
}

void BM_Topology(benchmark::State& state) {
  const TriangleMesh& mesh = dragon();
  for (auto _ : state) benchmark::DoNotOptimize(build_topology(mesh.V, mesh.F));
  state.counters["vertices"] = static_cast<double>(mesh.V.rows());
}
BENCHMARK(BM_Topology)->Unit(benchmark::kMillisecond);

void BM_LumpedMass(benchmark::State& state) {
  const TriangleMesh& mesh = dragon();
  for (auto _ : state) benchmark::DoNotOptimize(lumped_mass(mesh.V, mesh.F));
}
BENCHMARK(BM_LumpedMass)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace modal_deform
