// The whole bake of the 100k-vertex dragon (dragon_vrip_res2) with a 1k ghost at the paper's two
// sizes, with its pairs (the linearised rotations included): 67 dimensions (15 modes + 52
// derivatives) and 130 (20 + 110). Counters: the seconds of every stage (Basis::timings), the CPU
// seconds of the process between the stage changes the bake reports to its progress ("cpu
// <stage>": the ghost's thread counts towards the stages it runs during; the numeric
// factorisation towards "modes"), the dimension, the dragon's zero modes, the peak resident
// memory of the bake, and "cholmod_s": CHOLMOD alone analysing and factoring K − σM of the same
// stiffness matrix in the same process right after the bake, the floor the bake is measured
// against (bench/bake_limit.py), with the cost of its solves per right-hand side.
#include <benchmark/benchmark.h>

#include <sys/resource.h>

#include <fstream>
#include <map>
#include <string>

#include "bake/bake.h"
#include "energy/discrete_shells.h"
#include "linalg/cholmod_llt.h"
#include "mesh/mass.h"
#include "mesh/normalization.h"
#include "mesh/read_mesh.h"
#include "modes/stiffness_and_mass.h"
#include "reduction/attachment.h"
#include "util/stopwatch.h"

namespace modal_deform {
namespace {

const TriangleMesh& dragon() {
  static const TriangleMesh mesh = read_mesh(MODAL_DEFORM_SHARED_MESHES "/dragon_vrip_res2.ply.gz");
  return mesh;
}

// Resident-set high-water mark of this process in MB, from /proc/self/status (VmHWM).
double peak_rss_mb() {
  std::ifstream status("/proc/self/status");
  std::string key;
  double kb = 0;
  while (status >> key) {
    if (key == "VmHWM:") {
      status >> kb;
      break;
    }
  }
  return kb / 1024;
}

// CHOLMOD alone on K − σM for the bake's K (the shells Hessian of the simulated submesh in the
// normalised frame) and the bake's σ for deflated rigid motions: seconds to analyse and factor,
// and milliseconds per right-hand side of a solve one, 8 and 52 wide (the eigensolver's blocks and
// the derivatives'). Together with the right-hand sides a bake needs, the floor of its time.
struct CholmodAlone {
  double seconds = 0;
  std::map<int, double> ms_per_rhs;  // by block width
};

CholmodAlone cholmod_alone(const TriangleMesh& mesh) {
  const Attachment attachment = attach(mesh.V, mesh.F);
  const double scale = normalizing_scale(mesh.V);
  const Eigen::VectorXd fine_mass = lumped_mass(mesh.V, mesh.F);
  const auto S = static_cast<Eigen::Index>(attachment.simulated.size());
  RowMatrixX3d V(S, 3);
  Eigen::VectorXd mass(S);
  for (Eigen::Index s = 0; s < S; ++s) {
    V.row(s) = scale * mesh.V.row(attachment.simulated[static_cast<size_t>(s)]);
    mass[s] = scale * scale * fine_mass[attachment.simulated[static_cast<size_t>(s)]];
  }
  const DiscreteShells shells(V, attachment.faces);
  const SparseMatrix K = shells.hessian(shells.rest());
  const Eigen::VectorXd m = dof_masses(mass);
  const Eigen::VectorXd shift = 1e-10 * K.diagonal().sum() / m.sum() * m;
  CholmodAlone alone;
  CholmodLLT llt(3);
  {
    const Stopwatch stopwatch(alone.seconds);
    llt.analyze(K);
    llt.factorize(K, shift, 0.0);
  }
  for (const int width : {1, 8, 52}) {
    const Eigen::MatrixXd B = Eigen::MatrixXd::Random(K.rows(), width);
    llt.solve_in_workspace(B);  // the workspace allocated and touched once, as in the bake
    double seconds = 0;
    constexpr int kRepeats = 3;
    {
      const Stopwatch stopwatch(seconds);
      for (int r = 0; r < kRepeats; ++r) llt.solve_in_workspace(B);
    }
    alone.ms_per_rhs[width] = 1e3 * seconds / (kRepeats * width);
  }
  return alone;
}

// User and system CPU seconds of the whole process so far.
double cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const auto seconds = [](const timeval& t) {
    return static_cast<double>(t.tv_sec) + 1e-6 * t.tv_usec;
  };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

void BM_Bake(benchmark::State& state) {
  const TriangleMesh& mesh = dragon();
  BakeOptions options;
  options.modes = static_cast<int>(state.range(0));
  options.derivatives = static_cast<int>(state.range(1));
  options.ghost = 1000;
  Basis basis;
  std::map<std::string, double> cpu;
  for (auto _ : state) {
    std::ofstream("/proc/self/clear_refs")
        << "5";  // restart the high-water mark at the current RSS
    cpu.clear();
    std::string stage = "validation";
    double since = cpu_seconds();
    const auto account = [&](const std::string& next) {
      const double now = cpu_seconds();
      cpu[stage] += now - since;
      stage = next;
      since = now;
    };
    // A stage's first report always reaches the callback (util/progress.h).
    Progress progress([&](const std::string& reported, double) {
      if (reported != stage) account(reported);
      return true;
    });
    basis = bake(mesh.V, mesh.F, options, progress);
    account("");
    state.counters["peak_rss_MB"] = peak_rss_mb();
  }
  const CholmodAlone alone = cholmod_alone(mesh);
  state.counters["cholmod_s"] = alone.seconds;
  for (const auto& [width, ms] : alone.ms_per_rhs)
    state.counters["solve_ms_per_rhs_" + std::to_string(width)] = ms;
  for (const auto& [stage, seconds] : basis.timings) state.counters[stage] = seconds;
  for (const auto& [stage, seconds] : cpu) state.counters["cpu " + stage] = seconds;
  state.counters["dimension"] = basis.dimension();
  state.counters["zero_modes"] = basis.num_floppy;
  state.counters["dropped"] = basis.num_dropped;
}
BENCHMARK(BM_Bake)
    ->Args({15, 52})
    ->Args({20, 110})
    ->ArgNames({"modes", "derivatives"})
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1)
    ->Repetitions(1);

}  // namespace
}  // namespace modal_deform
