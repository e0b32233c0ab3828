// work(i) for i in [0, count) on the OpenMP threads (on the calling thread when count is 1),
// handed out one at a time: a thread whose core another process takes does not hold the others
// up at the end. An exception must not leave an OpenMP region (the process would end, and
// Blender with it): the first one thrown is kept and rethrown here once every thread is done.
#pragma once

#include <exception>

namespace modal_deform {

template <typename Index, typename Work>
void parallel_for(Index count, Work&& work) {
  std::exception_ptr failure;
#pragma omp parallel for schedule(dynamic) if (count > 1)
  for (Index i = 0; i < count; ++i) {
    try {
      work(i);
    } catch (...) {
#pragma omp critical(modal_deform_parallel_for)
      if (!failure) failure = std::current_exception();
    }
  }
  if (failure) std::rethrow_exception(failure);
}

}  // namespace modal_deform
