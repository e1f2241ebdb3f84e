// Settings shared by every integrator run, and the per-run statistics they report.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>

namespace tb {

struct RenderSettings {
  int64_t spp = 16;          // samples per pixel in total
  int64_t passes = 8;        // Welch samples per pixel: spp is split evenly over the passes
  int max_depth = 10;        // maximum number of scattering events
  uint64_t seed = 1;
  double time_budget_s = 0;  // > 0: stop after the pass during which the budget ran out
  std::function<void(double)> progress = [](double) {};
  const std::atomic<bool>* interrupted = nullptr;  // stop between passes
};

}  // namespace tb
