#include "linalg/blas_threads.h"

#include "util/win32.h"
#ifndef _WIN32
#include <dlfcn.h>
#include <sched.h>
#endif

#include <algorithm>
#include <mutex>
#include <thread>

#include <cholmod.h>

namespace modal_deform {
namespace {

struct OpenBlasThreads {
  int (*get)() = nullptr;
  void (*set)(int) = nullptr;
};

#ifdef _WIN32
// The Windows extension links CHOLMOD statically against the OpenBLAS DLL it bundles
// (windows/windows.mk): its thread controls are imported by name from that DLL.
extern "C" int openblas_get_num_threads(void);
extern "C" void openblas_set_num_threads(int);

const OpenBlasThreads& openblas_threads() {
  static const OpenBlasThreads found{openblas_get_num_threads, openblas_set_num_threads};
  return found;
}

int usable_cores() {
  DWORD_PTR process = 0, system = 0;
  if (GetProcessAffinityMask(GetCurrentProcess(), &process, &system) && process != 0)
    return __builtin_popcountll(process);
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}
#else
// The thread controls of the OpenBLAS that CHOLMOD itself calls: looked up among CHOLMOD's own
// dependencies, since a process may hold several BLAS libraries (NumPy's, a wheel's bundled copy).
const OpenBlasThreads& openblas_threads() {
  static const OpenBlasThreads found = [] {
    OpenBlasThreads threads;
    Dl_info info{};
    if (dladdr(reinterpret_cast<void*>(&cholmod_factorize), &info) == 0 ||
        info.dli_fname == nullptr)
      return threads;
    void* cholmod = dlopen(info.dli_fname, RTLD_LAZY | RTLD_NOLOAD);
    if (cholmod == nullptr) return threads;
    threads.get = reinterpret_cast<int (*)()>(dlsym(cholmod, "openblas_get_num_threads"));
    threads.set = reinterpret_cast<void (*)(int)>(dlsym(cholmod, "openblas_set_num_threads"));
    dlclose(cholmod);  // drops only the reference RTLD_NOLOAD took: CHOLMOD stays linked
    if (threads.get == nullptr || threads.set == nullptr) threads = OpenBlasThreads{};
    return threads;
  }();
  return found;
}

int usable_cores() {
  cpu_set_t cpus;
  if (sched_getaffinity(0, sizeof(cpus), &cpus) == 0) return CPU_COUNT(&cpus);
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}
#endif

// Limits nest and may live on several threads at once (two bakes): the first one saves the
// caller's setting, the last one restores it.
std::mutex limit_mutex;
int live_limits = 0;
int callers_threads = 0;

}  // namespace

int BlasThreadLimit::most_threads() { return std::max(1, usable_cores() - 1); }

int BlasThreadLimit::current() {
  const OpenBlasThreads& threads = openblas_threads();
  return threads.get ? threads.get() : 0;
}

BlasThreadLimit::BlasThreadLimit() {
  const OpenBlasThreads& threads = openblas_threads();
  if (!threads.get) return;
  const std::lock_guard<std::mutex> lock(limit_mutex);
  if (live_limits++ > 0) return;
  callers_threads = threads.get();
  if (callers_threads > most_threads()) threads.set(most_threads());
}

BlasThreadLimit::~BlasThreadLimit() {
  const OpenBlasThreads& threads = openblas_threads();
  if (!threads.get) return;
  const std::lock_guard<std::mutex> lock(limit_mutex);
  if (--live_limits > 0) return;
  if (threads.get() != callers_threads) threads.set(callers_threads);
}

}  // namespace modal_deform
