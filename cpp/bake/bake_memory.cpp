#include "bake/bake_memory.h"

#include "util/win32.h"
#ifndef _WIN32
#include <sys/resource.h>
#include <unistd.h>
#endif

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string>

#include "util/errors.h"

namespace modal_deform {
namespace {

// Dense columns of 3#S doubles alive at once besides the ones the bake keeps throughout (modes,
// rigid motions): the block Lanczos vectors while the modes are computed (6 per mode asked for on
// the dragons; up to 12 are allowed, but memory never written is not taken); during the
// derivative solves eight blocks as wide as the derivatives (right-hand sides, their projection,
// the solution, residual, correction, CHOLMOD's solution and workspace, and one for what the
// allocator holds back). The estimates against the measured peaks of whole processes:
// bench/results/raw_scan.json.
constexpr double kLanczosColumnsPerMode = 6;
constexpr double kDerivativeBlocks = 8;
// Bytes per vertex for the mesh, its topology, the energy's terms, the ghost and the attachment.
constexpr double kMeshBytesPerVertex = 1200;
// Bytes per stiffness entry alive during the factorisation: K (value, row index), the lower
// triangle CHOLMOD factors and the copy it is built in.
constexpr double kStiffnessBytesPerEntry = 24;

// A GB figure for messages.
std::string gigabytes(double bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f GB", bytes / 1e9);
  return text;
}

#ifdef _WIN32
// Physical memory not in use (what /proc/meminfo's MemAvailable is on Linux); infinity when
// unknown.
double system_available() {
  MEMORYSTATUSEX status{};
  status.dwLength = sizeof status;
  if (!GlobalMemoryStatusEx(&status)) return std::numeric_limits<double>::infinity();
  return static_cast<double>(status.ullAvailPhys);
}

// What the process may still commit (RAM and page file): past it, allocations fail.
double address_space_left() {
  MEMORYSTATUSEX status{};
  status.dwLength = sizeof status;
  if (!GlobalMemoryStatusEx(&status)) return std::numeric_limits<double>::infinity();
  return static_cast<double>(status.ullAvailPageFile);
}
#else
// "MemAvailable: 123456 kB" from /proc/meminfo, in bytes; infinity when not found.
double system_available() {
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  double kilobytes = 0;
  std::string unit;
  while (meminfo >> key >> kilobytes >> unit)
    if (key == "MemAvailable:") return 1024 * kilobytes;
  return std::numeric_limits<double>::infinity();
}

// The address-space limit less the process's mapped size; infinity without a limit.
double address_space_left() {
  rlimit limit{};
  if (getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY)
    return std::numeric_limits<double>::infinity();
  std::ifstream statm("/proc/self/statm");
  double pages = 0;
  if (!(statm >> pages)) return std::numeric_limits<double>::infinity();
  return static_cast<double>(limit.rlim_cur) - pages * static_cast<double>(sysconf(_SC_PAGESIZE));
}
#endif

}  // namespace

BakeMemory estimate_bake_memory(Eigen::Index vertices, Eigen::Index simulated,
                                double stiffness_nonzeros, double factor_bytes, int modes,
                                int derivatives) {
  BakeMemory need;
  need.mesh = kMeshBytesPerVertex * static_cast<double>(vertices);
  need.stiffness = kStiffnessBytesPerEntry * stiffness_nonzeros;
  need.factor = factor_bytes;
  const double column = 8.0 * 3 * static_cast<double>(simulated);
  const double kept = modes + 6.0;  // modes, a few zero modes
  const double widest =
      std::max(kLanczosColumnsPerMode * (modes + 6.0), kDerivativeBlocks * derivatives);
  // The assembly holds U on the simulated and on all vertices, in double and in float.
  const double assembly =
      8.0 * 3 * static_cast<double>(simulated + vertices) + 4.0 * 3 * static_cast<double>(vertices);
  need.vectors = std::max(column * (kept + widest), assembly * (modes + derivatives + 6.0));
  return need;
}

double available_memory() { return std::min(system_available(), address_space_left()); }

void require_memory(const BakeMemory& need, double available) {
  if (need.total() <= available) return;
  throw OutOfMemory(message(
      "bake: not enough memory: the bake needs about ", gigabytes(need.total()), " (factor of K ",
      gigabytes(need.factor), " from CHOLMOD's analysis, stiffness matrix ",
      gigabytes(need.stiffness), ", basis vectors ", gigabytes(need.vectors), ", mesh ",
      gigabytes(need.mesh), ") but only ", gigabytes(available),
      " is available (free memory, or the process's address-space limit); close other "
      "programs, bake fewer modes and derivatives, or decimate the mesh"));
}

}  // namespace modal_deform
