// Shared machinery of the estimator checks (VALIDATION.md A and B): unbiasedness by a t-test of
// batch means against a known integral, and replicate variances with the standard error of s² from
// the fourth moment. Streams are Rng::for_sample(seed, key, batch): results do not depend on the
// number of threads.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "lib/core/uniforms.h"
#include "validate/stats/tests.h"
#include "validate/stats/welford.h"

namespace tb::checks {

// One realisation of an estimator, drawing its uniforms from u.
using Realisation = std::function<double(Uniforms&)>;

struct UnbiasednessOutcome {
  std::string name;
  double truth = 0.0, mean = 0.0, std_error = 0.0;
  double t = 0.0, p_value = 1.0;
  double min_detectable_bias = 0.0;  // at 90% power and the corrected alpha
  int64_t realisations = 0, nonfinite = 0;
  bool rejected = false;
};

// `realisations` realisations cut into `batches` batches; two-sided one-sample t test of the batch
// means against truth at level alpha.
inline UnbiasednessOutcome test_unbiased(const std::string& name, const Realisation& r, double truth,
                                         int64_t realisations, int batches, uint64_t seed, uint64_t key,
                                         double alpha) {
  const int64_t per_batch = std::max<int64_t>(1, realisations / batches);
  std::vector<double> means(batches);
  std::vector<int64_t> nonfinite(batches, 0);
  parallel_for(static_cast<size_t>(batches), [&](size_t b) {
    Rng rng = Rng::for_sample(seed, key, b);
    RngUniforms u(rng);
    stats::Welford w;
    for (int64_t i = 0; i < per_batch; ++i) w.add(r(u));
    means[b] = w.mean();
    nonfinite[b] = w.nonfinite();
  });
  stats::Welford bm;
  UnbiasednessOutcome o;
  for (int b = 0; b < batches; ++b) {
    bm.add(means[b]);
    o.nonfinite += nonfinite[b];
  }
  const auto t = stats::one_sample_t_test(bm, truth);
  o.name = name;
  o.truth = truth;
  o.mean = bm.mean();
  o.std_error = bm.std_error();
  o.t = t.statistic;
  o.p_value = t.p_value;
  o.min_detectable_bias = stats::minimal_detectable_bias(o.std_error, alpha);
  o.realisations = per_batch * batches;
  o.rejected = t.rejects(alpha) || o.nonfinite > 0;
  return o;
}

// Moments of `replicates` independent realisations (parallel in chunks, deterministic merge order).
inline stats::Welford replicate_moments(const Realisation& r, int64_t replicates, uint64_t seed, uint64_t key) {
  constexpr int64_t kChunk = 64;
  const int64_t chunks = (replicates + kChunk - 1) / kChunk;
  std::vector<stats::Welford> ws(chunks);
  parallel_for(static_cast<size_t>(chunks), [&](size_t c) {
    Rng rng = Rng::for_sample(seed, key, c);
    RngUniforms u(rng);
    const int64_t end = std::min<int64_t>(replicates, (static_cast<int64_t>(c) + 1) * kChunk);
    for (int64_t i = static_cast<int64_t>(c) * kChunk; i < end; ++i) ws[c].add(r(u));
  });
  stats::Welford all;
  for (const auto& w : ws) all.merge(w);
  return all;
}

}  // namespace tb::checks
