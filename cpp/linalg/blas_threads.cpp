#include "linalg/blas_threads.h"

#include <dlfcn.h>

#include <algorithm>

namespace modal_deform {
namespace {

// OpenBLAS's controls, looked up at run time in the libraries loaded with this one (CHOLMOD's
// BLAS among them); null with any other BLAS.
using GetThreads = int (*)();
using SetThreads = void (*)(int);

GetThreads get_threads() { return reinterpret_cast<GetThreads>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads")); }
SetThreads set_threads() { return reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads")); }

}  // namespace

int blas_threads() {
  const GetThreads get = get_threads();
  return get && set_threads() ? get() : 0;
}

BlasLeavesACore::BlasLeavesACore() : previous_(blas_threads()) {
  if (previous_ > 1) set_threads()(previous_ - 1);
}

BlasLeavesACore::~BlasLeavesACore() {
  if (previous_ > 1) set_threads()(previous_);
}

}  // namespace modal_deform
