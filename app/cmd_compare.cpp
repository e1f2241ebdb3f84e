#include "app/cmd_compare.h"

#include <cmath>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <optional>

#include <fmt/format.h>

#include "lib/core/atomic_file.h"
#include "app/compare_metrics.h"
#include "lib/film/exr_io.h"
#include "lib/film/pfm_io.h"
#include "validate/image_compare.h"
#include "validate/pass_tile_compare.h"

namespace tb {

namespace {

std::string extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}
bool is_exr(const std::string& path) { return extension(path) == ".exr"; }
bool is_pfm(const std::string& path) { return extension(path) == ".pfm"; }
bool is_image(const std::string& path) { return is_exr(path) || is_pfm(path); }

// A PFM holds a mean only: one exact Welch sample per pixel (variance 0), like an EXR without
// variance/count channels.
WelchImage welch_from_pfm(const PfmImage& p) {
  WelchImage w(p.width, p.height);
  for (size_t i = 0; i < p.rgb.size(); ++i) w.add(i, p.rgb[i]);
  return w;
}

WelchImage load_welch(const std::string& path) {
  if (is_pfm(path)) {
    fmt::print(stderr, "tb compare: warning: {} is a PFM (a mean only); treated as an exact reference\n", path);
    return welch_from_pfm(read_pfm(path));
  }
  const ExrImage e = read_exr(path);
  if (!e.variance || !e.count)
    fmt::print(stderr, "tb compare: warning: {} has no variance/count channels; treated as an exact reference\n", path);
  return welch_from_exr_image(e);
}

// The RGB of a .pfm or .exr (row 0 at the top).
PfmImage load_rgb(const std::string& path) {
  if (is_pfm(path)) return read_pfm(path);
  const ExrImage e = read_exr(path);
  PfmImage p;
  p.width = e.width;
  p.height = e.height;
  p.rgb = e.rgb;
  return p;
}

WelchImage load_reference(const std::string& mean_path, const std::string& variance_path) {
  const PfmImage m = load_rgb(mean_path), v = load_rgb(variance_path);
  if (m.width != v.width || m.height != v.height)
    throw std::invalid_argument(fmt::format("--reference-mean {} is {} x {}, --reference-variance {} is {} x {}",
                                            mean_path, m.width, m.height, variance_path, v.width, v.height));
  return welch_from_reference(m.width, m.height, m.rgb, v.rgb);
}

// tb render's side files of an EXR: OUT.tiles.json (per-pass tile sums) and OUT.json (the record).
std::string side_file(const std::string& exr, const char* ext) {
  return std::filesystem::path(exr).replace_extension(ext).string();
}

// Whether the record next to an EXR says its pixels are dependent within a pass (MCMC renders).
bool record_says_dependent(const std::string& exr) {
  std::ifstream in(side_file(exr, ".json"));
  if (!in) return false;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    return j.value("pixels_dependent_within_pass", false);
  } catch (const std::exception&) {
    return false;
  }
}

int compare_images(const CompareArgs& a) {
  const bool reference_form = !a.reference_mean.empty();
  const WelchImage img_a = load_welch(a.inputs[0]);
  const WelchImage img_b = reference_form ? load_reference(a.reference_mean, a.reference_variance)
                                          : load_welch(a.inputs[1]);
  if (img_a.width != img_b.width || img_a.height != img_b.height)
    throw std::invalid_argument(fmt::format("A is {} x {}, B is {} x {}", img_a.width, img_a.height, img_b.width,
                                            img_b.height));
  ImageCompareOptions opt;
  opt.skew_correction = a.skew_correction;
  opt.test = a.test == "pixel" ? CompareTest::kPixel : CompareTest::kTiled;
  opt.tile = a.tile;
  if (a.skew_correction && opt.test == CompareTest::kTiled)
    throw std::invalid_argument("--skew-correction applies to --test pixel only");
  if (a.tile > 0 && opt.test == CompareTest::kPixel) throw std::invalid_argument("--tile applies to --test tiled only");
  const ImageCompareResult r = compare_welch_images(img_a, img_b, a.alpha, opt);
  const std::string b_name =
      reference_form ? fmt::format("reference mean {}, variance of the mean {} (effective count {})", a.reference_mean,
                                   a.reference_variance, kReferenceEffectiveCount)
                     : a.inputs[1];
  fmt::print("A: {}\nB: {}\n", a.inputs[0], b_name);
  const char* unit = r.tiled ? "tile-channel" : "pixel-channel";
  if (r.tiled) {
    fmt::print("test: tiled Welch, {0}x{0} tiles ({1}); per tile and channel t = sum(mean_a - mean_b) / sqrt(sum of "
               "squared standard errors), Satterthwaite dof\n",
               r.tile,
               r.tile_from_skewness ? fmt::format("chosen from the stored third moments: smallest power of 2 with "
                                                  "predicted |Stouffer shift| <= {:g}", r.max_skew_shift)
               : a.tile > 0        ? std::string("given by --tile")
                                   : fmt::format("fallback: {} has no moment3 channels, so k is not chosen from the skewness",
                                                 img_a.has_third_moment() ? (reference_form ? std::string("B") : a.inputs[1])
                                                                          : a.inputs[0]));
    if (r.third_moments)
      fmt::print("  predicted Stouffer shift from skewness: {:.3g} at {}x{} tiles, {:.3g} per pixel{}\n", r.predicted_shift,
                 r.tile, r.tile, r.predicted_shift_pixel,
                 r.skew_condition_met()  ? ""
                 : r.tile_from_skewness ? "  (ABOVE the bound even for the whole image: the verdict may reflect skew, "
                                          "not a difference of means)"
                                        : fmt::format("  (ABOVE the bound {:g} at this k: the verdict may reflect skew; "
                                                      "without --tile, k is chosen to meet it)", r.max_skew_shift));
  } else if (r.third_moments) {
    fmt::print("test: per-pixel Welch; predicted Stouffer shift from skewness {:.3g}{}\n", r.predicted_shift_pixel,
               r.predicted_shift_pixel > r.max_skew_shift ? fmt::format(" (above {:g}: heavy tails can reject equal "
                                                                        "means; --test tiled is valid here)",
                                                                        r.max_skew_shift)
                                                          : "");
  }
  fmt::print("  validity: Welch samples (passes) independent; pixels independent within a pass (sum of variances). "
             "Splatting (lt, bdpt t = 1) correlates pixels within a pass positively and a PSS MLT pass shares one "
             "normalisation over all pixels: there Var(D) is underestimated. Measured false-alarm rates of the tiled test at alpha 0.01 "
             "(Cornell box 24x24, docs/statistics.md): pt 0.010, lt 0.005, bdpt 0.013, pssmlt 0.075 (above alpha; "
             "renders whose record says their pixels are dependent (MCMC) are decided by the pass-tile test below)\n");
  fmt::print("alpha {:g} (each of 3 tests {:.3g}, per {} {:.3g}); {} {}s tested, {} identical "
             "skipped\n",
             r.alpha, r.alpha_each, unit, r.alpha_pixel, r.tested, unit, r.skipped_identical);
  if (r.skew_corrected)
    fmt::print("  t skew-corrected (Hall's transformation, from the stored third moments): valid where |c| is small "
               "and a pixel's rare contributions were sampled; {} pixel-channels with |c| > 0.2 (max |c| {:.3g})\n",
               r.skew_large, r.skew_max);
  else if (opt.skew_correction)
    fmt::print("  t not skew-corrected: {} has no moment3 channels (written by tb render since the skew "
               "correction); heavy-tailed pixels may then reject consistent means\n",
               img_a.has_third_moment() ? b_name : a.inputs[0]);
  fmt::print("  {}-wise (Sidak over {}s): p = {:.4g}{}\n", r.tiled ? "tile" : "pixel", unit, r.p_pixel_family,
             r.rejects_pixel() ? "  REJECTS" : "");
  static const char* kChannel[] = {"R", "G", "B"};
  auto ch = [](int c) { return c >= 0 && c < 3 ? kChannel[c] : "-"; };
  fmt::print("  Stouffer sum z / sqrt(P), worst channel {} = {:.4g}:   p = {:.4g} (Sidak over 3 channels){}\n",
             ch(r.stouffer_channel), r.stouffer.statistic, r.stouffer.p_value, r.rejects_stouffer() ? "  REJECTS" : "");
  fmt::print("  sum z^2, worst channel {} = {:.6g} (chi^2, {:.0f} dof):   p = {:.4g} (Sidak over 3 channels){}\n",
             ch(r.sum_z2_channel), r.sum_z2.statistic, r.sum_z2.dof, r.sum_z2.p_value,
             r.rejects_sum_z2() ? "  REJECTS" : "");
  if (r.zero_variance_mismatch > 0)
    fmt::print("  {} {}s with zero variance in both images and different means\n", r.zero_variance_mismatch, unit);
  if (r.skipped_below_float_range > 0)
    fmt::print("  {} {}s skipped: means below 1.1e-19, whose variance a float EXR cannot hold\n",
               r.skipped_below_float_range, unit);
  if (r.worst.x >= 0)
    fmt::print("  worst {} ({}, {}) {}: A {:.6g}, B {:.6g}, t = {:.4g}, dof {:.4g}, p = {:.4g}\n",
               r.tiled ? fmt::format("{0}x{0} tile at", r.tile) : std::string("pixel"), r.worst.x,
               r.worst.y, r.worst.channel >= 0 && r.worst.channel < 3 ? kChannel[r.worst.channel] : "?", r.worst.mean_a,
               r.worst.mean_b, r.worst.t, r.worst.dof, r.worst.p);
  fmt::print("  mean relative difference (A - B) / B: {:+.4g}\n", r.mean_relative_difference);
  fmt::print("  power: {} (Stouffer over the channels; R {}, G {}, B {} alone; docs/statistics.md)\n",
             mde_phrase(r.min_detectable_relative_bias),
             std::isfinite(r.min_detectable_bias_channel[0]) ? fmt::format("{:.3g}%", 100.0 * r.min_detectable_bias_channel[0]) : "-",
             std::isfinite(r.min_detectable_bias_channel[1]) ? fmt::format("{:.3g}%", 100.0 * r.min_detectable_bias_channel[1]) : "-",
             std::isfinite(r.min_detectable_bias_channel[2]) ? fmt::format("{:.3g}%", 100.0 * r.min_detectable_bias_channel[2]) : "-");
  {  // error of A with B as the reference (docs/compare.md, rRMSE; relMSE with eps = 0.01)
    std::vector<Rgb> ma(img_a.pixels()), mb(img_b.pixels()), vb(img_b.pixels());
    for (size_t i = 0; i < ma.size() && i < mb.size(); ++i) {
      ma[i] = img_a.mean(i);
      mb[i] = img_b.mean(i);
      vb[i] = img_b.count[i] > 0 ? img_b.variance(i) / double(img_b.count[i]) : Rgb(0.0);
    }
    const compare::RelativeError e = compare::relative_error(ma, mb, vb, compare::reference_floor(mb, 0.01));
    fmt::print("  A against B as reference: rRMSE {:.4g} (B's own {:.3g}; {} pixel-channels above 1% of the mean), "
               "relMSE(eps 0.01) {:.4g}\n",
               e.rrmse, e.rrmse_ref, e.channels, compare::relmse_eps(ma, mb));
    // The part of the error that one global scale explains (an estimator's normalisation, e.g.
    // the bootstrap constant of PSS MLT, is common to all pixels of a pass): A rescaled so that
    // its channel sums equal B's.
    Rgb sa(0.0), sb(0.0);
    for (size_t i = 0; i < ma.size(); ++i) sa += ma[i], sb += mb[i];
    std::vector<Rgb> scaled = ma;
    for (auto& v : scaled)
      for (int c = 0; c < 3; ++c) v[c] *= sa[c] > 0 ? sb[c] / sa[c] : 1.0;
    const compare::RelativeError es = compare::relative_error(scaled, mb, vb, compare::reference_floor(mb, 0.01));
    fmt::print("  image sums A / B: R {:.5f}, G {:.5f}, B {:.5f}; A rescaled to B's sums: rRMSE {:.4g}, relMSE {:.4g}\n",
               sb[0] > 0 ? sa[0] / sb[0] : 0.0, sb[1] > 0 ? sa[1] / sb[1] : 0.0, sb[2] > 0 ? sa[2] / sb[2] : 0.0,
               es.rrmse, compare::relmse_eps(scaled, mb));
    std::string bins;
    for (const auto& b : compare::relmse_by_brightness(ma, mb))
      bins += fmt::format("{}{:.0f}% [{:.3g}, {:.3g}]", bins.empty() ? "" : ", ", 100.0 * b.share, b.lo, b.hi);
    fmt::print("  relMSE by reference brightness, fifths of the pixels dark to bright: {}\n", bins);
  }
  // The pass-tile test (validate/pass_tile_compare.h) when both renders carry their per-pass tile
  // sums; it decides when either render's pixels are dependent within a pass (MCMC).
  std::optional<PassTileCompareResult> pt;
  const bool dependent = is_exr(a.inputs[0]) && (record_says_dependent(a.inputs[0]) ||
                                                 (!reference_form && is_exr(a.inputs[1]) && record_says_dependent(a.inputs[1])));
  if (!reference_form && is_exr(a.inputs[0]) && is_exr(a.inputs[1]) &&
      std::filesystem::exists(side_file(a.inputs[0], ".tiles.json")) &&
      std::filesystem::exists(side_file(a.inputs[1], ".tiles.json"))) {
    pt = compare_pass_tiles(PassTiles::read(side_file(a.inputs[0], ".tiles.json")),
                            PassTiles::read(side_file(a.inputs[1], ".tiles.json")), a.alpha);
    fmt::print("pass-tile test ({}x{} tiles, {} and {} passes; Welch over the passes per tile-channel and per channel "
               "total, weighted Bonferroni: alpha/2 over {} totals, alpha/2 over {} tile-channels; valid whatever the dependence within a pass): p = {:.4g}{}\n",
               pt->grid_x, pt->grid_y, pt->passes_a, pt->passes_b, pt->tested_totals, pt->tested_tiles, pt->p_family,
               pt->rejects() ? "  REJECTS" : "");
    fmt::print("  worst {} {}: A {:.6g}, B {:.6g} ({:+.3g}), t = {:.4g}, dof {:.4g}; totals A / B - 1: R {:+.3g}, "
               "G {:+.3g}, B {:+.3g}\n",
               pt->worst_tile < 0 ? std::string("image total") : fmt::format("tile {}", pt->worst_tile),
               ch(pt->worst_channel), pt->worst_mean_a, pt->worst_mean_b, pt->worst_rel_diff, pt->worst_t, pt->worst_dof,
               pt->total_rel_diff[0], pt->total_rel_diff[1], pt->total_rel_diff[2]);
  }
  const bool by_tiles = dependent && pt.has_value();
  if (dependent && !pt)
    fmt::print("warning: a render's pixels are dependent within a pass (MCMC) and the pass-tile files "
               "(OUT.tiles.json) are missing: the per-pixel verdict below can reject consistent renders\n");
  const bool rejects = by_tiles ? pt->rejects() : r.rejects();
  fmt::print("{} ({})\n", rejects ? "DIFFERENT" : "consistent",
             by_tiles ? fmt::format("pass-tile test, p = {:.4g}: pixels are dependent within a pass; the pixel-wise "
                                    "combined p = {:.4g} is for information",
                                    pt->p_family, r.p_value())
                      : fmt::format("combined p = {:.4g}", r.p_value()));
  if (!a.json_out.empty()) {
    nlohmann::json j = r.details();
    if (pt) j["pass_tiles"] = pt->details();
    j["verdict_from"] = by_tiles ? "pass_tiles" : "pixels";
    j["a"] = a.inputs[0];
    j["b"] = reference_form ? nlohmann::json{{"reference_mean", a.reference_mean},
                                             {"reference_variance", a.reference_variance},
                                             {"effective_count", kReferenceEffectiveCount}}
                            : nlohmann::json(a.inputs[1]);
    j["rejects"] = rejects;
    j["rejects_pixels"] = r.rejects();
    write_file_atomic(a.json_out, j.dump(1));
  }
  return rejects ? 1 : 0;
}

}  // namespace

int cmd_compare(const CompareArgs& a, const std::atomic<bool>* interrupted) {
  auto reject_options = [](const std::vector<std::string>& given, const char* form) {
    for (const auto& o : given) fmt::print(stderr, "tb compare: {} does not apply to the {} form\n", o, form);
    return given.empty();
  };
  if (!a.reference_mean.empty() || !a.reference_variance.empty()) {
    if (a.reference_mean.empty() || a.reference_variance.empty()) {
      fmt::print(stderr, "tb compare: --reference-mean and --reference-variance go together\n");
      return 2;
    }
    if (a.inputs.size() != 1 || !is_image(a.inputs[0])) {
      fmt::print(stderr, "tb compare: the reference form takes one image: tb compare A.exr --reference-mean R.pfm "
                         "--reference-variance V.pfm\n");
      return 2;
    }
    if (!reject_options(a.scene_options_given, "reference (A.exr --reference-mean R --reference-variance V)")) return 2;
    return compare_images(a);
  }
  if (a.inputs.size() == 1 && !is_image(a.inputs[0])) {
    if (!reject_options(a.image_options_given, "scene")) return 2;
    CompareSceneArgs s = a.scene;
    s.scene = a.inputs[0];
    return cmd_compare_scene(s, interrupted);
  }
  if (a.inputs.size() == 2 && is_image(a.inputs[0]) && is_image(a.inputs[1])) {
    if (!reject_options(a.scene_options_given, "image (A.exr B.exr)")) return 2;
    return compare_images(a);
  }
  fmt::print(stderr,
             "tb compare: expected two images (tb compare A.exr B.exr [--alpha A]; .exr or .pfm), one image with a "
             "reference (tb compare A.exr --reference-mean R.pfm --reference-variance V.pfm) or one scene file "
             "(tb compare SCENE --integrators A,B,... --time S [--reference REF.exr])\n");
  return 2;
}

}  // namespace tb
