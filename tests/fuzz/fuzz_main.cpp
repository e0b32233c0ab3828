// A libFuzzer entry point for one target of fuzz_targets.h, chosen at compile time
// (FUZZ_TARGET, see CMakeLists.txt). A Failure or any exception the core should not throw is
// reported and ends the process, so libFuzzer records the input as a crash.
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "fuzz_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    modal_deform::fuzz::FUZZ_TARGET(data, size);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "fuzz failure: %s\n", error.what());
    std::abort();
  }
  return 0;
}
