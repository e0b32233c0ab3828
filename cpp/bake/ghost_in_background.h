// The ghost mesh (ghost.h), simplified on a thread of its own while the bake's CHOLMOD orders the
// stiffness matrix: both are serial, so together they take the time of the longer, and the
// factorisation after them has both cores for its BLAS.
#pragma once

#include <atomic>
#include <chrono>
#include <future>
#include <string>

#include "reduction/ghost.h"
#include "util/bake_stages.h"
#include "util/progress.h"

namespace modal_deform {

class GhostInBackground {
 public:
  // Starts ghost_mesh(V, F, mass, target); the arrays must outlive the object.
  GhostInBackground(const VerticesRef& V, const FacesRef& F, const VectorRef& mass, int target)
      : progress_([this](const std::string&, double fraction) {
          fraction_ = fraction;
          return !stop_.load();
        }),
        ghost_(std::async(std::launch::async, [&V, &F, &mass, target, this] {
          return ghost_mesh(V, F, mass, target, &progress_);
        })) {}
  // When the bake stops early, cancels the ghost and waits, so nothing outlives the bake.
  ~GhostInBackground() {
    stop_ = true;
    if (ghost_.valid()) ghost_.wait();
  }
  GhostInBackground(const GhostInBackground&) = delete;
  GhostInBackground& operator=(const GhostInBackground&) = delete;

  // Waits for the ghost, passing its progress on to the bake's bar (which may cancel) every
  // kPollInterval: the stage is reported at least at its start and end, however soon the ghost was
  // ready.
  Ghost get(Progress& progress) {
    do {
      progress.report(stages::kGhost, fraction_.load());
    } while (ghost_.wait_for(kPollInterval) != std::future_status::ready);
    progress.report(stages::kGhost, 1.0);
    return ghost_.get();
  }

 private:
  // Shorter than the bar's interval between reports (Progress), so the bar moves at its own pace.
  static constexpr std::chrono::milliseconds kPollInterval{50};

  std::atomic<bool> stop_{false};
  std::atomic<double> fraction_{0.0};
  Progress progress_;
  std::future<Ghost> ghost_;
};

}  // namespace modal_deform
