// Progress reporting for long native calls (the bake, the full solve).
//
// A Progress forwards (stage, fraction) to the caller's callback no more often than every
// `interval` seconds (the first and the last report of a stage always go through), and throws
// Cancelled when the callback returns false, so a cancel takes effect at the next report.
#pragma once

#include <chrono>
#include <functional>
#include <string>

#include "util/errors.h"

namespace modal_deform {

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
