// Shared machinery of the estimator checks (docs/validation.md A and B): unbiasedness by a t-test of
// batch means against a known integral, and replicate variances with the standard error of s² from
// the fourth moment. Streams are Rng::for_sample(seed, key, batch): results do not depend on the
// number of threads.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <algorithm>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "lib/core/hash.h"
#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "lib/core/uniforms.h"
#include "validate/registry.h"
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

// A family of unbiasedness cases under one check: each case's t-test at the Šidák-corrected level
// of family_alpha over the cases, one record with per-case details, the smallest p and the largest
// relative bias detectable at 90% power. `key` seeds the cases' streams (hash_values(key, i));
// `what` names the pairs in the message ("technique/problem").
struct UnbiasedCase {
  std::string name;
  Realisation r;
  double truth = 0.0;
};
inline CheckResult unbiased_family(const CheckContext& ctx, const std::vector<UnbiasedCase>& cases, uint64_t key,
                                   int64_t realisations, int batches, double family_alpha,
                                   int64_t samples_per_realisation, const std::string& what,
                                   const std::string& correction) {
  const double alpha = stats::sidak_alpha(family_alpha, static_cast<int64_t>(cases.size()));
  CheckResult res;
  res.alpha = alpha;
  res.statistic_name = "min p";
  res.statistic = 1.0;
  res.passed = true;
  nlohmann::json per_case = nlohmann::json::array();
  std::string worst;
  double worst_mdb_rel = 0.0;
  for (size_t i = 0; i < cases.size(); ++i) {
    const auto o =
        test_unbiased(cases[i].name, cases[i].r, cases[i].truth, realisations, batches, ctx.seed, hash_values(key, i), alpha);
    per_case.push_back({{"case", o.name}, {"truth", o.truth}, {"mean", o.mean}, {"std_error", o.std_error},
                        {"t", o.t}, {"p", o.p_value}, {"min_detectable_bias", o.min_detectable_bias},
                        {"nonfinite", o.nonfinite}, {"rejected", o.rejected}});
    worst_mdb_rel = std::max(worst_mdb_rel, o.min_detectable_bias / std::abs(o.truth));
    if (o.p_value < res.statistic) {
      res.statistic = o.p_value;
      worst = o.name;
    }
    if (o.rejected) {
      res.passed = false;
      res.message += fmt::format("{}: mean {:.6g} vs {:.6g} (t = {:.2f}, p = {:.2g}); ", o.name, o.mean, o.truth, o.t, o.p_value);
    }
    res.samples += o.realisations * samples_per_realisation;
    ctx.progress(static_cast<double>(i + 1) / static_cast<double>(cases.size()));
  }
  res.p_value = res.statistic;
  res.details["cases"] = per_case;
  res.details["family_alpha"] = family_alpha;
  res.details["correction"] = correction;
  res.details["batches"] = batches;
  res.details["realisations_per_case"] = realisations;
  res.details["worst_relative_min_detectable_bias_90pct_power"] = worst_mdb_rel;
  res.min_detectable_effect = worst_mdb_rel;
  res.effect_kind = "relative bias of the estimate (worst case)";
  if (res.passed)
    res.message = fmt::format("{} {} pairs unbiased (t-test of {} batch means, alpha' = {:.2g}); smallest p = "
                              "{:.3g} ({}); detectable relative bias at 90% power <= {:.2g}",
                              cases.size(), what, batches, alpha, res.statistic, worst, worst_mdb_rel);
  else
    res.message = "biased: " + res.message;
  return res;
}

// West et al. 2022, Sec. 3.2 (Fig. 1 bottom): "the additional variance vanishes as n increases".
// A limit, not an ordering: MMIS_n is a different unbiased estimator from the reference MIS with
// exact marginals (its denominators sum sampled conditional densities, among them the one that drew
// the sample), so it may end slightly below the reference. What the claim implies at a fixed budget:
// the variance falls significantly from the smallest to the largest n (one-sided z of the difference
// of the two sample variances), and at the largest n the ratio to the reference lies within
// 1 ± band (equivalence: both one-sided z-tests reject at alpha). The band is ours, not the paper's.
struct VanishingExcess {
  double ratio_first = 0.0, ratio_last = 0.0, ratio_last_se = 0.0;
  double fall_z = 0.0, fall_p = 1.0, equivalence_p = 1.0;
  bool falls = false, within = false;
  bool holds() const { return falls && within; }
};

inline VanishingExcess vanishing_excess(const stats::Welford& first, const stats::Welford& last, double reference,
                                        double band, double alpha) {
  VanishingExcess v;
  v.ratio_first = first.variance() / reference;
  v.ratio_last = last.variance() / reference;
  v.ratio_last_se = last.variance_std_error() / reference;
  const auto fall = stats::z_test_greater(first.variance() - last.variance(),
                                          std::hypot(first.variance_std_error(), last.variance_std_error()), 0.0);
  v.fall_z = fall.statistic;
  v.fall_p = fall.p_value;
  const auto lo = stats::z_test_greater(v.ratio_last, v.ratio_last_se, 1.0 - band);
  const auto hi = stats::z_test_greater(1.0 + band, v.ratio_last_se, v.ratio_last);
  v.equivalence_p = std::max(lo.p_value, hi.p_value);
  v.falls = fall.rejects(alpha);
  v.within = lo.rejects(alpha) && hi.rejects(alpha);
  return v;
}

// The band of `vanishing_excess` for Fig. 1 bottom (N = 64, T = 4, n = 1 ... 16): at quick size the
// standard error of the n = 16 ratio is about 0.03, so a band of 0.15 already failed once at 0.975.
inline constexpr double kMmisApproachBand = 0.25;

}  // namespace tb::checks
