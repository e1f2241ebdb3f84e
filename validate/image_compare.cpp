#include "validate/image_compare.h"

#include <limits>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <boost/math/distributions/normal.hpp>
#include <fmt/format.h>

namespace tb {
namespace {

// Normal quantile with the same two-sided tail as p, signed like t. p = 0 (underflow) maps to
// |z| = 38, beyond which the normal tail underflows double anyway.
double z_from_two_sided_p(double p, double t) {
  constexpr double kZCap = 38.0;
  double z;
  if (p <= 0.0)
    z = kZCap;
  else if (p >= 1.0)
    z = 0.0;
  else
    z = std::min(kZCap, boost::math::quantile(boost::math::complement(boost::math::normal_distribution<double>(), 0.5 * p)));
  return t < 0 ? -z : z;
}

}  // namespace

namespace {
// The shift of one unit's z per unit of m / se_hat (image_compare.h): kappa(dof) times
// sigma / se_hat's correction 1 / E[sigma / s] (1 / se_hat overestimates 1 / sigma); 0 (no
// stated power from this unit) where dof <= 1.
double unit_gain(double dof) {
  const double b = stats::inverse_sd_bias(dof);
  return std::isfinite(b) ? stats::t_to_z_slope(dof) / b : 0.0;
}
}  // namespace

double uniform_bias_mde(const std::vector<std::pair<double, double>>& all, double power) {
  // Tests without signal or without a level (a channel with no tested unit) add no power.
  std::vector<std::pair<double, double>> gain_alpha;
  for (const auto& [g, a] : all)
    if (g > 0.0 && std::isfinite(g) && a > 0.0 && a < 1.0) gain_alpha.emplace_back(g, a);
  double best = 0.0;
  for (const auto& [g, a] : gain_alpha) best = std::max(best, g);
  if (!(best > 0.0)) return kMdeNone;
  const auto miss = [&](double d) {  // probability that no test rejects
    double m = 1.0;
    for (const auto& [g, a] : gain_alpha) m *= 1.0 - stats::z_test_power(d * g, a);
    return m;
  };
  // Bracket: the best single test alone reaches the power at its own minimal detectable shift.
  double lo = 0.0, hi = 0.0;
  for (const auto& [g, a] : gain_alpha)
    if (g == best) hi = stats::minimal_detectable_shift(a, power) / g;
  for (int it = 0; it < 100 && hi - lo > 1e-12 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (1.0 - miss(mid) >= power ? hi : lo) = mid;
  }
  return hi;
}

std::string mde_phrase(double mde) {
  if (!std::isfinite(mde)) return "no uniform bias detectable (no signal)";
  return fmt::format("detects a uniform bias of {:.3g}% at 90% power", 100.0 * mde);
}

nlohmann::json mde_json(double mde) { return std::isfinite(mde) ? nlohmann::json(mde) : nlohmann::json(nullptr); }

double ImageCompareResult::p_value() const {
  const double p_min = zero_variance_mismatch > 0 ? 0.0 : std::min({p_pixel_family, stouffer.p_value, sum_z2.p_value});
  return stats::sidak_adjust(p_min, 3);
}

std::string ImageCompareResult::message() const {
  return fmt::format(
      "{}: {}P={} {}-channels, mean rel. diff {:+.3g}; Stouffer Z={:.3g} (ch {}, p={:.3g}), sum z^2={:.4g} (ch {}, p={:.3g}), "
      "worst {} ({}, {}) ch {} t={:.3g} p={:.3g} (family p={:.3g}){}; alpha={} ({} per test); {}",
      rejects() ? "different" : "consistent", tiled ? fmt::format("{}x{} tiles, ", tile, tile) : "", tested,
      tiled ? "tile" : "pixel", mean_relative_difference, stouffer.statistic, stouffer_channel,
      stouffer.p_value, sum_z2.statistic, sum_z2_channel, sum_z2.p_value, tiled ? "tile at" : "pixel", worst.x, worst.y, worst.channel, worst.t, worst.p, p_pixel_family,
      zero_variance_mismatch > 0 ? fmt::format(", {} zero-variance mismatches", zero_variance_mismatch) : "", alpha,
      alpha_each, mde_phrase(min_detectable_relative_bias));
}

nlohmann::json ImageCompareResult::details() const {
  return {{"alpha", alpha},
          {"alpha_each", alpha_each},
          {"alpha_pixel", alpha_pixel},
          {"tested", tested},
          {"skipped_identical", skipped_identical},
          {"zero_variance_mismatch", zero_variance_mismatch},
          {"skipped_below_float_range", skipped_below_float_range},
          {"worst", {{"x", worst.x}, {"y", worst.y}, {"channel", worst.channel}, {"mean_a", worst.mean_a},
                     {"mean_b", worst.mean_b}, {"t", worst.t}, {"dof", worst.dof}, {"p", worst.p}}},
          {"p_pixel_family", p_pixel_family},
          {"stouffer_z", stouffer.statistic},
          {"stouffer_channel", stouffer_channel},
          {"sum_z2_channel", sum_z2_channel},
          {"stouffer_p", stouffer.p_value},
          {"sum_z2", sum_z2.statistic},
          {"sum_z2_dof", sum_z2.dof},
          {"sum_z2_p", sum_z2.p_value},
          {"mean_relative_difference", mean_relative_difference},
          {"skew_corrected", skew_corrected},
          {"skew_large", skew_large},
          {"skew_max", skew_max},
          {"test", tiled ? "tiled" : "pixel"},
          {"tile", tile},
          {"tile_from_skewness", tile_from_skewness},
          {"third_moments", third_moments},
          {"predicted_skew_shift", predicted_shift},
          {"predicted_skew_shift_pixel", predicted_shift_pixel},
          {"max_skew_shift", max_skew_shift},
          {"skew_condition_met", skew_condition_met()},
          {"min_detectable_relative_bias", mde_json(min_detectable_relative_bias)},
          {"min_detectable_relative_bias_independent_channels", mde_json(min_detectable_relative_bias_independent)},
          {"min_detectable_relative_bias_channel",
           {mde_json(min_detectable_bias_channel[0]), mde_json(min_detectable_bias_channel[1]),
            mde_json(min_detectable_bias_channel[2])}},
          {"rejects", rejects()}};
}

// Means below this have a variance (~mean^2) under FLT_MIN: an EXR's float variance plane holds
// 0 for them (see the header).
const double kFloatVarianceFloor = std::sqrt(double(std::numeric_limits<float>::min()));

ImageCompareResult compare_welch_images(const WelchImage& a, const WelchImage& b, double alpha) {
  return compare_welch_images(a, b, alpha, ImageCompareOptions{});
}

namespace {
// The unbiased third cumulant of n samples from their third central moment (1/n) sum (x - m)^3.
double k3_from_m3(double m3, int64_t n) {
  if (n < 3) return 0.0;
  const double dn = double(n);
  return dn * dn / ((dn - 1.0) * (dn - 2.0)) * m3;
}

constexpr double kSkewValidity = 0.2;  // |c| beyond which the one-term correction is unreliable
constexpr int kSkewPoolRadius = 3;     // skewness pooled over (2r + 1)^2 pixels

// Per pixel and channel, the standardised skewness k3 / s^3 of one Welch sample, averaged over the
// pixels of a (2r + 1)^2 window that have at least three samples and a positive variance: one
// pixel's 8-32 Welch samples estimate their skewness far too noisily (a noisy c inflates sum z^2),
// while the skewness of the per-sample distribution varies slowly over the image.
std::vector<Rgb> pooled_skewness(const WelchImage& w) {
  const size_t n = w.pixels();
  std::vector<Rgb> g(n, Rgb(0.0)), out(n, Rgb(0.0));
  std::vector<std::array<uint8_t, 3>> ok(n, {0, 0, 0});
  for (size_t i = 0; i < n; ++i) {
    if (w.count[i] < 3) continue;
    const Rgb v = w.variance(i), m3 = w.third_central_moment(i);
    for (int c = 0; c < 3; ++c)
      if (v[c] > 0) {
        g[i][c] = k3_from_m3(m3[c], w.count[i]) / (v[c] * std::sqrt(v[c]));
        ok[i][c] = std::isfinite(g[i][c]) ? 1 : 0;
      }
  }
  for (int y = 0; y < w.height; ++y)
    for (int x = 0; x < w.width; ++x) {
      Rgb sum(0.0);
      double cnt[3] = {0, 0, 0};
      for (int dy = -kSkewPoolRadius; dy <= kSkewPoolRadius; ++dy)
        for (int dx = -kSkewPoolRadius; dx <= kSkewPoolRadius; ++dx) {
          const int xx = x + dx, yy = y + dy;
          if (xx < 0 || yy < 0 || xx >= w.width || yy >= w.height) continue;
          const size_t j = size_t(yy) * size_t(w.width) + size_t(xx);
          for (int c = 0; c < 3; ++c)
            if (ok[j][c]) sum[c] += g[j][c], cnt[c] += 1;
        }
      for (int c = 0; c < 3; ++c) out[size_t(y) * size_t(w.width) + size_t(x)][c] = cnt[c] > 0 ? sum[c] / cnt[c] : 0.0;
    }
  return out;
}

}  // namespace

namespace {

// The three global tests over the tested units (pixel-channels or tile-channels), per channel.
void finish_global_tests(ImageCompareResult& r, const std::vector<double> (&zc)[3], double min_p, double sum_diff,
                         double sum_b, const double (&signal)[3]) {
  r.tested = static_cast<int64_t>(zc[0].size() + zc[1].size() + zc[2].size());
  r.mean_relative_difference = sum_b != 0.0 ? sum_diff / sum_b : 0.0;
  if (r.tested > 0) {
    r.alpha_pixel = stats::sidak_alpha(r.alpha_each, r.tested);
    r.p_pixel_family = stats::sidak_adjust(std::min(min_p, 1.0), r.tested);
    // The three channels of a pixel come from the same paths, so their z are correlated: the global
    // tests run per channel and the channel with the smallest p is Šidák-adjusted over the three
    // (valid under any dependence between channels for the min-p form, conservative here).
    bool first = true;
    for (int c = 0; c < 3; ++c) {
      if (zc[c].empty()) continue;
      const stats::TestResult st = stats::stouffer(zc[c]), sq = stats::sum_z2_test(zc[c]);
      if (first || st.p_value < r.stouffer.p_value) {
        r.stouffer = st;
        r.stouffer_channel = c;
      }
      if (first || sq.p_value < r.sum_z2.p_value) {
        r.sum_z2 = sq;
        r.sum_z2_channel = c;
      }
      first = false;
    }
    r.stouffer.p_value = stats::sidak_adjust(r.stouffer.p_value, 3);
    r.sum_z2.p_value = stats::sidak_adjust(r.sum_z2.p_value, 3);
    // Power of the Stouffer tests against a uniform relative bias (image_compare.h).
    r.alpha_stouffer = stats::sidak_alpha(r.alpha_each, 3);
    std::vector<std::pair<double, double>> gains;
    for (int c = 0; c < 3; ++c) {
      if (zc[c].empty() || !std::isfinite(signal[c])) continue;
      r.stouffer_gain[c] = std::abs(signal[c]) / std::sqrt(double(zc[c].size()));
      r.min_detectable_bias_channel[c] = uniform_bias_mde({{r.stouffer_gain[c], r.alpha_stouffer}});
      gains.emplace_back(r.stouffer_gain[c], r.alpha_stouffer);
    }
    // The headline is the best single channel's: a rejection in any channel rejects, so it holds
    // whatever the dependence between channels (in a render they come from the same paths).
    for (int c = 0; c < 3; ++c)
      r.min_detectable_relative_bias = std::min(r.min_detectable_relative_bias, r.min_detectable_bias_channel[c]);
    r.min_detectable_relative_bias_independent = uniform_bias_mde(gains);
  }
}

// Per k x k tile (edge tiles smaller) and channel, the sums the tiled Welch test needs.
struct TileSums {
  Rgb d{0.0};        // sum (mean_a - mean_b)
  Rgb v{0.0};        // Var(D) = sum (s_a^2 / n_a + s_b^2 / n_b)
  Rgb dof_den{0.0};  // Satterthwaite: sum ((s_a^2 / n_a)^2 / (n_a - 1) + (s_b^2 / n_b)^2 / (n_b - 1))
  Rgb k3{0.0};       // kappa3(D) = sum (k3_a / n_a^2 - k3_b / n_b^2)
  Rgb max_abs_mean{0.0};
  Rgb sum_b{0.0};
  int x0 = 0, y0 = 0;
};

std::vector<TileSums> tile_sums(const WelchImage& a, const WelchImage& b, int k) {
  const int tx = (a.width + k - 1) / k, ty = (a.height + k - 1) / k;
  std::vector<TileSums> t(size_t(tx) * size_t(ty));
  for (int j = 0; j < ty; ++j)
    for (int i = 0; i < tx; ++i) t[size_t(j) * size_t(tx) + size_t(i)].x0 = i * k, t[size_t(j) * size_t(tx) + size_t(i)].y0 = j * k;
  const bool third = a.has_third_moment() && b.has_third_moment();
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      const size_t p = size_t(y) * size_t(a.width) + size_t(x);
      const int64_t na = a.count[p], nb = b.count[p];
      if (na < 2 && nb < 2)
        throw std::invalid_argument(fmt::format("compare_welch_images: pixel {} has fewer than 2 Welch samples in both", p));
      TileSums& s = t[size_t(y / k) * size_t(tx) + size_t(x / k)];
      const Rgb ma = a.mean(p), mb = b.mean(p), va = a.variance(p), vb = b.variance(p);
      const Rgb m3a = third ? a.third_central_moment(p) : Rgb(0.0), m3b = third ? b.third_central_moment(p) : Rgb(0.0);
      for (int c = 0; c < 3; ++c) {
        const double ea = na >= 2 ? va[c] / double(na) : 0.0, eb = nb >= 2 ? vb[c] / double(nb) : 0.0;
        s.d[c] += ma[c] - mb[c];
        s.v[c] += ea + eb;
        s.dof_den[c] += (na >= 2 ? ea * ea / double(na - 1) : 0.0) + (nb >= 2 ? eb * eb / double(nb - 1) : 0.0);
        s.k3[c] += k3_from_m3(m3a[c], na) / (double(na) * double(na)) - k3_from_m3(m3b[c], nb) / (double(nb) * double(nb));
        s.max_abs_mean[c] = std::max({s.max_abs_mean[c], std::abs(ma[c]), std::abs(mb[c])});
        s.sum_b[c] += mb[c];
      }
    }
  return t;
}

}  // namespace

double tile_skew_shift(const WelchImage& a, const WelchImage& b, int k) {
  if (a.width != b.width || a.height != b.height || k < 1) throw std::invalid_argument("tile_skew_shift: bad sizes or k");
  if (!a.has_third_moment() || !b.has_third_moment()) return 0.0;
  const std::vector<TileSums> t = tile_sums(a, b, k);
  double worst = 0.0;
  for (int c = 0; c < 3; ++c) {
    double sum_c = 0.0;
    int64_t n = 0;
    for (const TileSums& s : t) {
      if (!(s.v[c] > 0)) continue;
      const double ct = s.k3[c] / (6.0 * s.v[c] * std::sqrt(s.v[c]));
      if (!std::isfinite(ct)) continue;
      sum_c += ct;
      ++n;
    }
    if (n > 0) worst = std::max(worst, std::abs(3.0 * sum_c / std::sqrt(double(n))));
  }
  return worst;
}

int choose_tile(const WelchImage& a, const WelchImage& b, double bound) {
  const int whole = std::max(a.width, a.height);
  for (int k = 1;; k *= 2) {
    const int kk = std::min(k, whole);
    if (kk == whole || tile_skew_shift(a, b, kk) <= bound) return kk;
  }
}

namespace {

ImageCompareResult compare_tiled(const WelchImage& a, const WelchImage& b, double alpha, const ImageCompareOptions& o) {
  ImageCompareResult r;
  r.alpha = alpha;
  r.alpha_each = stats::sidak_alpha(alpha, 3);
  r.tiled = true;
  r.max_skew_shift = o.max_skew_shift;
  r.third_moments = a.has_third_moment() && b.has_third_moment();
  const int whole = std::max(a.width, a.height);
  if (o.tile > 0)
    r.tile = std::min(o.tile, whole);
  else if (r.third_moments) {
    r.tile = choose_tile(a, b, o.max_skew_shift);
    r.tile_from_skewness = true;
  } else
    r.tile = std::min(std::max(1, o.fallback_tile), whole);
  r.predicted_shift = tile_skew_shift(a, b, r.tile);
  r.predicted_shift_pixel = tile_skew_shift(a, b, 1);
  const std::vector<TileSums> tiles = tile_sums(a, b, r.tile);
  std::vector<double> zc[3];
  double signal[3] = {0.0, 0.0, 0.0};
  double min_p = 2.0, sum_diff = 0.0, sum_b = 0.0;
  for (const TileSums& s : tiles)
    for (int c = 0; c < 3; ++c) {
      PixelChannelTest pc;
      pc.x = s.x0;
      pc.y = s.y0;
      pc.channel = c;
      pc.mean_a = s.d[c] + s.sum_b[c];  // tile sums
      pc.mean_b = s.sum_b[c];
      if (s.v[c] == 0.0) {
        if (s.d[c] == 0.0)
          ++r.skipped_identical;
        else if (s.max_abs_mean[c] < kFloatVarianceFloor)
          ++r.skipped_below_float_range;
        else {
          ++r.zero_variance_mismatch;
          pc.p = 0.0;
          pc.t = s.d[c] > 0 ? kInfinity : -kInfinity;
          if (min_p > 0.0) {
            min_p = 0.0;
            r.worst = pc;
          }
        }
        continue;
      }
      pc.t = s.d[c] / std::sqrt(s.v[c]);
      // Satterthwaite's effective dof of a sum of independent variance estimates; infinite when
      // only exact references (n < 2) and ... contribute no estimated variance.
      pc.dof = s.dof_den[c] > 0 ? s.v[c] * s.v[c] / s.dof_den[c] : 1e12;
      pc.p = stats::students_t_two_sided_p(pc.t, pc.dof);
      pc.z = z_from_two_sided_p(pc.p, pc.t);
      zc[c].push_back(pc.z);
      signal[c] += unit_gain(pc.dof) * (s.sum_b[c] + 0.5 * s.d[c]) / std::sqrt(s.v[c]);
      sum_diff += s.d[c];
      sum_b += s.sum_b[c];
      if (pc.p < min_p) {
        min_p = pc.p;
        r.worst = pc;
      }
    }
  finish_global_tests(r, zc, min_p, sum_diff, sum_b, signal);
  return r;
}

}  // namespace

ImageCompareResult compare_welch_images(const WelchImage& a, const WelchImage& b, double alpha,
                                        const ImageCompareOptions& options) {
  if (options.test == CompareTest::kTiled) {
    if (a.width != b.width || a.height != b.height)
      throw std::invalid_argument(
          fmt::format("compare_welch_images: sizes differ ({}x{} vs {}x{})", a.width, a.height, b.width, b.height));
    return compare_tiled(a, b, alpha, options);
  }
  if (a.width != b.width || a.height != b.height)
    throw std::invalid_argument(
        fmt::format("compare_welch_images: sizes differ ({}x{} vs {}x{})", a.width, a.height, b.width, b.height));
  ImageCompareResult r;
  r.alpha = alpha;
  r.alpha_each = stats::sidak_alpha(alpha, 3);
  r.skew_corrected = options.skew_correction && a.has_third_moment() && b.has_third_moment();
  r.third_moments = a.has_third_moment() && b.has_third_moment();
  r.max_skew_shift = options.max_skew_shift;
  r.predicted_shift = r.predicted_shift_pixel = tile_skew_shift(a, b, 1);
  const std::vector<Rgb> ga = r.skew_corrected ? pooled_skewness(a) : std::vector<Rgb>{};
  const std::vector<Rgb> gb = r.skew_corrected ? pooled_skewness(b) : std::vector<Rgb>{};
  std::vector<double> zc[3];
  double signal[3] = {0.0, 0.0, 0.0};
  double min_p = 2.0, sum_diff = 0.0, sum_b = 0.0;
  for (size_t i = 0; i < a.pixels(); ++i) {
    const int64_t na = a.count[i], nb = b.count[i];
    if (na < 2 && nb < 2)
      throw std::invalid_argument(fmt::format("compare_welch_images: pixel {} has fewer than 2 Welch samples in both", i));
    const Rgb ma = a.mean(i), mb = b.mean(i), va = a.variance(i), vb = b.variance(i);
    for (int c = 0; c < 3; ++c) {
      PixelChannelTest pc;
      pc.x = static_cast<int>(i % size_t(a.width));
      pc.y = static_cast<int>(i / size_t(a.width));
      pc.channel = c;
      pc.mean_a = ma[c];
      pc.mean_b = mb[c];
      const double se2 = (na >= 2 ? va[c] / double(na) : 0.0) + (nb >= 2 ? vb[c] / double(nb) : 0.0);
      if (se2 == 0.0) {
        if (ma[c] == mb[c]) {
          ++r.skipped_identical;
        } else if (std::max(std::abs(ma[c]), std::abs(mb[c])) < kFloatVarianceFloor) {
          ++r.skipped_below_float_range;
        } else {
          ++r.zero_variance_mismatch;
          pc.p = 0.0;
          pc.t = ma[c] > mb[c] ? kInfinity : -kInfinity;
          if (min_p > 0.0) {
            min_p = 0.0;
            r.worst = pc;
          }
        }
        continue;
      }
      stats::TestResult t;
      if (na >= 2 && nb >= 2)
        t = stats::welch_t_test(ma[c], va[c], na, mb[c], vb[c], nb);
      else if (na >= 2)
        t = stats::one_sample_t_test(ma[c], std::sqrt(va[c]), na, mb[c]);
      else {
        t = stats::one_sample_t_test(mb[c], std::sqrt(vb[c]), nb, ma[c]);
        t.statistic = -t.statistic;  // keep the sign convention a - b
      }
      if (r.skew_corrected) {
        // kappa3 of the mean of n samples = k3 / n^2, k3 = g s^3 with the pooled skewness g.
        const auto k3_of_mean = [](double g, double var, int64_t n) {
          return n >= 3 ? g * var * std::sqrt(var) / (double(n) * double(n)) : 0.0;
        };
        const double kappa3 = k3_of_mean(ga[i][c], va[c], na) - k3_of_mean(gb[i][c], vb[c], nb);
        const double cs = kappa3 / (6.0 * se2 * std::sqrt(se2));
        if (std::isfinite(cs) && cs != 0.0) {
          r.skew_max = std::max(r.skew_max, std::abs(cs));
          if (std::abs(cs) > kSkewValidity) ++r.skew_large;
          t.statistic = hall_transform(t.statistic, cs);
          t.p_value = stats::students_t_two_sided_p(t.statistic, t.dof);
        }
      }
      pc.t = t.statistic;
      pc.dof = t.dof;
      pc.p = t.p_value;
      pc.z = z_from_two_sided_p(t.p_value, t.statistic);
      zc[c].push_back(pc.z);
      signal[c] += unit_gain(t.dof) * 0.5 * (ma[c] + mb[c]) / std::sqrt(se2);
      sum_diff += ma[c] - mb[c];
      sum_b += mb[c];
      if (pc.p < min_p) {
        min_p = pc.p;
        r.worst = pc;
      }
    }
  }
  finish_global_tests(r, zc, min_p, sum_diff, sum_b, signal);
  return r;
}

}  // namespace tb
