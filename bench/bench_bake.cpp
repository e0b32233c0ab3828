// The whole bake of the 100k-vertex dragon (dragon_vrip_res2) with a 1k ghost: 67 dimensions
// (20 modes + 47 derivatives) and 130 (21 modes + 109 derivatives: with 20 modes the dragon has
// 14 modes besides its rigid motions, whose 105 pairs cannot give 110 derivatives). Counters: the
// seconds of every stage (Basis::timings), the CPU seconds of the process between the stage
// changes the bake reports to its progress ("cpu <stage>": the ghost's thread counts towards the
// stages it runs during; the numeric factorisation towards "modes"), the dimension, the dragon's
// zero modes, and the peak resident memory of the bake.
#include <benchmark/benchmark.h>

#include <sys/resource.h>

#include <fstream>
#include <map>
#include <string>

#include "mesh/read_mesh.h"
#include "bake/bake.h"

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

// User and system CPU seconds of the whole process so far.
double cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const auto seconds = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * t.tv_usec; };
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
    std::ofstream("/proc/self/clear_refs") << "5";  // restart the high-water mark at the current RSS
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
  for (const auto& [stage, seconds] : basis.timings) state.counters[stage] = seconds;
  for (const auto& [stage, seconds] : cpu) state.counters["cpu " + stage] = seconds;
  state.counters["dimension"] = basis.dimension();
  state.counters["zero_modes"] = basis.num_floppy;
  state.counters["dropped"] = basis.num_dropped;
}
BENCHMARK(BM_Bake)
    ->Args({20, 47})
    ->Args({21, 109})
    ->ArgNames({"modes", "derivatives"})
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1)
    ->Repetitions(2);

}  // namespace
}  // namespace modal_deform
