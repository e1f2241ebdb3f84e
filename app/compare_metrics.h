// The error measures of the equal-time comparison `tb compare SCENE --integrators ...`
// (docs/compare.md). Header-only so the unit tests (tests/render/compare_scene_test.cpp) can use
// them without linking the program.
//
// Relative RMSE against a reference image R (pixel-channels c with R_c > floor only):
//     rRMSE = sqrt( (1/K) sum_c ((I_c - R_c) / R_c)^2 ),   K = number of such pixel-channels.
// The floor is a fraction of the mean reference value over all pixel-channels (default 1%): a
// channel of a dark pixel has an unbounded relative error and a noisy reference, so it is left out
// and counted.
//
// Reference noise: when R is itself a Monte Carlo estimate with per-channel variance of its mean
// v_c (EXR variance / count), an independent unbiased render I has
//     E[(I_c - R_c)^2] = MSE_c(I) + v_c,
// so the measured rRMSE^2 is the render's own rRMSE^2 plus the reference's
//     rRMSE_ref^2 = (1/K) sum_c v_c / R_c^2.
// We report rRMSE as defined above (nothing subtracted) and rRMSE_ref next to it, so the reader
// sees when a render is as good as the reference and the comparison reaches its floor.
//
// Weight of one rRMSE in the convergence fit (validate/stats/convergence_fit.h): ln rRMSE has
// variance 1 / (2 k) where k is Satterthwaite's effective number of chi^2_1 terms of the mean of
// squared errors, k = (sum s_c^2)^2 / sum s_c^4 (as validate/render/render_convergence.h); with
// one render per checkpoint each s_c^2 is estimated by its own squared error e_c^2, which for
// normal errors overstates sum s_c^4 about threefold (E e^4 = 3 s^4), so k is conservative.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "lib/core/spectrum.h"

namespace tb::compare {

// floor = fraction * mean of the finite reference values over all pixel-channels.
inline double reference_floor(const std::vector<Rgb>& ref, double fraction) {
  double sum = 0.0;
  int64_t n = 0;
  for (const Rgb& r : ref)
    for (int c = 0; c < 3; ++c)
      if (std::isfinite(r[c])) sum += r[c], ++n;
  return n > 0 ? fraction * sum / static_cast<double>(n) : 0.0;
}

struct RelativeError {
  double rrmse = 0.0;        // see the header
  double rrmse_ref = 0.0;    // the reference's own relative noise (0 without its variance)
  double mean_relative = 0.0;  // mean of (I - R) / R: a bias shows here
  // Median of |I - R| / R: robust to the few outliers (fireflies in dim pixels) that can dominate
  // rRMSE, so a heavy-tailed run is recognised as such (a diagnostic; the fit uses rRMSE).
  double median_abs_relative = 0.0;
  int64_t channels = 0;      // K: pixel-channels with R > floor
  int64_t below_floor = 0;   // pixel-channels left out
  int64_t nonfinite = 0;     // pixel-channels of I that are NaN / Inf (left out, counted)
  double effective_terms = 1.0;  // Satterthwaite's k (>= 1)
};

// The relative MSE of the form peer renderers' papers and benchmarks use (Tungsten's and
// Rousselle et al.'s): mean over all pixel-channels of (I - R)^2 / (R^2 + eps), eps = 0.01.
// No floor: the eps keeps dark channels bounded. NaN / Inf channels of I are left out.
inline double relmse_eps(const std::vector<Rgb>& img, const std::vector<Rgb>& ref, double eps = 0.01) {
  double s = 0.0;
  int64_t k = 0;
  const size_t n = std::min(img.size(), ref.size());
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      const double r = ref[i][c], x = img[i][c];
      if (!std::isfinite(r) || !std::isfinite(x)) continue;
      s += (x - r) * (x - r) / (r * r + eps);
      ++k;
    }
  return k > 0 ? s / static_cast<double>(k) : 0.0;
}

// Where relmse_eps comes from: pixels sorted by the reference's mean over channels and cut into
// `bins` groups of equal count (dark to bright); per group its share of the total (the shares sum
// to 1) and its brightness range. An MCMC estimator that puts its samples where the image is
// bright shows its error in the dark groups; a path tracer spreads it more evenly.
struct BrightnessBin {
  double lo = 0.0, hi = 0.0;  // reference brightness range of the group
  double share = 0.0;         // the group's part of sum (I - R)^2 / (R^2 + eps)
};
inline std::vector<BrightnessBin> relmse_by_brightness(const std::vector<Rgb>& img, const std::vector<Rgb>& ref,
                                                       int bins = 5, double eps = 0.01) {
  const size_t n = std::min(img.size(), ref.size());
  std::vector<std::pair<double, double>> px;  // (brightness, error summed over channels)
  px.reserve(n);
  double total = 0.0;
  for (size_t i = 0; i < n; ++i) {
    double e = 0.0;
    for (int c = 0; c < 3; ++c) {
      const double r = ref[i][c], x = img[i][c];
      if (std::isfinite(r) && std::isfinite(x)) e += (x - r) * (x - r) / (r * r + eps);
    }
    px.push_back({(ref[i][0] + ref[i][1] + ref[i][2]) / 3.0, e});
    total += e;
  }
  std::sort(px.begin(), px.end());
  std::vector<BrightnessBin> out;
  if (px.empty() || bins < 1) return out;
  for (int b = 0; b < bins; ++b) {
    const size_t lo = px.size() * static_cast<size_t>(b) / static_cast<size_t>(bins);
    const size_t hi = px.size() * static_cast<size_t>(b + 1) / static_cast<size_t>(bins);
    if (hi <= lo) continue;
    BrightnessBin bin{px[lo].first, px[hi - 1].first, 0.0};
    for (size_t i = lo; i < hi; ++i) bin.share += px[i].second;
    bin.share = total > 0.0 ? bin.share / total : 0.0;
    out.push_back(bin);
  }
  return out;
}

// ref_var_of_mean: per pixel the variance of the reference value itself (may be empty).
inline RelativeError relative_error(const std::vector<Rgb>& img, const std::vector<Rgb>& ref,
                                    const std::vector<Rgb>& ref_var_of_mean, double floor) {
  RelativeError out;
  double s2 = 0.0, s4 = 0.0, sv = 0.0, se = 0.0;
  std::vector<double> abs_rel;
  const size_t n = std::min(img.size(), ref.size());
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      const double r = ref[i][c];
      if (!(r > floor) || !std::isfinite(r)) {
        ++out.below_floor;
        continue;
      }
      if (!std::isfinite(img[i][c])) {
        ++out.nonfinite;
        continue;
      }
      const double e = (img[i][c] - r) / r;
      s2 += e * e;
      s4 += e * e * e * e;
      se += e;
      abs_rel.push_back(std::abs(e));
      if (!ref_var_of_mean.empty()) sv += ref_var_of_mean[i][c] / (r * r);
      ++out.channels;
    }
  if (out.channels == 0) return out;
  const double k = static_cast<double>(out.channels);
  out.rrmse = std::sqrt(s2 / k);
  out.rrmse_ref = std::sqrt(sv / k);
  out.mean_relative = se / k;
  out.effective_terms = s4 > 0.0 ? std::max(1.0, s2 * s2 / s4) : k;
  const size_t mid = abs_rel.size() / 2;
  std::nth_element(abs_rel.begin(), abs_rel.begin() + static_cast<std::ptrdiff_t>(mid), abs_rel.end());
  out.median_abs_relative = abs_rel[mid];
  if (abs_rel.size() % 2 == 0) {  // the mean of the two middle values
    const double lower = *std::max_element(abs_rel.begin(), abs_rel.begin() + static_cast<std::ptrdiff_t>(mid));
    out.median_abs_relative = 0.5 * (out.median_abs_relative + lower);
  }
  return out;
}

// Per pixel: the mean over its channels above the floor of |I - R| / R; negative (-1) where no
// channel is above the floor.
inline std::vector<double> relative_error_map(const std::vector<Rgb>& img, const std::vector<Rgb>& ref, double floor) {
  std::vector<double> m(std::min(img.size(), ref.size()), -1.0);
  for (size_t i = 0; i < m.size(); ++i) {
    double s = 0.0;
    int used = 0;
    for (int c = 0; c < 3; ++c)
      if (ref[i][c] > floor && std::isfinite(ref[i][c])) {
        s += std::isfinite(img[i][c]) ? std::abs(img[i][c] - ref[i][c]) / ref[i][c] : HUGE_VAL;
        ++used;
      }
    if (used > 0) m[i] = s / used;
  }
  return m;
}

// A linear-RGB "hot" colour ramp of v / scale in [0, 1] (black, red, yellow, white), for an
// error map written through the sRGB preview (lib/film/png_preview.h). Pixels without a value
// (negative) are a dark blue, so they are not mistaken for zero error.
inline std::vector<Rgb> heat_colours(const std::vector<double>& map, double scale) {
  std::vector<Rgb> out(map.size());
  for (size_t i = 0; i < map.size(); ++i) {
    if (map[i] < 0.0) {
      out[i] = Rgb(0.0, 0.0, 0.05);
      continue;
    }
    const double v = std::clamp(map[i] / scale, 0.0, 1.0) * 3.0;
    out[i] = Rgb(std::clamp(v, 0.0, 1.0), std::clamp(v - 1.0, 0.0, 1.0), std::clamp(v - 2.0, 0.0, 1.0));
  }
  return out;
}

// Time budgets of the checkpoints: S / 2^(count-1), ..., S / 2, S.
inline std::vector<double> checkpoint_budgets(double total_s, int count) {
  std::vector<double> t;
  for (int k = count - 1; k >= 0; --k) t.push_back(std::ldexp(total_s, -k));
  return t;
}

// A plain-text table with columns padded to their widest cell (first column left-aligned, the
// others right-aligned), one row a line.
inline std::string text_table(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows) {
  std::vector<size_t> w(header.size(), 0);
  auto widen = [&](const std::vector<std::string>& r) {
    for (size_t c = 0; c < r.size() && c < w.size(); ++c) w[c] = std::max(w[c], r[c].size());
  };
  widen(header);
  for (const auto& r : rows) widen(r);
  auto line = [&](const std::vector<std::string>& r) {
    std::string s;
    for (size_t c = 0; c < w.size(); ++c) {
      const std::string cell = c < r.size() ? r[c] : "";
      s += c == 0 ? fmt::format("{:<{}}", cell, w[c]) : fmt::format("  {:>{}}", cell, w[c]);
    }
    while (!s.empty() && s.back() == ' ') s.pop_back();
    return s + "\n";
  };
  std::string out = line(header);
  size_t total = 0;
  for (size_t c = 0; c < w.size(); ++c) total += w[c] + (c ? 2 : 0);
  out += std::string(total, '-') + "\n";
  for (const auto& r : rows) out += line(r);
  return out;
}

}  // namespace tb::compare
