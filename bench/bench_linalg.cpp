// Linear algebra of the bake on a shells-pattern matrix of the 100k-vertex dragon (300k DOFs): the
// Hessian of springs along edges and across hinges, shifted as for the eigensolver.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <vector>

#include "../tests/cpp/stand_in_stiffness.h"
#include "linalg/cholmod_llt.h"
#include "mesh/mass.h"
#include "mesh/mesh_topology.h"
#include "mesh/normalization.h"
#include "mesh/read_mesh.h"
#include "modes/rigid_motions.h"
#include "modes/stiffness_and_mass.h"
#include "modes/vibration_modes.h"

namespace modal_deform {
namespace {

struct Problem {
  SparseMatrix K;
  Eigen::VectorXd mass;
  Eigen::VectorXd shift;  // −σ M, plus a unit stiffness on the DOFs of unreferenced vertices
  Eigen::MatrixXd Z;      // rigid motions of the 7 components
};

const Problem& dragon() {
  static const Problem problem = [] {
    TriangleMesh mesh = read_mesh(MODAL_DEFORM_SHARED_MESHES "/dragon_vrip_res2.ply.gz");
    mesh.V *= normalizing_scale(mesh.V);
    Problem p{testing::spring_network_hessian(mesh.V, mesh.F), lumped_mass(mesh.V, mesh.F), {}, {}};
    const std::vector<int> labels = build_topology(mesh.V, mesh.F).vertex_component;
    p.Z = rigid_motions(
        mesh.V,
        Eigen::Map<const Eigen::VectorXi>(labels.data(), static_cast<Eigen::Index>(labels.size())),
        p.mass);
    const Eigen::VectorXd m = dof_masses(p.mass);
    const std::vector<bool> decoupled = decoupled_dofs(p.K, p.mass);
    p.shift = 1e-8 * p.K.diagonal().sum() / m.sum() * m;
    for (size_t d = 0; d < decoupled.size(); ++d)
      if (decoupled[d]) p.shift[static_cast<Eigen::Index>(d)] = 1.0;
    return p;
  }();
  return problem;
}

double minimum(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }

void BM_CholmodAnalyze(benchmark::State& state) {
  const Problem& p = dragon();
  for (auto _ : state) {
    CholmodLLT llt(3);
    llt.analyze(p.K);
    state.counters["L_nonzeros"] = llt.factor_nonzeros();
  }
  state.counters["rows"] = static_cast<double>(p.K.rows());
  state.counters["A_nonzeros"] = static_cast<double>(p.K.nonZeros());
}
BENCHMARK(BM_CholmodAnalyze)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(3)
    ->ComputeStatistics("min", minimum);

void BM_CholmodFactorize(benchmark::State& state) {
  const Problem& p = dragon();
  CholmodLLT llt(3);
  llt.analyze(p.K);
  for (auto _ : state) llt.factorize(p.K, p.shift);
}
BENCHMARK(BM_CholmodFactorize)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(3)
    ->ComputeStatistics("min", minimum);

void BM_CholmodSolve(benchmark::State& state) {
  const Problem& p = dragon();
  CholmodLLT llt(3);
  llt.factorize(p.K, p.shift);
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(p.K.rows(), state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(llt.solve(B));
}
BENCHMARK(BM_CholmodSolve)
    ->Arg(1)
    ->Arg(64)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3)
    ->Repetitions(3)
    ->ComputeStatistics("min", minimum);

// The lowest modes M-orthogonal to the rigid motions (the spring network also has 9 mechanisms).
void BM_VibrationModes(benchmark::State& state) {
  const Problem& p = dragon();
  for (auto _ : state) {
    const VibrationModes modes =
        vibration_modes(p.K, p.mass, static_cast<int>(state.range(0)), p.Z);
    state.counters["solves"] = modes.solves;
    state.counters["max_residual"] = modes.residuals.maxCoeff();
  }
}
BENCHMARK(BM_VibrationModes)
    ->Arg(20)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(2)
    ->ComputeStatistics("min", minimum);

}  // namespace
}  // namespace modal_deform
