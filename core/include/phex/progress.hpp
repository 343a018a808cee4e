// phex — progress reports and cancellation shared by the long stages.
#pragma once
#include <atomic>
#include <functional>
#include <string>

namespace phex {

struct Progress {
  std::string stage;     // "triangulate", "dualize", "planarize", "clip", "measure"
  double fraction = 0;   // 0..1 within the stage
  std::string message;   // e.g. "round 2, iteration 5, planarity 3.1e-07"
};
using ProgressFn = std::function<void(const Progress&)>;

// Raised by the caller (another thread, or the progress callback itself) to stop at the next check.
using CancelFlag = std::atomic<bool>;

// Throws Error(Cancelled) when `cancel` is set.
void checkCancel(const CancelFlag* cancel);

}  // namespace phex
