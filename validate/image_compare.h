// Comparison of two images of Welch samples (Jung, Hanika & Dachsbacher 2020; docs/validation.md A).
// Per pixel and channel, Welch's two-sample t-test of the means of the Welch samples
// (validate/stats welch_t_test; one-sample t-test when one image has fewer than two Welch
// samples there, i.e. is a known reference). Three tests, each at alpha_each =
// Šidák(alpha, 3) so that the comparison as a whole has level alpha:
//   (1) pixel-wise: reject if min p < Šidák(alpha_each, P) over the P pixel-channels tested;
//   (2) Stouffer: Z = sum z_i / sqrt(P) (uniform-sign bias, e.g. a 2% scale error);
//   (3) sum z_i^2 against chi^2_P (mixed-sign bias).
// (2) and (3) assume independent z_i, which holds across pixels but not across the three channels
// of a pixel (the same paths make them): they are run per channel, and the channel with the
// smallest p is Šidák-adjusted over the three; the reported statistic is that channel's.
// z_i is the normal quantile with the same two-sided p-value and the sign of t_i, so z_i is
// standard normal under H0 whatever the Welch dof. Pixel-channels where both images have zero
// variance are skipped when their means agree and count as hard failures when they differ,
// unless both means are below sqrt(FLT_MIN) ~ 1.1e-19 in magnitude: images read from EXR carry
// their variance in float, where the variance of such values (~mean^2) underflows to 0, so
// there "zero variance" means "not stored", and those pixel-channels are skipped and counted.
//
// Skew correction (ImageCompareOptions::skew_correction, on in `tb compare`): a pixel whose Welch
// samples are skewed (rare bright contributions) has a skewed t: the sample that misses its rare
// samples has both a low mean and a small variance, so t is too often negative, and Stouffer's sum
// over many pixels turns that into a rejection although the means agree. With the third central
// moments of both images (WelchImage::has_third_moment, EXR channels moment3.*), t is replaced by
// Hall's transformation (Hall 1992, "On the removal of skewness by transformation", JRSS B 54)
//     t' = t + c (1 + 2 t^2) + (4/3) c^2 t^3,   c = kappa3(D) / (6 Var(D)^(3/2)),
// D = mean_a - mean_b, kappa3(D) = k3_a / n_a^2 - k3_b / n_b^2, k3 = g s^3 the third cumulant of
// one image's Welch samples with g their standardised skewness (unbiased k3 / s^3) pooled over a
// 7x7 window (one pixel's few samples estimate it too noisily), Var(D) the Welch standard error
// squared. It removes the n^(-1/2)
// term of the Edgeworth expansion of the studentised difference,
//     P(T <= x) = Phi(x) + c (2 x^2 + 1) phi(x) + O(1/n),
// and is monotone ((1 + 2 c t)^2 >= 0). Its validity condition, reported: |c| small (the one-term
// expansion; pixel-channels with |c| > 0.2 are counted), and the skew must be visible in the
// samples: a pixel whose rare contributions no Welch sample caught has no measured skew and
// stays uncorrected.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "lib/film/welch_image.h"
#include "validate/stats/tests.h"

namespace tb {

struct PixelChannelTest {
  int x = -1, y = -1, channel = -1;
  double mean_a = 0, mean_b = 0;
  double t = 0, dof = 0, p = 1, z = 0;
};

// Which Welch test (docs/statistics.md, "Heavy tails: the tiled Welch test"):
//   kPixel  one test per pixel-channel (above);
//   kTiled  one test per k x k tile and channel: D = sum over the tile of (mean_a - mean_b),
//           Var(D) = sum of the squared standard errors (pixels independent within a pass),
//           Satterthwaite's dof, then the same three global tests over the tiles. k is chosen
//           from the third cumulants of the Welch samples (moment3 channels) as the smallest
//           power of two whose predicted Stouffer shift is <= max_skew_shift (see tile_skew_shift),
//           the whole image if none is.
enum class CompareTest { kPixel, kTiled };

struct ImageCompareOptions {
  bool skew_correction = false;  // Hall's transformation of t, when both images have third moments (kPixel only)
  CompareTest test = CompareTest::kPixel;
  int tile = 0;                  // kTiled: 0 = choose k from the third moments; otherwise this k
  double max_skew_shift = 0.25;  // kTiled: bound on the predicted |Stouffer shift| that chooses k
  int fallback_tile = 8;         // kTiled, k = 0 and an image without third moments (older EXRs)
};

inline constexpr double kMdeNone = std::numeric_limits<double>::infinity();

struct ImageCompareResult {
  double alpha = 0, alpha_each = 0, alpha_pixel = 0;
  bool skew_corrected = false;      // the transformation was applied
  int64_t skew_large = 0;           // pixel-channels with |c| > 0.2: the correction is unreliable there
  double skew_max = 0;              // largest |c|
  int64_t tested = 0;               // P
  int64_t skipped_identical = 0;    // zero variance in both, equal means
  int64_t zero_variance_mismatch = 0;
  int64_t skipped_below_float_range = 0;  // zero variance in both, different means, |means| < sqrt(FLT_MIN)
  PixelChannelTest worst;           // smallest p
  double p_pixel_family = 1;        // Šidák-adjusted smallest p: 1 - (1 - p_min)^P
  stats::TestResult stouffer, sum_z2;  // of the channel with the smallest p; p Šidák-adjusted over 3
  int stouffer_channel = -1, sum_z2_channel = -1;
  double mean_relative_difference = 0;  // sum(mean_a - mean_b) / sum(mean_b), for messages
  // Power: the smallest relative difference d between the two images' means, uniform over the
  // image (mean_a = (1 + d) mean_b in every tested pixel or tile), that the Stouffer tests alone
  // reject with 90% power at their level; the pixel-wise and sum z^2 tests only add power, so the
  // whole comparison detects it at least as often. Unit i of a channel moves z_i by
  // kappa(dof_i) d m_i / sigma_i (m_i the mean of the two means, sigma_i the true standard error
  // of the difference, kappa = stats::t_to_z_slope); with the estimated se_i, 1 / sigma_i is
  // estimated without bias by 1 / (se_i b(dof_i)), b = stats::inverse_sd_bias. So channel c's Z
  // has mean d g_c with
  //     g_c = sum_i kappa_i m_i / (se_i b_i) / sqrt(P_c)      (stouffer_gain),
  // and is held to alpha_stouffer = Šidák(alpha_each, 3). Channel c alone detects
  // d_c = minimal_detectable_shift(alpha_stouffer, 0.9) / g_c (min_detectable_bias_channel). A
  // rejection in any channel rejects, so min_c d_c holds whatever the dependence between the
  // channels (in a render they come from the same paths, often almost perfectly correlated):
  // that is min_detectable_relative_bias. For independent channels the bias is smaller:
  // min_detectable_relative_bias_independent solves 1 - prod_c (1 - z_test_power(d g_c,
  // alpha_stouffer)) = 0.9 (uniform_bias_mde). Valid for a bias small against each unit's mean
  // (the shift of z is linear there) and, with the skew correction, up to the correction's own
  // change of slope. Infinite where no unit has signal.
  double stouffer_gain[3] = {0.0, 0.0, 0.0};
  double alpha_stouffer = 0.0;
  double min_detectable_bias_channel[3] = {kMdeNone, kMdeNone, kMdeNone};
  double min_detectable_relative_bias = kMdeNone;
  double min_detectable_relative_bias_independent = kMdeNone;
  // Tiled test (ImageCompareOptions::test == kTiled). For kPixel, tile = 1 and the shifts are
  // still predicted when both images have third moments.
  bool tiled = false;
  int tile = 1;                     // k; tested counts tile-channels, worst.x/y is a tile's top-left pixel
  bool tile_from_skewness = false;  // k was chosen from the third moments (not given, not the fallback)
  bool third_moments = false;       // both images have them, so the shifts below are measured
  double predicted_shift = 0;       // largest over channels of |3 sum_tiles c_tile / sqrt(T)| at k
  double predicted_shift_pixel = 0; // the same at k = 1 (the per-pixel test)
  double max_skew_shift = 0.25;
  bool skew_condition_met() const { return !third_moments || predicted_shift <= max_skew_shift; }

  bool rejects_pixel() const { return zero_variance_mismatch > 0 || p_pixel_family < alpha_each; }
  bool rejects_stouffer() const { return stouffer.p_value < alpha_each; }
  bool rejects_sum_z2() const { return sum_z2.p_value < alpha_each; }
  bool rejects() const { return rejects_pixel() || rejects_stouffer() || rejects_sum_z2(); }
  // The smallest of the three family p-values, Šidák-adjusted over the three tests.
  double p_value() const;
  std::string message() const;
  nlohmann::json details() const;
};

// The smallest d with 1 - prod_k (1 - z_test_power(d g_k, alpha_k)) >= power, for independent
// two-sided z tests k whose statistics have mean d g_k (gain_alpha: the pairs (g_k, alpha_k));
// infinite when every g_k is 0.
double uniform_bias_mde(const std::vector<std::pair<double, double>>& gain_alpha, double power = 0.9);
// "detects a uniform bias of 1.2% at 90% power" (or why none is detectable), for messages.
std::string mde_phrase(double min_detectable_relative_bias);
// The bias as JSON: a number, or null when infinite.
nlohmann::json mde_json(double min_detectable_relative_bias);

// Throws std::invalid_argument if the sizes differ or a pixel has fewer than two Welch samples
// in both images.
ImageCompareResult compare_welch_images(const WelchImage& a, const WelchImage& b, double alpha);
ImageCompareResult compare_welch_images(const WelchImage& a, const WelchImage& b, double alpha,
                                        const ImageCompareOptions& options);

// Predicted shift of Stouffer's Z from skewness for k x k tiles (docs/statistics.md): per tile and
// channel c_tile = kappa3(D) / (6 Var(D)^(3/2)) with kappa3(D) = sum (k3_a / n_a^2 - k3_b / n_b^2)
// (k3 the unbiased third cumulant of one pixel's Welch samples), E[t_tile] = -3 c_tile + O(1/n),
// so E[Z] = -3 sum c_tile / sqrt(T) over the T tiles. Largest |.| over the channels; 0 when an
// image has no third moments.
double tile_skew_shift(const WelchImage& a, const WelchImage& b, int k);
// The smallest k in 1, 2, 4, ... (the last candidate the whole image) with tile_skew_shift <= bound.
int choose_tile(const WelchImage& a, const WelchImage& b, double bound);

// Hall's transformation t' of a studentised statistic t with skewness coefficient c (see above).
inline double hall_transform(double t, double c) { return t + c * (1.0 + 2.0 * t * t) + (4.0 / 3.0) * c * c * t * t * t; }

}  // namespace tb
