// Determinism of the random streams: a pure function of (seed, key, index, dim), the same
// for any thread count and visiting order (STYLE.md, "Sampling and randomness").
#include <vector>

#include <fmt/format.h>

#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "validate/registry.h"

namespace tb {
namespace {

std::vector<double> draw(uint64_t seed, size_t n, size_t threads, bool reversed) {
  ThreadLimit limit(threads);
  std::vector<double> v(n);
  parallel_for(n, [&](size_t i) {
    const size_t idx = reversed ? n - 1 - i : i;
    Rng r = Rng::for_sample(seed, 0xd1ce, idx);
    double acc = 0;
    for (int d = 0; d < 8; ++d) acc += r.uniform();
    v[idx] = acc;
  });
  return v;
}

CheckResult run_determinism(const CheckContext& ctx) {
  const size_t n = static_cast<size_t>(ctx.size(1 << 16, 1 << 20));
  const std::vector<double> ref = draw(ctx.seed, n, 1, false);
  int64_t mismatches = 0;
  for (auto [threads, reversed] : {std::pair{size_t{2}, false}, {size_t{2}, true}, {size_t{1}, true}}) {
    const std::vector<double> v = draw(ctx.seed, n, threads, reversed);
    for (size_t i = 0; i < n; ++i) mismatches += (v[i] != ref[i]);
  }
  // Random access to a dimension must equal sequential drawing.
  for (size_t i = 0; i < 256; ++i) {
    Rng r = Rng::for_sample(ctx.seed, 0xd1ce, i);
    for (uint64_t d = 0; d < 8; ++d) mismatches += (r.uniform() != Rng::uniform_at(ctx.seed, 0xd1ce, i, d));
  }
  CheckResult res;
  res.passed = mismatches == 0;
  res.statistic_name = "mismatches";
  res.statistic = static_cast<double>(mismatches);
  res.samples = static_cast<int64_t>(3 * n + 256 * 8);
  res.message = fmt::format("{} of {} values differ between 1/2 threads, reversed order, random access", mismatches,
                            res.samples);
  return res;
}

TB_REGISTER_CHECK({.name = "core.rng.determinism",
                   .description = "Streams are bit-identical for 1 and 2 threads, reversed visiting order, "
                                  "and random access to a dimension",
                   .kind = CheckKind::kDeterministic,
                   .run = run_determinism});

}  // namespace
}  // namespace tb
