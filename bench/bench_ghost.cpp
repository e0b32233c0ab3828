// Ghost stage: edge collapse of the 100k-vertex dragon to the paper's ghost sizes, and the
// restriction of a 130-vector basis (20 modes + 110 derivatives) to a 1k ghost.
#include <benchmark/benchmark.h>

#include "mesh/mass.h"
#include "mesh/read_mesh.h"
#include "reduction/ghost.h"

namespace modal_deform {
namespace {

struct Dragon {
  TriangleMesh mesh = read_mesh(MODAL_DEFORM_SHARED_MESHES "/dragon_vrip_res2.ply.gz");
  Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
};

const Dragon& dragon() {
  static const Dragon loaded;
  return loaded;
}

void BM_GhostMesh(benchmark::State& state) {
  const Dragon& d = dragon();
  const int target = static_cast<int>(state.range(0));
  Ghost ghost;
  for (auto _ : state) ghost = ghost_mesh(d.mesh.V, d.mesh.F, d.mass, target);
  state.counters["fine_vertices"] = static_cast<double>(d.mesh.V.rows());
  state.counters["ghost_vertices"] = static_cast<double>(ghost.V.rows());
  state.counters["ghost_faces"] = static_cast<double>(ghost.F.rows());
}
BENCHMARK(BM_GhostMesh)->Arg(500)->Arg(1000)->Arg(2500)->Arg(5000)->Unit(benchmark::kMillisecond);

void BM_RestrictToGhost(benchmark::State& state) {
  const Dragon& d = dragon();
  const Ghost ghost = ghost_mesh(d.mesh.V, d.mesh.F, d.mass, 1000);
  const Eigen::MatrixXd U = Eigen::MatrixXd::Random(3 * d.mesh.V.rows(), state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(restrict_to_ghost(ghost, d.mass, U));
  state.counters["fine_vertices"] = static_cast<double>(d.mesh.V.rows());
  state.counters["columns"] = static_cast<double>(U.cols());
  state.SetBytesProcessed(state.iterations() * U.size() * static_cast<int64_t>(sizeof(double)));
}
BENCHMARK(BM_RestrictToGhost)->Arg(130)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace modal_deform
