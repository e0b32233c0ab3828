// The threads of the BLAS under CHOLMOD's supernodal kernels (OpenBLAS here). OpenBLAS starts
// one thread per core, and its threads wait for each other busily: on the 2-core machine the bake
// was measured on, the modes stage (factorisation and 62 single solves, while the ghost is
// simplified on the other core) took 20-23 s wall and 15-17 s CPU of the process with two BLAS
// threads, 13-16 s and 8-10 s with one.
#pragma once

namespace modal_deform {

// The BLAS's thread count, or 0 when the BLAS does not say (one other than OpenBLAS).
int blas_threads();

// While it lives, the BLAS leaves one core to a thread of the caller's: it runs on one thread fewer
// than it had (at least one); the destructor restores the count. The count is global to the
// process (numpy in the same process shares it when it uses the same OpenBLAS): guards that
// overlap in time on different threads (two bakes at once) leave it right when the last ends,
// and either count in between, which changes only the speed.
class BlasLeavesACore {
 public:
  BlasLeavesACore();
  ~BlasLeavesACore();
  BlasLeavesACore(const BlasLeavesACore&) = delete;
  BlasLeavesACore& operator=(const BlasLeavesACore&) = delete;

 private:
  int previous_ = 0;
};

}  // namespace modal_deform
