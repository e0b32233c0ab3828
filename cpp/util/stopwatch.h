// Wall-clock accounting of a scope, for the per-stage timings the bake reports.
#pragma once

#include <chrono>

namespace modal_deform {

// Adds the wall seconds from construction to destruction to `total`, also when an exception
// leaves the scope.
class Stopwatch {
 public:
  explicit Stopwatch(double& total) : total_(total), start_(std::chrono::steady_clock::now()) {}
  ~Stopwatch() {
    total_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  Stopwatch(const Stopwatch&) = delete;
  Stopwatch& operator=(const Stopwatch&) = delete;

 private:
  double& total_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace modal_deform
