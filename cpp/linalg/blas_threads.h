// How many threads the BLAS under CHOLMOD may use while the core calls it.
//
// OpenBLAS keeps a pool of worker threads that spin (sched_yield) between calls and wait for each
// other inside every call: when another process (Blender's viewport, another add-on) holds one of
// a few cores, a worker that loses its core stalls the whole call. While a BlasThreadLimit lives,
// OpenBLAS runs on at most one thread fewer than the cores this process may use (one core is left
// to whatever else runs; on two cores that is one BLAS thread, and the idle workers sleep), never
// more than the caller had set. The caller's setting is restored when the last limit in the
// process ends: Blender's NumPy has an OpenBLAS of its own, but a plain Python's NumPy may share
// the core's one. Nothing happens when the BLAS is not OpenBLAS.
#pragma once

namespace modal_deform {

class BlasThreadLimit {
 public:
  BlasThreadLimit();
  ~BlasThreadLimit();
  BlasThreadLimit(const BlasThreadLimit&) = delete;
  BlasThreadLimit& operator=(const BlasThreadLimit&) = delete;

  // The threads OpenBLAS uses now; 0 when the BLAS under CHOLMOD is not OpenBLAS.
  static int current();
  // The most threads OpenBLAS may use inside a limit: the usable cores less one, at least one.
  static int most_threads();
};

}  // namespace modal_deform
