// Parallel loops on TBB. Work is split over indices, and every random decision inside a
// loop body must come from a stream keyed by the index (Rng::for_sample), never from the
// thread, so results are identical whatever the number of threads.
#pragma once

#include <cstddef>
#include <memory>

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

namespace tb {

// Calls f(i) for i in [begin, end), in parallel.
template <class F>
void parallel_for(size_t begin, size_t end, F&& f, size_t grain = 1) {
  if (end <= begin) return;
  tbb::parallel_for(tbb::blocked_range<size_t>(begin, end, grain), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) f(i);
  });
}
template <class F>
void parallel_for(size_t n, F&& f) {
  parallel_for(size_t{0}, n, std::forward<F>(f));
}

// While alive, limits TBB to `threads` worker threads (0 = no limit).
class ThreadLimit {
 public:
  explicit ThreadLimit(size_t threads) {
    if (threads > 0)
      control_ = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
  }

 private:
  std::unique_ptr<tbb::global_control> control_;
};

}  // namespace tb
