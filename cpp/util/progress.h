// Progress reporting for long native calls (the bake).
//
// A Progress forwards (stage, fraction) to the caller's callback no more often than every
// `interval` seconds (the first and the last report of a stage always go through), and throws
// Cancelled when the callback returns false, so a cancel takes effect at the next report.
#pragma once

#include <array>
#include <chrono>
#include <functional>
#include <string>

#include "util/errors.h"

namespace modal_deform {

// The bake's stages in the order they run (cpp/bake/bake.h): the names its progress reports and
// Basis::timings use, exported to Python as BAKE_STAGES so that one bar runs over the whole bake.
// A bake without a proxy skips the first and the last.
namespace stages {
inline constexpr const char* kProxy = "proxy";
inline constexpr const char* kAttachment = "attachment";
inline constexpr const char* kHessian = "hessian";
inline constexpr const char* kFactorisation = "factorisation";
inline constexpr const char* kGhost = "ghost";
inline constexpr const char* kModes = "modes";
inline constexpr const char* kThirdDerivatives = "third derivatives";
inline constexpr const char* kDerivativeSolves = "derivative solves";
inline constexpr const char* kOrthonormalisation = "orthonormalisation";
inline constexpr const char* kAssembly = "assembly";
inline constexpr const char* kProlongation = "prolongation";
}  // namespace stages
inline constexpr std::array<const char*, 11> kBakeStages = {
    stages::kProxy,           stages::kAttachment,         stages::kHessian,  stages::kFactorisation,
    stages::kGhost,           stages::kModes,              stages::kThirdDerivatives,
    stages::kDerivativeSolves, stages::kOrthonormalisation, stages::kAssembly, stages::kProlongation};

using ProgressCallback = std::function<bool(const std::string& stage, double fraction)>;

class Progress {
 public:
  explicit Progress(ProgressCallback callback = {}, double interval_seconds = 0.1)
      : callback_(std::move(callback)), interval_(interval_seconds) {}

  // Reports `fraction` in [0, 1] of `stage`; throws Cancelled when the callback says stop.
  void report(const std::string& stage, double fraction) {
    if (!callback_) return;
    const auto now = std::chrono::steady_clock::now();
    const bool stage_changed = stage != stage_;
    const bool due = std::chrono::duration<double>(now - last_).count() >= interval_;
    if (!(stage_changed || due || fraction >= 1.0)) return;
    stage_ = stage;
    last_ = now;
    if (!callback_(stage, fraction)) throw Cancelled();
  }

 private:
  ProgressCallback callback_;
  double interval_;
  std::string stage_;
  std::chrono::steady_clock::time_point last_{};
};

}  // namespace modal_deform
