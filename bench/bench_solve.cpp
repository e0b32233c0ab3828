// Posing: the full-space reference solve on the generated test shapes (time to converge).
#include <benchmark/benchmark.h>

#include <cmath>

#include "mesh/primitives.h"
#include "solve/full_solver.h"

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
  Rod(TriangleMesh m, double L, const Eigen::Vector3d& axis, double bend, double twist) : mesh(std::move(m)) {
    for (int v = 0; v < mesh.V.rows(); ++v) {
      if (mesh.V(v, 2) < 1e-9) handles[0].push_back(v);
      if (mesh.V(v, 2) > L - 1e-9) handles[1].push_back(v);
    }
    Eigen::Matrix4d down = Eigen::Matrix4d::Identity();
    down(2, 3) = -L;
    const Eigen::Matrix4d end =
        rigid({-1, 0, 0}, bend, axis + Eigen::Vector3d(0, L / bend, 0)) * down * rigid({0, 0, 1}, twist, axis);
    transforms = {Eigen::Matrix4d::Identity(), end};
  }
};

void run(benchmark::State& state, const Rod& rod) {
  const EnergyKind energy = state.range(0) == 0 ? EnergyKind::kShells : EnergyKind::kArap;
  FullSolveResult result;
  for (auto _ : state)
    result = solve_full(rod.mesh.V, rod.mesh.F, rod.handles, Eigen::VectorXd(), rod.transforms, 1000, energy, 1.0, 1.0,
                        1e-8, 200);
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
